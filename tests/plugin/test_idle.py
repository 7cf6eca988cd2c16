"""An untouched skin skips its receptors (plugin/core/pipeline/step.cc, idle
receptors) and makes the idle time up in one exact step when contact
resumes. Skipping must not change what the receptors report."""

import mujoco
import numpy as np
import pytest

from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

IDLE_SLOT = 4  # plugin_state header: kStReceptorsIdle (plugin/core/pipeline/model.h)


def run(outputs, **skin):
    tip = scenes.Fingertip(nx=48, pitch_m=1.5e-4, ridges=False, skin={"outputs": outputs, **skin})
    m = scenes.build_model(tip, scenes.Texture(kind="flat"), scenes.Protocol(timestep_s=2e-4))
    d = mujoco.MjData(m)
    layout = SkinLayout.from_model(m)
    spikes, idle = [], []
    for k in range(4000):
        # press 0.16 s, lift 0.32 s (the membranes relax, the filters ring
        # down), press again
        d.ctrl[:] = [0.0, -0.5 if (k < 800 or k >= 2400) else 0.02]
        mujoco.mj_step(m, d)
        spikes.append(layout.block(d.sensordata, "spikes").copy())
        idle.append(d.plugin_state[m.plugin_stateadr[0] + IDLE_SLOT])
    return np.array(spikes), np.array(idle)


def test_idle_receptors_report_what_stepped_receptors_report():
    # With a voltage output every step is advanced (the membranes are shown);
    # with spikes only, quiescent receptors are skipped while untouched.
    # Noise off: the catch-up is then exact (with noise it draws one
    # Ornstein-Uhlenbeck transition for the whole gap, not the stepped path).
    skipped, idle = run("spikes force", noise="0 0 0")
    stepped, never = run("spikes voltage force", noise="0 0 0")
    assert idle.max() == 1 and never.max() == 0  # the idle path was taken, and only there
    assert idle[1600:2400].all()  # the second half of the lift was idle
    assert idle[3000:].max() == 0  # and contact ended it
    assert stepped.sum() > 0 and stepped[2400:].sum() > 0
    # Exact integration over one long step or many short ones: the same
    # spikes. Round-off (1e-16 relative) moves a spike time by ~1e-15 s, so a
    # spike lying within that of a step boundary may be counted one step
    # earlier or later: per receptor the running counts differ by at most 1,
    # the totals not at all.
    lag = np.abs(np.cumsum(skipped, axis=0) - np.cumsum(stepped, axis=0))
    assert lag.max() <= 1
    np.testing.assert_array_equal(skipped.sum(axis=0), stepped.sum(axis=0))
    assert (skipped != stepped).any(axis=1).sum() <= 4  # and rarely


def test_idle_with_default_noise_is_taken_and_deterministic():
    # Default noise: untouched receptors rest >= 4.5 membrane noise sds below
    # threshold (receptors.cc Quiescent), so the idle path is still taken.
    # Its catch-up draws other noise than stepping would (the pad starts in
    # the air, so from the first landing on): the same run twice is
    # bit-identical, and in each press the counts match the stepped run's to
    # within noise (per class totals within 15%).
    skipped, idle = run("spikes force")
    again, _ = run("spikes force")
    stepped, never = run("spikes voltage force")
    assert idle[1600:2400].all() and never.max() == 0
    np.testing.assert_array_equal(skipped, again)
    layout = SkinLayout.from_model(
        scenes.build_model(
            scenes.Fingertip(nx=48, pitch_m=1.5e-4, ridges=False),
            scenes.Texture(kind="flat"),
            scenes.Protocol(timestep_s=2e-4),
        )
    )
    for c in ("SA1", "RA", "PC"):
        m = layout.classes == c
        for press in (slice(0, 800), slice(2400, None)):
            a, b = skipped[press, m].sum(), stepped[press, m].sum()
            assert b > 0 and abs(a - b) <= 0.15 * b, (c, press, a, b)


@pytest.mark.parametrize(
    "skin",
    [
        {"pressure": "winkler"},
        {"pressure": "winkler", "oversample": "3"},
        {"pressure": "winkler", "oversample": "3", "substep": "receptors"},
        {"pressure": "elastic", "nx": "24"},
    ],
    ids=["winkler", "oversample3", "substep_receptors", "elastic"],
)
def test_idle_steps_repeated_by_forward_equal_steps_alone(skin):
    # An idle step saves neither the receptor blocks nor the last quantities
    # (it leaves them as they are): an mj_forward with other ctrl before each
    # mj_step still leaves no trace, through press, idle lift and press.
    # (`elastic` at K = 1 only: oversampled, its repeat agrees to the solver's
    # tolerance, not bit for bit; step.cc SaveOrRestoreEvaluationStart.)
    nx = int(skin.pop("nx", 48))
    tip = scenes.Fingertip(nx=nx, pitch_m=1.5e-4, ridges=False, skin={"outputs": "spikes force"})
    tip.skin.update(skin)
    m = scenes.build_model(tip, scenes.Texture(kind="flat"), scenes.Protocol(timestep_s=2e-4))

    def run(forward: bool):
        d = mujoco.MjData(m)
        out, idle = [], []
        for k in range(3000):
            press = [0.0, -0.5 if (k < 800 or k >= 2400) else 0.02]
            if forward:
                d.ctrl[:] = [0.0, 0.3]
                mujoco.mj_forward(m, d)
            d.ctrl[:] = press
            mujoco.mj_step(m, d)
            out.append(d.sensordata.copy())
            idle.append(d.plugin_state[m.plugin_stateadr[0] + IDLE_SLOT])
        return np.array(out), np.array(idle)

    alone, idle = run(False)
    both, _ = run(True)
    assert idle[1600:2400].all() and idle[2600:].max() == 0
    assert alone[2400:].any()
    np.testing.assert_array_equal(both, alone)
