"""mjtouch: tactile skin for MuJoCo fingertips.

Importing mjtouch registers the ``mjtouch.skin`` sensor plugin, so MJCF that
uses it loads with ``mujoco.MjModel.from_xml_path``. Submodules:

- :mod:`mjtouch.scenes`   MJCF builders (fingertip, plates, sliding scenes)
- :mod:`mjtouch.sensor`   reading the plugin's sensordata blocks by name
- :mod:`mjtouch.rollout`  running scenes and collecting spikes and stress
- :mod:`mjtouch.analysis` rates and spectra
- :mod:`mjtouch.core`     the C++ stages called directly (no MuJoCo scene)
- :mod:`mjtouch.robot`    :func:`attach` a skin to any robot's fingertip geom
- :mod:`mjtouch.meshes`   textures from mesh files (``textures.from_mesh``)
"""

import importlib.metadata as _metadata
import pathlib as _pathlib

from mjtouch._loader import PluginNotBuiltError, library_path
from mjtouch._loader import load as _load


def _compiled_dirs() -> list[str]:
    """Directories of the installed distribution's compiled extension
    (mjtouch._core) that are not this package's: importing mjtouch from a
    source tree (tests, ``python -m``) still finds the built extension, as
    _loader finds the built plugin library."""
    here = _pathlib.Path(__file__).resolve().parent
    try:
        files = _metadata.files("mjtouch") or []
    except _metadata.PackageNotFoundError:
        return []
    found = {str(_pathlib.Path(f.locate()).resolve().parent) for f in files
             if f.name.startswith("_core.") and f.suffix in (".so", ".pyd")}
    return sorted(d for d in found if d != str(here))


__path__ += _compiled_dirs()

__version__ = "0.1.0"
MUJOCO_VERSION = "4.0.0"  # the plugin is compiled against exactly this release

_load()

from mjtouch.scene.robot import attach, layouts  # noqa: E402  (after the plugin loads)

__all__ = ["PluginNotBuiltError", "attach", "layouts", "library_path", "MUJOCO_VERSION",
           "__version__"]
