"""shear="partial": Coulomb stick and slip per taxel in the plugin.

A smooth ellipsoidal pad pressed on a plate at constant normal force P
under a tangential force Q ramped past mu P (motors on slide joints, so the
pad neither rolls nor tilts). Cattaneo-Mindlin: the stick zone is the
contact shrunk by c/a = (1 - Q / (mu P))^k, k = 1/4 for the Winkler skin's
parabolic pressure (springs clamped at mu p) and 1/3 for the half-space's
Hertz pressure, so the stuck share of the loaded area is (c/a)^2.
"""

import mujoco
import mujoco.rollout
import numpy as np
import pytest

from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

TIMESTEP_S = 5e-4
NORMAL_N = 1.0
PRESS_STEPS = 300
MU_PLATE, MU_PAD = 0.8, 1.2  # MuJoCo takes the larger
SKINS = {
    # stiffness / young: a contact ~25 cells across on the 48-cell grid
    "winkler": {"pressure": "winkler", "stiffness": "5e8"},
    "elastic": {"pressure": "elastic", "skin": "halfspace", "young": "1e6"},
}
EXPONENT = {"winkler": 0.25, "elastic": 1.0 / 3.0}


def _model(skin: dict[str, str]) -> mujoco.MjModel:
    spec = mujoco.MjSpec()
    spec.option.timestep = TIMESTEP_S
    spec.option.gravity = [0, 0, 0]
    spec.worldbody.add_geom(
        name="plate",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.04, 0.02, 0.002],
        pos=[0, 0, -0.002],
        friction=[MU_PLATE, 0.005, 0.0001],
    )
    finger = spec.worldbody.add_body(name="finger", pos=[0, 0, 0.0071])
    for name, axis in (("x", [1, 0, 0]), ("y", [0, 1, 0]), ("z", [0, 0, 1])):
        finger.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis)
    finger.add_geom(
        name="pad",
        type=mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        size=[0.008, 0.007, 0.007],
        mass=0.05,
        solref=[0.004, 1],
        friction=[MU_PAD, 0.005, 0.0001],
    )
    for joint in ("x", "z"):
        spec.add_actuator(
            name=joint, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT, gear=[1, 0, 0, 0, 0, 0]
        )
    cfg = {
        "nx": "48",
        "pitch": "1.5e-4",
        "ridges": "false",
        "classes": "SA1",
        "outputs": "force pressure stick slip shear",
        "shear": "partial",
    }
    cfg.update(skin)
    scenes.add_skin_sensor(spec, "pad", {k: v for k, v in cfg.items() if v is not None})
    return spec.compile()


def _controls(ramp_steps: int, q_max_over_mu_p: float) -> np.ndarray:
    """ctrl (x force, z force) per step: pressed at NORMAL_N, then the
    tangential force ramped from 0 to q_max_over_mu_p x mu P."""
    n = PRESS_STEPS + ramp_steps
    ctrl = np.zeros((n, 2))
    ctrl[:, 1] = -NORMAL_N
    ctrl[PRESS_STEPS:, 0] = (
        np.arange(1, ramp_steps + 1) / ramp_steps * q_max_over_mu_p * MU_PAD * NORMAL_N
    )
    return ctrl


def _run(m, d, controls):
    out = np.empty((len(controls), m.nsensordata))
    for k, c in enumerate(controls):
        d.ctrl[:] = c
        mujoco.mj_step(m, d)
        out[k] = d.sensordata
    return out


def _blocks(lay, sd):
    return {name: lay.block(sd, name) for name in ("force", "pressure", "stick", "slip", "shear")}


@pytest.fixture(scope="module", params=sorted(SKINS))
def ramp(request):
    m = _model(SKINS[request.param])
    lay = SkinLayout.from_model(m)
    out = _run(m, mujoco.MjData(m), _controls(1500, 1.25))
    return request.param, lay, out


