"""Plugin state survives mj_copyData, mj_resetData and threaded rollouts."""

import mujoco
import mujoco.rollout
import numpy as np
from conftest import fast_tip, rollout_and_serial

from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout


def _model():
    proto = scenes.Protocol(timestep_s=2e-4, press_s=0.05)
    return scenes.build_model(fast_tip(), scenes.Texture(period_m=0.6e-3), proto), proto


def _run(m, d, n, speed=0.03):
    out = np.empty((n, m.nsensordata))
    for k in range(n):
        d.ctrl[:] = [speed if d.time > 0.05 else 0.0, -0.5]
        mujoco.mj_step(m, d)
        out[k] = d.sensordata
    return out


def test_copy_data_mid_run_continues_identically():
    m, _ = _model()
    d = mujoco.MjData(m)
    _run(m, d, 400)
    d2 = mujoco.MjData(m)
    mujoco.mj_copyData(d2, m, d)
    a = _run(m, d, 300)
    b = _run(m, d2, 300)
    assert np.array_equal(a, b)
    assert a[:, :].any()  # something nonzero was compared


def test_reset_data_mid_run_repeats_from_start():
    m, _ = _model()
    d = mujoco.MjData(m)
    first = _run(m, d, 500)
    mujoco.mj_resetData(m, d)
    second = _run(m, d, 500)
    assert np.array_equal(first, second)


def test_repeated_forward_does_not_advance_receptors():
    m, _ = _model()
    d = mujoco.MjData(m)
    _run(m, d, 450)
    # mj_step leaves time one step past its sensor evaluation: the first
    # mj_forward evaluates at the new time (a real advance), later ones at
    # the same time must change nothing.
    mujoco.mj_forward(m, d)
    state = d.plugin_state.copy()
    sd = d.sensordata.copy()
    mujoco.mj_forward(m, d)
    mujoco.mj_forward(m, d)
    assert np.array_equal(d.plugin_state, state)
    assert np.array_equal(d.sensordata, sd)


def test_rollout_one_and_two_threads_bit_identical():
    m, proto = _model()
    ctrl = scenes.controls(proto, 0.06)
    speeds = np.array([0.02, 0.03, 0.04, 0.05])
    controls = np.repeat(ctrl[None], len(speeds), axis=0)
    controls[:, int(round(proto.press_s / proto.timestep_s)) :, 0] = speeds[:, None]
    d = mujoco.MjData(m)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    s0 = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, s0, spec)
    s0 = np.repeat(s0[None], len(speeds), axis=0)
    _, one = mujoco.rollout.rollout(m, mujoco.MjData(m), s0, controls)
    _, two = mujoco.rollout.rollout(m, [mujoco.MjData(m), mujoco.MjData(m)], s0, controls)
    assert np.array_equal(one, two)
    # and each batch entry equals a serial mj_step run
    d = mujoco.MjData(m)
    serial = np.empty_like(one[2])
    for k in range(controls.shape[1]):
        d.ctrl[:] = controls[2, k]
        mujoco.mj_step(m, d)
        serial[k] = d.sensordata
    assert np.array_equal(serial, one[2])


def _threads_model(threads: int, pressure: str = "winkler"):
    proto = scenes.Protocol(timestep_s=2e-4, press_s=0.05)
    tip = fast_tip(
        skin={
            "threads": str(threads),
            "pressure": pressure,
            "outputs": "spikes stress force",
            "stress_method": "direct",
        }
    )
    return scenes.build_model(tip, scenes.Texture(period_m=0.6e-3), proto)


def test_stress_threads_one_and_two_bit_identical():
    # The stage's thread pool splits work into chunks fixed by the inputs,
    # each receptor's sum on one thread: sensordata may not depend on the
    # count. `winkler` takes the folded path, `contacts` the reference one.
    for pressure in ("winkler", "contacts"):
        runs = []
        for threads in (1, 2):
            m = _threads_model(threads, pressure)
            runs.append(_run(m, mujoco.MjData(m), 450))
        assert np.array_equal(runs[0], runs[1])
        assert np.abs(runs[0]).max() > 0  # stresses were compared


def test_rollout_two_threads_with_stress_threads_equals_serial():
    # Two rollout threads share the pool with the plugin's own threads=2: a
    # busy pool makes the caller run its chunks itself (no deadlock) and the
    # result equals a serial run.
    m = _threads_model(2)
    proto = scenes.Protocol(timestep_s=2e-4, press_s=0.05)
    two, serial = rollout_and_serial(m, m, proto, 0.07)
    for b in range(len(two)):
        assert np.array_equal(serial[b], two[b])
    assert np.abs(two).max() > 0


def _elastic_model(solver: str, precision: str = "float"):
    # the elastic contact's warm start lives in plugin_state (p(n-1), and
    # p(n-2) for pcg's extrapolation): copies and resets must carry it
    proto = scenes.Protocol(timestep_s=2e-4, press_s=0.05)
    tip = fast_tip(
        skin={
            "pressure": "elastic",
            "contact_solver": solver,
            "elastic_precision": precision,
            "outputs": "force pressure stress",
        }
    )
    return scenes.build_model(tip, scenes.Texture(period_m=0.6e-3), proto)


