"""Deprecated alias of :mod:`mjtouch.experiments.stimuli`, kept for one release.

Import from ``mjtouch.experiments.stimuli``; this module re-exports its public names,
and ``plate_spec``, now ``vibrating_plate_spec`` (``mjtouch.scene.scenes.plate_spec`` is
the textured plate).
"""

from mjtouch.experiments.stimuli import *  # noqa: F403
from mjtouch.experiments.stimuli import vibrating_plate_spec as plate_spec  # noqa: F401
