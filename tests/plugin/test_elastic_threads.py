"""The `elastic` contact solve on the `threads` pool (plugin/core/common/fft.*,
contact/contact_solver.cc): each compliance apply's FFT passes are split by
columns / frequency lanes and the preconditioner by rows, parts that write
disjoint outputs with per-lane arithmetic independent of the split, so
sensordata must not depend on the thread count; and a rollout whose threads
share the pool with the plugin's must equal serial runs."""

import mujoco
import numpy as np
import pytest
from conftest import fast_tip, rollout_and_serial

from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

PROTO = scenes.Protocol(timestep_s=2e-4, press_s=0.05)


def _model(threads: int, solver: str = "pcg", precision: str = "float", shift: bool = False):
    tip = fast_tip(
        skin={
            "pressure": "elastic",
            "threads": str(threads),
            "contact_solver": solver,
            "elastic_precision": precision,
            "grid_shift": str(shift).lower(),
            "outputs": "force pressure stress",
        }
    )
    return scenes.build_model(tip, scenes.Texture(period_m=0.6e-3), PROTO)


def _run(m, n, speed=0.03):
    d = mujoco.MjData(m)
    out = np.empty((n, m.nsensordata))
    for k in range(n):
        d.ctrl[:] = [speed if d.time > PROTO.press_s else 0.0, -0.5]
        mujoco.mj_step(m, d)
        out[k] = d.sensordata
    return out


@pytest.mark.parametrize(
    "solver, precision, shift",
    [("pcg", "float", False), ("pk", "double", False), ("pcg", "float", True)],
)  # grid_shift: its shifted solve too
def test_elastic_sensordata_identical_for_threads_1_2_3(solver, precision, shift):
    runs = {t: _run(_model(t, solver, precision, shift), 320) for t in (1, 2, 3)}
    m = _model(1, solver, precision, shift)
    pressure = SkinLayout.from_model(m).block(runs[1], "pressure")
    # the solve ran: a fragmented contact of many cells while sliding
    assert (pressure[-1] > 0).sum() > 50
    assert np.array_equal(runs[1], runs[2])
    assert np.array_equal(runs[1], runs[3])


def test_rollout_threads_share_the_pool_with_the_elastic_solve():
    # two rollout threads, each plugin instance asking for 2 threads: a busy
    # pool makes a caller run its parts itself (no deadlock, same bits)
    m = _model(2)
    two, serial = rollout_and_serial(m, _model(1), PROTO, 0.06)
    for b in range(len(two)):
        assert np.array_equal(serial[b], two[b])
    assert SkinLayout.from_model(m).block(two, "pressure").max() > 0