def test_stuck_share_follows_cattaneo(ramp):
    name, lay, out = ramp
    b = _blocks(lay, out)
    force, slip, stick = b["force"], b["slip"], b["stick"]
    touching = force[:, 0] > 0
    assert np.all(slip[touching, 1] == max(MU_PLATE, MU_PAD))  # mu from the geoms
    ratio = np.hypot(force[:, 1], force[:, 2]) / (slip[:, 1] * force[:, 0] + (~touching))
    loaded = (stick >= 0).sum(axis=1)
    checked = 0
    # Up to 0.9 mu P: beyond, the stick zone is a few cells across and the
    # elastic solver flags single steps' rim cells (|q| within 2e-3 of mu p)
    # as stuck.
    for k in np.flatnonzero(touching & (ratio > 0.05) & (ratio < 0.9))[::25]:
        expected = (1.0 - ratio[k]) ** (2.0 * EXPONENT[name])
        # The grid resolves the stick and contact ellipses' sizes to half a
        # cell each: share = (c/a)^2 moves by share (1/c + 1/a) (c, a the
        # equivalent radii in cells), plus one cell of the count.
        a = np.sqrt(loaded[k] / np.pi)
        c = a * np.sqrt(expected)
        tol = expected * (1.0 / max(c, 0.5) + 1.0 / a) + 1.0 / loaded[k]
        assert abs(slip[k, 0] - expected) <= tol, (k, ratio[k], slip[k, 0], expected, tol)
        assert slip[k, 0] == np.count_nonzero(stick[k] == 1) / loaded[k]
        checked += 1
    assert checked >= 10
    # the shares fall monotonically with the load over the ramp
    on_ramp = np.flatnonzero(touching & (ratio < 0.9))
    on_ramp = on_ramp[on_ramp >= PRESS_STEPS]
    shares = slip[on_ramp, 0]
    # (the creeping pad moves the pressure field: a few rim cells may change)
    assert shares[0] == 1.0 and np.all(np.diff(shares) <= 4.0 / loaded[on_ramp[1:]])
    assert shares[-1] < 0.4


def test_stick_zone_shrinks_monotonically_under_a_rising_load(ramp):
    # Cattaneo under a monotone tangential load: the stick zone only
    # shrinks, so no loaded cell goes from slip back to stick between steps,
    # up to the friction limit (rim cells at |q| ~ mu p flickered when the
    # elastic solve stopped short of convergence above ~0.75 mu P).
    name, lay, out = ramp
    b = _blocks(lay, out)
    force, slip, stick = b["force"], b["slip"], b["stick"]
    ratio = np.hypot(force[:, 1], force[:, 2]) / (slip[:, 1] * force[:, 0] + 1e-300)
    rising = (
        np.flatnonzero((ratio[1:] > ratio[:-1]) & (ratio[:-1] > 0.05) & (ratio[1:] < 1 - 1e-3)) + 1
    )
    rising = rising[rising > PRESS_STEPS]
    assert ratio[rising].max() > 0.97 and len(rising) > 500
    back = [np.count_nonzero((stick[k - 1] == 0) & (stick[k] == 1)) for k in rising]
    assert max(back) == 0, (name, int(np.argmax(back)), max(back))
    high = rising[ratio[rising] > 0.9]
    assert np.all(np.diff(slip[high, 0]) <= 0.0)  # the stuck share falls there too


def test_tractions_sum_to_mujocos_force_and_obey_coulomb(ramp):
    _, lay, out = ramp
    b = _blocks(lay, out)
    n2 = lay.nx * lay.nx
    area = lay.pitch_m**2
    force, slip = b["force"], b["slip"]
    qx, qy, p = b["shear"][:, :n2], b["shear"][:, n2:], b["pressure"]
    image = lay.image(out, "shear")  # (steps, 2, nx, nx), row j along pad y
    assert np.array_equal(image[:, 1].reshape(len(out), n2), qy)
    touching = force[:, 0] > 0
    assert touching[PRESS_STEPS:].mean() > 0.9
    mu_p = slip[:, 1:2] * p
    scale = slip[:, 1] * force[:, 0] + 1e-300
    np.testing.assert_array_less(
        np.abs(qx.sum(1) * area - force[:, 1])[touching], 1e-9 * scale[touching]
    )
    np.testing.assert_array_less(
        np.abs(qy.sum(1) * area - force[:, 2])[touching], 1e-9 * scale[touching]
    )
    # Coulomb: |q| <= mu p everywhere below full slip; = mu p where slipping
    # (within 1e-7 of mu P every cell slips and the solve's residual, 1e-8
    # of the load, is spread over the disks)
    q = np.hypot(qx, qy)
    below = touching & (np.hypot(force[:, 1], force[:, 2]) < (1 - 1e-7) * slip[:, 1] * force[:, 0])
    assert np.all(q[below] <= mu_p[below] * (1 + 1e-9) + 1e-9)
    slipping = (b["stick"] == 0) & below[:, None]
    assert slipping.any()
    np.testing.assert_allclose(q[slipping], mu_p[slipping], rtol=1e-9)
    assert np.all(q[b["stick"] == -1] == 0.0)


