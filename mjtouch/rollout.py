"""Deprecated alias of :mod:`mjtouch.experiments.rollout`, kept for one release.

Import from ``mjtouch.experiments.rollout``; this module re-exports its public names.
"""

from mjtouch.experiments.rollout import *  # noqa: F403
