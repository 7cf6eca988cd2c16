"""Deprecated alias of :mod:`mjtouch.experiments.tuning`, kept for one release.

Import from ``mjtouch.experiments.tuning``; this module re-exports its public names.
"""

from mjtouch.experiments.tuning import *  # noqa: F403
