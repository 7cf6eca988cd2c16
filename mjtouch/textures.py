"""Deprecated alias of :mod:`mjtouch.scene.textures`, kept for one release.

Import from ``mjtouch.scene.textures``; this module re-exports its public names.
"""

from mjtouch.scene.meshes import from_mesh  # noqa: F401
from mjtouch.scene.textures import *  # noqa: F403
