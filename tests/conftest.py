import pathlib
import sys

import mujoco
import mujoco.rollout
import numpy as np
import pytest

import mjtouch  # noqa: F401  (registers the plugin)
from mjtouch.scene import scenes

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


def geom_type(name: str) -> mujoco.mjtGeom:
    return getattr(mujoco.mjtGeom, f"mjGEOM_{name.upper()}")


def add_geom(parent, kind: str, size, euler_deg=None, **kw):
    """A geom of type ``kind`` ("sphere", "box", ...); size has 1 to 3 numbers."""
    size = list(size) + [0.0] * (3 - len(size))
    g = parent.add_geom(type=geom_type(kind), size=size, **kw)
    if euler_deg is not None:
        g.alt.type = mujoco.mjtOrientation.mjORIENTATION_EULER
        g.alt.euler = list(euler_deg)
    return g


def pad_spec(
    skin: dict[str, str] | None = None, pad: dict | None = None, texture: bool = True
) -> mujoco.MjSpec:
    """A minimal scene: a free pad resting on a plate (+ optional grating).
    ``pad``: add_geom arguments (kind, size, euler_deg) for the pad geom;
    skin attributes with value "" are left out (their defaults)."""
    cfg = {"nx": "48", "pitch": "1.5e-4", "texture": "texture" if texture else ""}
    cfg.update(skin or {})
    spec = mujoco.MjSpec()  # angles in degrees (compiler.degree)
    spec.option.timestep = 2e-4
    spec.worldbody.add_geom(
        name="plate", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.04, 0.02, 0.002], pos=[0, 0, -0.002]
    )
    if texture:
        spec.add_hfield(
            name="h",
            nrow=2,
            ncol=5,
            size=[0.01, 0.01, 0.0001, 0.001],
            userdata=[0, 1, 0, 1, 0, 0, 1, 0, 1, 0],
        )
        spec.worldbody.add_geom(
            name="texture",
            type=mujoco.mjtGeom.mjGEOM_HFIELD,
            hfieldname="h",
            contype=0,
            conaffinity=0,
        )
    finger = spec.worldbody.add_body(name="finger", pos=[0, 0, 0.0071])
    finger.add_freejoint()
    add_geom(
        finger,
        **(pad or {"kind": "ellipsoid", "size": [0.008, 0.007, 0.007]}),
        name="pad",
        mass=0.05,
        solref=[0.004, 1],
    )
    scenes.add_skin_sensor(spec, "pad", {k: v for k, v in cfg.items() if v != ""})
    return spec


def pad_scene(skin: dict[str, str] | None = None, texture: bool = True) -> str:
    """:func:`pad_spec` as MJCF text (MjSpec.to_xml)."""
    return pad_spec(skin, texture=texture).to_xml()


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
        _fields_ = [
            ("name", ctypes.c_char_p),
            ("nattribute", ctypes.c_int),
            ("attributes", ctypes.POINTER(ctypes.c_char_p)),
        ]

    root = pathlib.Path(mujoco.__file__).parent
    lib = ctypes.CDLL(str(sorted(root.glob("libmujoco.so.*"))[0]))
    lib.mjp_getPlugin.restype = ctypes.POINTER(Plugin)
    lib.mjp_getPlugin.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_int)]
    slot = ctypes.c_int()
    plugin = lib.mjp_getPlugin(b"mjtouch.skin", ctypes.byref(slot))
    assert plugin, "mjtouch.skin is not registered"
    return [plugin.contents.attributes[i].decode() for i in range(plugin.contents.nattribute)]


def rollout_and_serial(
    m_rollout: mujoco.MjModel,
    m_serial: mujoco.MjModel,
    proto: scenes.Protocol,
    duration_s: float,
    speeds=(0.02, 0.04),
) -> tuple[np.ndarray, np.ndarray]:
    """sensordata (len(speeds), nstep, nsensordata) of a press and slide at
    each speed: by mujoco.rollout on two threads (one MjData each) with
    m_rollout, and stepped serially with m_serial from the same state."""
    ctrl = scenes.controls(proto, duration_s)
    speeds = np.asarray(speeds)
    controls = np.repeat(ctrl[None], len(speeds), axis=0)
    controls[:, int(round(proto.press_s / proto.timestep_s)) :, 0] = speeds[:, None]
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    s0 = np.empty(mujoco.mj_stateSize(m_rollout, spec))
    mujoco.mj_getState(m_rollout, mujoco.MjData(m_rollout), s0, spec)
    s0 = np.repeat(s0[None], len(speeds), axis=0)
    _, two = mujoco.rollout.rollout(
        m_rollout, [mujoco.MjData(m_rollout), mujoco.MjData(m_rollout)], s0, controls
    )
    serial = np.empty_like(two)
    for b in range(len(speeds)):
        d = mujoco.MjData(m_serial)
        for k in range(controls.shape[1]):
            d.ctrl[:] = controls[b, k]
            mujoco.mj_step(m_serial, d)
            serial[b, k] = d.sensordata
    return two, serial


def hertz_sphere_press(h, young_pa: float, poisson: float, **skin):
    """The elastic half-space skin pressed by h's sphere with h's load,
    settled (1500 steps), 32 cells per Hertz contact radius on a 96^2 grid,
    tolerance 1e-8; skin: extra attributes. Returns (force block, pressure
    (96, 96), pitch m)."""
    from mjtouch.scene.sensor import SkinLayout

    pitch, n = h.contact_radius_m / 32, 96
    attrs = dict(
        nx=n,
        pitch=pitch,
        ridges="false",
        pressure="elastic",
        skin="halfspace",
        young=young_pa,
        poisson=poisson,
        tolerance=1e-8,
        outputs="force pressure",
        **skin,
    )
    m = scenes.sphere_press_spec(h.radius_m, attrs).compile()
    d = mujoco.MjData(m)
    layout = SkinLayout.from_model(m)
    d.ctrl[0] = h.load_n
    for _ in range(1500):
        mujoco.mj_step(m, d)
    force = layout.block(d.sensordata, "force")
    return force, layout.block(d.sensordata, "pressure").reshape(n, n), pitch