def test_full_slip_when_the_force_reaches_mu_p(ramp):
    _, lay, out = ramp
    b = _blocks(lay, out)
    n2 = lay.nx * lay.nx
    force, slip, p = b["force"], b["slip"], b["pressure"]
    # MuJoCo's sliding friction reaches mu P to its solver's tolerance
    full = (force[:, 0] > 0) & (
        np.hypot(force[:, 1], force[:, 2]) >= (1 - 1e-7) * slip[:, 1] * force[:, 0]
    )
    assert full.sum() >= 5
    assert np.all(slip[full, 0] == 0.0)
    assert np.all(b["stick"][full] <= 0)
    # q = p F / P on every cell: the uniform full-slip field, |q| = mu p
    # to MuJoCo's 1e-7
    area = lay.pitch_m**2
    for axis, shear in ((1, b["shear"][full, :n2]), (2, b["shear"][full, n2:])):
        ratio = force[full, axis] / (p[full].sum(1) * area)
        np.testing.assert_allclose(
            shear, ratio[:, None] * p[full], rtol=1e-12, atol=1e-12 * np.abs(shear).max()
        )
    q = np.hypot(b["shear"][full, :n2], b["shear"][full, n2:])
    np.testing.assert_allclose(q, slip[full, 1:2] * p[full], rtol=1e-6)


@pytest.fixture(scope="module", params=sorted(SKINS))
def determinism_model(request):
    skin = dict(SKINS[request.param], oversample="2")
    return _model(skin)


def test_copy_and_reset_are_bit_identical(determinism_model):
    m = determinism_model
    ctrl = _controls(500, 0.9)
    d = mujoco.MjData(m)
    first = _run(m, d, ctrl[:600])
    d2 = mujoco.MjData(m)
    mujoco.mj_copyData(d2, m, d)
    a = _run(m, d, ctrl[600:])
    assert np.array_equal(a, _run(m, d2, ctrl[600:]))
    lay = SkinLayout.from_model(m)
    assert 0.0 < lay.block(a, "slip")[-1, 0] < 1.0  # partial slip was compared
    mujoco.mj_resetData(m, d)
    assert np.array_equal(first, _run(m, d, ctrl[:600]))


# oversample 2 with winkler: the substeps after a step's first read and write
# one tangential buffer; (`elastic` with oversample > 1 repeats only to the
# solver's tolerance, its pressure history's documented limit)
@pytest.mark.parametrize("name, oversample", [("winkler", "2"), ("elastic", "1")])
def test_repeated_evaluation_restores_the_tangential_memory(name, oversample):
    m = _model(dict(SKINS[name], oversample=oversample))
    ctrl = _controls(500, 0.9)
    d = mujoco.MjData(m)
    _run(m, d, ctrl[:600])
    # mj_forward, then mj_forward at the same time with other ctrl, gives
    # what the second alone gives. Without warm start MuJoCo's forces depend
    # on the state alone.
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_WARMSTART
    d2 = mujoco.MjData(m)
    mujoco.mj_copyData(d2, m, d)
    d.ctrl[:] = ctrl[600]
    mujoco.mj_forward(m, d)
    d.ctrl[:] = d2.ctrl[:] = ctrl[600] * [1.3, 1.0]
    mujoco.mj_forward(m, d)
    mujoco.mj_forward(m, d2)
    lay = SkinLayout.from_model(m)
    assert 0.0 < lay.block(d.sensordata, "slip")[0] < 1.0
    assert np.array_equal(d.sensordata, d2.sensordata)
    assert np.array_equal(d.plugin_state, d2.plugin_state)


