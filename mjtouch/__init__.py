"""mjtouch: tactile skin for MuJoCo fingertips.

Importing mjtouch registers the ``mjtouch.skin`` sensor plugin, so MJCF that
uses it loads with ``mujoco.MjModel.from_xml_path``. Submodules:

- :mod:`mjtouch.scenes`   MJCF builders (fingertip, plates, sliding scenes)
- :mod:`mjtouch.sensor`   reading the plugin's sensordata blocks by name
- :mod:`mjtouch.rollout`  running scenes and collecting spikes and stress
- :mod:`mjtouch.analysis` rates and spectra
- :mod:`mjtouch.core`     the C++ stages called directly (no MuJoCo scene)
"""

from mjtouch._loader import PluginNotBuiltError, library_path, load as _load

__version__ = "0.1.0"
MUJOCO_VERSION = "4.0.0"  # the plugin is compiled against exactly this release

_load()

__all__ = ["PluginNotBuiltError", "library_path", "MUJOCO_VERSION", "__version__"]
