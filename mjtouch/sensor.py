"""Deprecated alias of :mod:`mjtouch.scene.sensor`, kept for one release.

Import from ``mjtouch.scene.sensor``; this module re-exports its public names.
"""

from mjtouch.scene.sensor import *  # noqa: F403