def test_rollout_two_threads_equals_serial(determinism_model):
    m = determinism_model
    controls = np.stack([_controls(300, 0.6), _controls(300, 1.1)])
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    s0 = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, mujoco.MjData(m), s0, spec)
    s0 = np.repeat(s0[None], len(controls), axis=0)
    _, two = mujoco.rollout.rollout(m, [mujoco.MjData(m), mujoco.MjData(m)], s0, controls)
    for b in range(len(controls)):
        assert np.array_equal(two[b], _run(m, mujoco.MjData(m), controls[b]))


def test_partial_differs_from_full_slip_only_in_shear_distribution():
    # same model, full slip: the same pressure and total force, other shear
    ctrl = _controls(400, 0.6)
    full = dict(SKINS["winkler"], shear="true", outputs="force pressure shear")
    part = dict(SKINS["winkler"], outputs="force pressure shear")
    outs = []
    for skin in (full, part):
        m = _model(skin)
        outs.append((SkinLayout.from_model(m), _run(m, mujoco.MjData(m), ctrl)))
    (lf, of), (lp, op) = outs
    assert np.array_equal(lf.block(of, "force"), lp.block(op, "force"))
    assert np.array_equal(lf.block(of, "pressure"), lp.block(op, "pressure"))
    shear_f, shear_p = lf.block(of, "shear")[-1], lp.block(op, "shear")[-1]
    assert np.isclose(shear_f.sum(), shear_p.sum(), rtol=1e-9)
    assert np.abs(shear_f - shear_p).max() > 0.1 * np.abs(shear_f).max()


@pytest.mark.parametrize(
    "attrs, needle",
    [
        ({"shear": "partly"}, "valid: true (full slip) false partial"),
        ({"shear": "partial", "pressure": "contacts"}, "`shear` = partial needs pressure="),
        ({"shear": "true"}, '`stick` needs shear="partial"'),
        ({"shear": "false", "outputs": "force shear"}, "`shear` needs shear="),
    ],
)
def test_bad_values_name_the_valid_set(attrs, needle):
    skin = dict(SKINS["winkler"], **attrs)
    if "outputs" not in attrs:
        skin["outputs"] = "force stick slip"
    if skin.get("pressure") == "contacts":
        skin.pop("stiffness")
    with pytest.raises(ValueError, match="mjtouch.skin") as err:
        _model(skin)
    assert needle in str(err.value)


def test_bench_example_times_and_checks_the_ramp():
    # examples/bench_partial_slip.py on a short ramp: every configuration
    # timed, partial slip met (0 < stuck share < 1 below the limit), the
    # Winkler solve exact (its tangential solve has no tolerance) and stage
    # 3's split sum close to the exact one.
    import pathlib
    import runpy

    ex = runpy.run_path(
        str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "bench_partial_slip.py")
    )
    start = ex["settled"]("slide_flat", "ramp")
    times = ex["timing"]("slide_flat", "ramp", start, 5, 1)
    assert set(times) == set(ex["CONFIGS"]) and all(v[0] > 0 for v in times.values())
    acc = ex["accuracy"]("slide_flat", "ramp", start, 60)
    for k in ("winkler+partial", "elastic+partial"):
        assert 0.0 < acc[k]["q_over_mu_p_max"] < 1.0
        assert 0.0 < acc[k]["stuck_share"] < 1.0
        # stage 3's coarse correction (stress_fold.h FoldedSplitStresses)
        # against the exact sums: its error a small part of the effect it
        # carries (partial against full slip)
        assert acc[k]["stress_split_rms_rel"] < 0.1 * acc[k]["full_slip_rms_rel"], acc[k]
    assert acc["winkler+partial"]["stress_rms_rel"] == 0.0
    assert acc["winkler+partial"]["stuck_share_max_diff"] == 0.0
