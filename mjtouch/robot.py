"""Deprecated alias of :mod:`mjtouch.scene.robot`, kept for one release.

Import from ``mjtouch.scene.robot``; this module re-exports its public names.
"""

from mjtouch.scene.robot import *  # noqa: F403
