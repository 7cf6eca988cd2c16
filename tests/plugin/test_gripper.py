"""Skin on any robot (issue 16): mjtouch.attach on the two fingertips of the
gripper example, each its own instance and readout; compile, copy, reset and
rollout stay deterministic."""

import pathlib
import runpy

import mujoco
import numpy as np
import pytest

import mjtouch
from mjtouch.scene import scenes

EX = runpy.run_path(
    str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "gripper_slide.py"),
    run_name="example",
)
PROTOCOL = scenes.Protocol(force_n=0.5, speed_m_s=0.04, timestep_s=2e-4)


@pytest.fixture(scope="module")
def gripper():
    model = EX["gripper_spec"](PROTOCOL).compile()
    ctrl = EX["controls"](model, PROTOCOL, 0.45)
    state, sd = EX["run"](model, ctrl, nthread=2)  # two threads, the same inputs
    return model, ctrl, state, sd


def test_two_fingertips_each_their_own_instance_and_readout(gripper):
    model, _, state, sd = gripper
    lays = mjtouch.layouts(model)
    assert sorted(lays) == ["skin_left", "skin_right"]
    assert lays["skin_left"].instance != lays["skin_right"].instance
    assert lays["skin_left"].sensor_adr != lays["skin_right"].sensor_adr
    assert np.array_equal(sd[0], sd[1]) and np.array_equal(state[0], state[1])
    out = EX["readouts"](model, sd[0], PROTOCOL)
    # each finger's strongest stress line is V/D of its own face's grating
    # (40 Hz left, 25 Hz right: 6 FFT bins apart), at the squeeze force
    for side in ("left", "right"):
        r = out[side]
        assert abs(r["peaks_hz"][0] - r["expected_hz"]) <= r["fft_bin_hz"], (side, r)
        assert r["normal_force_n"] == pytest.approx(PROTOCOL.force_n, rel=0.05)
        assert sum(r["rates_hz"].values()) > 0


def test_copy_reset_and_stepping_match_the_rollout(gripper):
    model, ctrl, _, sd = gripper
    n = 1000  # past the press (750 steps) into the slide
    data = mujoco.MjData(model)
    rows = []
    for k in range(n):
        data.ctrl[:] = ctrl[k]
        mujoco.mj_step(model, data)
        rows.append(data.sensordata.copy())
        if k == n // 2:
            twin = mujoco.MjData(model)
            mujoco.mj_copyData(twin, model, data)
            twin_start = k + 1
    assert np.array_equal(np.array(rows), sd[0, :n])
    for k in range(twin_start, n):
        twin.ctrl[:] = ctrl[k]
        mujoco.mj_step(model, twin)
    assert np.array_equal(twin.sensordata, rows[-1])
    mujoco.mj_resetData(model, data)
    for k in range(n):
        data.ctrl[:] = ctrl[k]
        mujoco.mj_step(model, data)
    assert np.array_equal(data.sensordata, rows[-1])


def test_attach_errors_name_the_problem():
    spec = EX["gripper_spec"](PROTOCOL)
    with pytest.raises(ValueError, match="'nope' is not in the spec"):
        mjtouch.attach(spec, "nope")
    with pytest.raises(ValueError, match="is taken"):
        mjtouch.attach(spec, "pad_left", name="skin_left")
    spec.worldbody.add_geom(name="disk", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[0.01, 0.001, 0])
    with pytest.raises(ValueError, match="'disk' is a mjGEOM_CYLINDER"):
        mjtouch.attach(spec, "disk")
    mjtouch.attach(spec, "bar", name="skin_bad", nx=3)  # checked at compile time
    with pytest.raises(ValueError, match="nx"):
        spec.compile()
