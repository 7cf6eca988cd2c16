"""Five skins on Gymnasium-Robotics' Shadow hand, one attach(spec, body=...)
call each, on the capsule fingertips' pad side (`facing`): fingertips pressed
by fixed plates report MuJoCo's normal force on their geom and spike; the
untouched one stays silent."""

import importlib.util
import math
import pathlib
import re

import mujoco
import numpy as np
import pytest

import mjtouch
from mjtouch import cli
from mjtouch.bench import hand
from mjtouch.bench.configs import DEFAULT_DENSITY, PRESETS

# the assets only (importing gymnasium_robotics registers every env)
_SPEC = importlib.util.find_spec("gymnasium_robotics")
assert _SPEC is not None, "Gymnasium-Robotics is missing: pip install -e '.[test]' (or [robots])"
HAND_XML = (
    pathlib.Path(_SPEC.submodule_search_locations[0]) / "envs" / "assets" / "hand" / "reach.xml"
)
FINGERS = ("ff", "mf", "rf", "lf", "th")
PRESSED = ("ff", "mf", "rf", "th")  # lf stays free
RL = mjtouch.scene.robot.RL_SKIN  # the bench's `rl` preset
DEPTH_M = 1.5e-3  # each plate starts this far into its fingertip


pad_facing = hand.pad_facing  # the hand bench's rule: one copy


def test_five_shadow_fingertips_report_mujocos_normal_force():
    spec = mujoco.MjSpec.from_file(str(HAND_XML))
    spec.option.gravity = [0, 0, 0]  # the weak servos (kp 1-5) would let the fingers sag
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    facing = {f: pad_facing(model, data, f) for f in FINGERS}
    # a fixed plate against each pressed pad, normal along the pad's outward
    hand.add_pad_plates(spec, model, data, facing, PRESSED, depth_m=DEPTH_M)
    for f in FINGERS:  # one call each: the body's one colliding geom, its pad side
        mjtouch.attach(
            spec,
            body=f"robot0:{f}distal",
            name=f"skin_{f}",
            facing=facing[f],
            outputs="spikes force coverage",
            **RL,
        )
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    skins = mjtouch.layouts(model)
    spikes = {f: 0.0 for f in FINGERS}
    steps = 250  # 0.5 s at the env's 2 ms
    for _ in range(steps):
        data.ctrl[:] = 0.0
        mujoco.mj_step(model, data)
        for f in FINGERS:
            spikes[f] += skins[f"skin_{f}"].block(data.sensordata, "spikes").sum()
    for f in FINGERS:
        lay = skins[f"skin_{f}"]
        g = model.geom(f"robot0:C_{f}distal").id
        mj = 0.0
        for i in range(data.ncon):
            if g in data.contact[i].geom:
                fc = np.zeros(6)
                mujoco.mj_contactForce(model, data, i, fc)
                mj += fc[0]
        force = lay.block(data.sensordata, "force")
        cov = lay.block(data.sensordata, "coverage")
        if f in PRESSED:
            assert mj > 0.01, (f, mj)  # pressed (weak servos: 0.03-0.3 N)
            assert force[0] == pytest.approx(mj, rel=0.05), f
            assert cov[0] == 1.0 and cov[1] == pytest.approx(mj, rel=1e-9), (f, cov)
            assert spikes[f] > 0, f
        else:
            assert mj == 0.0 and force[0] == 0.0 and spikes[f] == 0, (f, mj, spikes[f])


def test_hand_bench_runs_every_row(capsys):
    # `python -m mjtouch bench --hand` (mjtouch.bench.hand, the README cost
    # table's source): its smoke run prints every row with finite positive
    # times, and its skins are the bench's rl preset (half the default
    # densities, the preset's grid and substeps)
    rl = hand.rl_attributes()
    p = PRESETS["rl"]
    assert rl["nx"] == p["nx"] and rl["pitch"] == p["pitch_m"]
    np.testing.assert_allclose(rl["density"], np.array(DEFAULT_DENSITY) * p["density_scale"])
    assert rl["substep"] == p["skin.substep"] == "receptors"
    assert mjtouch.scene.robot.RL_SKIN == rl  # what README's snippet and the envs attach
    assert cli.main(["bench", "--hand", "--quick"]) == 0
    text = capsys.readouterr().out
    rows = [
        "bare, free",
        "bare + 1 acc-stage sensor, free",
        "5 skins rl, idle",
        "bare, 4 tips pressed",
        "5 skins rl, 4 pressed",
        "5 skins rl substep=full, 4 pressed",
        "5 default skins, 4 pressed",
    ]
    number = r"([0-9]+(?:\.[0-9]*)?)"
    for row in rows:
        found = re.findall(re.escape(row) + r"\s+" + r"\s+".join([number] * 4), text)
        # thread CPU, then rollout in-thread and threaded for all but two rows
        assert len(found) == (3 if row in rows[:5] else 1), (row, text)
        for values in found:
            assert all(math.isfinite(float(v)) and float(v) > 0 for v in values), (row, text)