def test_elastic_pcg_copy_and_reset_are_bit_identical():
    m = _elastic_model("pcg")
    d = mujoco.MjData(m)
    first = _run(m, d, 320)
    d2 = mujoco.MjData(m)
    mujoco.mj_copyData(d2, m, d)
    a = _run(m, d, 60)
    b = _run(m, d2, 60)
    assert np.array_equal(a, b)
    assert a.any()
    mujoco.mj_resetData(m, d)
    assert np.array_equal(_run(m, d, 320), first)


def test_elastic_pcg_matches_the_reference_solver_in_the_plugin():
    # the same rollout with contact_solver = pk (Polonsky & Keer from the last
    # step, the solver before #13) and double FFTs: the reference path against
    # the default (pcg, float FFTs: ~1e-6 from double, test_contact_solver.py).
    # Both stop at tolerance 1e-4 (about their error), so their pressures
    # differ by about that much, not more
    from mjtouch.scene.sensor import SkinLayout

    runs = {}
    for solver, precision in (("pcg", "float"), ("pk", "double")):
        m = _elastic_model(solver, precision)
        out = _run(m, mujoco.MjData(m), 320)
        layout = SkinLayout.from_model(m)
        runs[solver] = {k: layout.block(out, k) for k in ("force", "pressure", "stress")}
    a, b = runs["pcg"], runs["pk"]
    assert np.array_equal(a["force"][:, :3], b["force"][:, :3])  # MuJoCo's forces: same physics
    for block in ("pressure", "stress"):
        diff = np.sqrt(((a[block] - b[block]) ** 2).sum(axis=1))
        norm = np.sqrt((b[block] ** 2).sum(axis=1))
        touching = norm > 0
        assert touching.sum() > 100, block
        worst = (diff[touching] / norm[touching]).max()
        assert worst <= 1e-3, (block, worst)


def test_elastic_solve_box_grows_when_the_contact_jumps():
    # pcg solves on the last step's contact box (+3 cells) and then checks
    # every rendered cell outside it; when the contact outgrows the box the
    # box must grow. Jump the pad 2 mm deeper in one step (0.045 -> 0.36 N): the warm solve
    # (last box far too small) must match a cold solve of the same step on
    # every rendered cell (plugin_state zeroed: no pressure history, so no
    # warm start and no box). Both stop at the 1e-4 tolerance, whose error
    # is <= ~5e-4 against a tight solve (bench_elastic.py), so 2e-3 bounds
    # their difference.
    m = _elastic_model("pcg")
    layout = SkinLayout.from_model(m)
    d = mujoco.MjData(m)
    for _ in range(300):  # a light press: a small contact
        d.ctrl[:] = [0.0, -0.05]
        mujoco.mj_step(m, d)
    before = layout.block(d.sensordata, "pressure") > 0
    press = m.joint("press_z").qposadr[0]
    d.qpos[press] -= 2e-3
    cold = mujoco.MjData(m)
    mujoco.mj_copyData(cold, m, d)
    cold.plugin_state[:] = 0.0  # the warm start comes from the history blocks in it
    for dd in (d, cold):
        dd.ctrl[:] = [0.0, -0.05]
        mujoco.mj_step(m, dd)
    warm_p = layout.block(d.sensordata, "pressure")
    cold_p = layout.block(cold.sensordata, "pressure")
    after = cold_p > 0
    # the contact really outgrew the old box: cells touch > 3 cells beyond it
    n = layout.nx
    rows_before = np.flatnonzero(before.reshape(n, n).any(axis=1))
    rows_after = np.flatnonzero(after.reshape(n, n).any(axis=1))
    assert rows_after[0] < rows_before[0] - 3 and rows_after[-1] > rows_before[-1] + 3
    rel = np.linalg.norm(warm_p - cold_p) / np.linalg.norm(cold_p)
    assert rel <= 2e-3, rel
    assert rel > 0.0  # two solves from different starts: the cold one really was cold


def test_grid_shift_copy_reset_and_rollout_are_bit_identical():
    # grid_shift's second solve starts from its own history in plugin_state
    # (a fresh MjData's scratch holds none): copies, resets and two rollout
    # threads must reproduce it bit for bit, and it must change the
    # pressure (it is on)
    proto = scenes.Protocol(timestep_s=2e-4, press_s=0.05)
    models = {
        gs: scenes.build_model(
            fast_tip(
                skin={"pressure": "elastic", "grid_shift": gs, "outputs": "force pressure stress"}
            ),
            scenes.Texture(period_m=0.6e-3),
            proto,
        )
        for gs in ("false", "true")
    }
    m = models["true"]
    d = mujoco.MjData(m)
    first = _run(m, d, 320)
    assert not np.array_equal(first, _run(models["false"], mujoco.MjData(models["false"]), 320))
    d2 = mujoco.MjData(m)
    mujoco.mj_copyData(d2, m, d)
    a = _run(m, d, 60)
    assert np.array_equal(a, _run(m, d2, 60)) and a.any()
    mujoco.mj_resetData(m, d)
    assert np.array_equal(_run(m, d, 320), first)
    mujoco.mj_resetData(m, d)
    _run(m, d, 300)
    s0 = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, s0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    controls = np.tile([0.03, -0.5], (2, 40, 1))
    _, one = mujoco.rollout.rollout(m, mujoco.MjData(m), np.tile(s0, (2, 1)), controls)
    _, two = mujoco.rollout.rollout(
        m, [mujoco.MjData(m), mujoco.MjData(m)], np.tile(s0, (2, 1)), controls
    )
    assert np.array_equal(one, two) and np.abs(two).max() > 0
