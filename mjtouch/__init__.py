"""mjtouch: tactile skin for MuJoCo fingertips.

Importing mjtouch registers the ``mjtouch.skin`` sensor plugin, so MJCF that
uses it loads with ``mujoco.MjModel.from_xml_path``. Subpackages, by concern
(each imports only those above it in this list; no import cycles):

- :mod:`mjtouch.core`         the C++ stages called directly (no MuJoCo scene)
- :mod:`mjtouch.scene`        MJCF builders (``scenes``), ``textures``, ``meshes``,
  reading sensordata (``sensor.SkinLayout``), ``robot.attach``
- :mod:`mjtouch.analysis`     rates and spectra (``signals``, re-exported here),
  ``reference_solutions`` (Hertz, the layered half-space), ``figures``, ``testing``
- :mod:`mjtouch.experiments`  ``slide`` (``SlideParams``, ``run``), ``rollout``,
  ``stimuli``, ``tuning``, ``sweep``
- :mod:`mjtouch.envs`, :mod:`mjtouch.bench`, :mod:`mjtouch.viewer`
- :mod:`mjtouch.cli`          the ``mjtouch`` command, one module per subcommand

Deprecated aliases, kept for one release: ``mjtouch.scenes``, ``.textures``,
``.meshes``, ``.sensor``, ``.robot`` (now in ``mjtouch.scene``); ``.rollout``,
``.stimuli``, ``.tuning``, ``.sweep`` (``mjtouch.experiments``); ``.figures``,
``.testing`` (``mjtouch.analysis``); ``.oracles``
(``mjtouch.analysis.reference_solutions``). Each re-exports its new module's
public names.
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
    found = {
        str(_pathlib.Path(f.locate()).resolve().parent)
        for f in files
        if f.name.startswith("_core.") and f.suffix in (".so", ".pyd")
    }
    return sorted(d for d in found if d != str(here))


__path__ += _compiled_dirs()

__version__ = "0.1.0"
MUJOCO_VERSION = "4.0.0"  # the plugin is compiled against exactly this release

_load()

from mjtouch.scene.robot import attach, layouts  # noqa: E402  (after the plugin loads)

__all__ = [
    "PluginNotBuiltError",
    "attach",
    "layouts",
    "library_path",
    "MUJOCO_VERSION",
    "__version__",
]
