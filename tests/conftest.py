import pathlib
import sys

import mujoco
import numpy as np
import pytest

import mjtouch  # noqa: F401  (registers the plugin)
from mjtouch import scenes

REPO = pathlib.Path(__file__).resolve().parents[1]
MODELS = REPO / "models"
# Tests are grouped like the code (unit, plugin, science, robustness); some
# share helpers across groups (test_receptors.SA1, test_layered.BAD), so each
# group's folder is importable whichever is collected first.
for _group in ("unit", "plugin", "science", "robustness"):
    if str(REPO / "tests" / _group) not in sys.path:
        sys.path.insert(0, str(REPO / "tests" / _group))


def fast_tip(**kw) -> scenes.Fingertip:
    """A coarser skin for rollouts in tests: 64 x 64 taxels at 0.15 mm
    (3 taxels per 0.45 mm ridge), same physics."""
    kw.setdefault("nx", 64)
    kw.setdefault("pitch_m", 1.5e-4)
    return scenes.Fingertip(**kw)


def pad_scene(skin: dict[str, str] | None = None, pad: str = 'type="ellipsoid" size="0.008 0.007 0.007"',
              texture: bool = True, extra: str = "") -> str:
    """A minimal scene: a free pad resting on a plate (+ optional grating)."""
    cfg = {"nx": "48", "pitch": "1.5e-4", "texture": "texture" if texture else ""}
    cfg.update(skin or {})
    config = "".join(f'<config key="{k}" value="{v}"/>' for k, v in cfg.items() if v != "")
    tex = ""
    asset = ""
    if texture:
        asset = ('<asset><hfield name="h" nrow="2" ncol="5" size="0.01 0.01 0.0001 0.001" '
                 'elevation="0 1 0 1 0 0 1 0 1 0"/></asset>')
        tex = '<geom name="texture" type="hfield" hfield="h" contype="0" conaffinity="0"/>'
    return f"""<mujoco>
  <extension><plugin plugin="mjtouch.skin"/></extension>
  <option timestep="2e-4"/>
  {asset}
  <worldbody>
    <geom name="plate" type="box" size="0.04 0.02 0.002" pos="0 0 -0.002"/>
    {tex}
    <body name="finger" pos="0 0 0.0071"><freejoint/>
      <geom name="pad" {pad} mass="0.05" solref="0.004 1"/></body>
    {extra}
  </worldbody>
  <sensor><plugin name="skin" plugin="mjtouch.skin" objtype="geom" objname="pad">{config}</plugin></sensor>
</mujoco>"""


def assert_no_warnings(data: mujoco.MjData) -> None:
    counts = {mujoco.mjtWarning(i).name: data.warning[i].number for i in range(len(data.warning))}
    bad = {k: v for k, v in counts.items() if v}
    assert not bad, f"MuJoCo warnings: {bad}"


@pytest.fixture
def rng():
    return np.random.default_rng(0)


def registered_attributes() -> list[str]:
    """The attribute keys mjtouch.skin registers with MuJoCo (read back from
    MuJoCo's plugin table, so that tests follow the plugin's real list)."""
    import ctypes

    class Plugin(ctypes.Structure):  # the head of mjpPlugin (mjplugin.h)
        _fields_ = [("name", ctypes.c_char_p), ("nattribute", ctypes.c_int),
                    ("attributes", ctypes.POINTER(ctypes.c_char_p))]

    root = pathlib.Path(mujoco.__file__).parent
    lib = ctypes.CDLL(str(sorted(root.glob("libmujoco.so.*"))[0]))
    lib.mjp_getPlugin.restype = ctypes.POINTER(Plugin)
    lib.mjp_getPlugin.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_int)]
    slot = ctypes.c_int()
    plugin = lib.mjp_getPlugin(b"mjtouch.skin", ctypes.byref(slot))
    assert plugin, "mjtouch.skin is not registered"
    return [plugin.contents.attributes[i].decode() for i in range(plugin.contents.nattribute)]
