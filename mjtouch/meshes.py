"""Deprecated alias of :mod:`mjtouch.scene.meshes`, kept for one release.

Import from ``mjtouch.scene.meshes``; this module re-exports its public names.
"""

from mjtouch.scene.meshes import *  # noqa: F403
