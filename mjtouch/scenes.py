"""Deprecated alias of :mod:`mjtouch.scene.scenes`, kept for one release.

Import from ``mjtouch.scene.scenes``; this module re-exports its public names.
"""

from mjtouch.scene.scenes import *  # noqa: F403
