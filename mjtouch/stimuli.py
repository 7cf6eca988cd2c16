"""Deprecated alias of :mod:`mjtouch.experiments.stimuli`, kept for one release.

Import from ``mjtouch.experiments.stimuli``; this module re-exports its public names.
"""

from mjtouch.experiments.stimuli import *  # noqa: F403
