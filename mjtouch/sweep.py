"""Deprecated alias of :mod:`mjtouch.experiments.sweep`, kept for one release.

Import from ``mjtouch.experiments.sweep``; this module re-exports its public names.
"""

from mjtouch.experiments.sweep import *  # noqa: F403
