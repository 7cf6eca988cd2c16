"""The receptors' inputs at a step are the step's own: an mj_forward at the
same time with other inputs (ctrl) before the mj_step leaves no trace."""

import pathlib

import mujoco
import numpy as np
import pytest

SCENE = pathlib.Path(__file__).resolve().parents[2] / "models" / "slide_grating.xml"


def slide_model(**skin) -> mujoco.MjModel:
    xml = SCENE.read_text()
    extra = "".join(f'<config key="{k}" value="{v}"/>' for k, v in skin.items())
    anchor = '<config key="texture_group" value="3"/>'
    return mujoco.MjModel.from_xml_string(xml.replace(anchor, anchor + extra))


def press_ctrl(i: int) -> list[float]:
    """Slide at 0.5 (integrated), press 1 to 1.5 N varying (the press pulls
    the pad down: negative)."""
    return [0.5, -1.0 - 0.5 * np.sin(0.05 * i)]


def run(m, steps, forward_ctrl=None, first_only=False, pressed=False):
    """sensordata per step; before each mj_step (or only the first),
    an mj_forward with forward_ctrl when given. pressed: start with the pad
    1 mm into the plate (touching at t = 0)."""
    d = mujoco.MjData(m)
    if pressed:
        d.joint("press_z").qpos = -1e-3
    out = np.empty((steps, m.nsensordata))
    for i in range(steps):
        if forward_ctrl is not None and (i == 0 or not first_only):
            d.ctrl[:] = forward_ctrl
            mujoco.mj_forward(m, d)
        d.ctrl[:] = press_ctrl(i)
        mujoco.mj_step(m, d)
        out[i] = d.sensordata
    return out


SKINS = {
    "elastic": {},
    "winkler": {"pressure": "winkler"},
    "contacts": {"pressure": "contacts", "oversample": "1"},
    "winkler_oversample3": {"pressure": "winkler", "oversample": "3"},
    "elastic_grid_shift": {"grid_shift": "true"},
}


@pytest.mark.parametrize("skin", SKINS, ids=list(SKINS))
def test_forward_with_other_ctrl_then_step_equals_step_alone(skin):
    m = slide_model(**SKINS[skin])
    alone = run(m, 200)
    assert alone[:, :].any(), "the press must touch"
    both = run(m, 200, forward_ctrl=[0.0, 0.0])
    # bit-identical: the forward's evaluation is replaced, not integrated
    np.testing.assert_array_equal(both, alone)


@pytest.mark.parametrize("tolerance", [1e-4, 1e-6])
def test_elastic_oversampled_repeat_agrees_within_the_solver_tolerance(tolerance):
    # The documented exception: `elastic` with oversample > 1. The substeps
    # of the first evaluation overwrite the pressure history the repeated
    # one would warm-start from; the receptors still take the step's own
    # inputs, and the CG converges to its `tolerance` from the other start,
    # so the stress agrees to about that tolerance (shrinking with it).
    from mjtouch.sensor import SkinLayout

    m = slide_model(oversample="3", tolerance=repr(tolerance))
    blocks = SkinLayout.from_model(m).blocks
    alone = run(m, 200)
    both = run(m, 200, forward_ctrl=[0.0, 0.0])
    for name in ("stress", "force"):
        a, b = alone[:, blocks[name]], both[:, blocks[name]]
        rel = np.abs(a - b).max() / np.abs(a).max()
        assert rel <= 10 * tolerance, (name, rel)
    spikes = blocks["spikes"]
    assert abs(both[:, spikes].sum() - alone[:, spikes].sum()) <= 0.01 * alone[:, spikes].sum()


def test_leading_forward_of_a_fresh_run_leaves_the_spikes():
    # a forward with ctrl 0 at t = 0 (e.g. to draw the first frame) before
    # the run's first step
    from mjtouch.sensor import SkinLayout

    m = slide_model()
    layout = SkinLayout.from_model(m)
    spikes = layout.blocks["spikes"]
    alone = run(m, 400, pressed=True)
    lead = run(m, 400, forward_ctrl=[0.0, 0.0], first_only=True, pressed=True)
    assert alone[:, spikes].sum() > 0
    np.testing.assert_array_equal(lead, alone)


def test_repeated_forward_with_unchanged_inputs_changes_nothing():
    m = slide_model()
    d = mujoco.MjData(m)
    for i in range(150):
        d.ctrl[:] = press_ctrl(i)
        mujoco.mj_step(m, d)
    mujoco.mj_forward(m, d)
    first = d.sensordata.copy()
    state = d.plugin_state.copy()
    for _ in range(3):
        mujoco.mj_forward(m, d)
    np.testing.assert_array_equal(d.sensordata, first)
    np.testing.assert_array_equal(d.plugin_state, state)


def test_copy_after_forward_steps_like_the_original():
    # the saved evaluation start lives in plugin_state: a copy taken between
    # the forward and the step steps as the uncopied run does
    m = slide_model(pressure="winkler")
    d = mujoco.MjData(m)
    for i in range(100):
        d.ctrl[:] = press_ctrl(i)
        mujoco.mj_step(m, d)
    ref = mujoco.MjData(m)
    mujoco.mj_copyData(ref, m, d)
    d.ctrl[:] = [0.0, 0.0]
    mujoco.mj_forward(m, d)
    copy = mujoco.MjData(m)
    mujoco.mj_copyData(copy, m, d)
    for i in range(100, 160):
        for x in (ref, copy):
            x.ctrl[:] = press_ctrl(i)
            mujoco.mj_step(m, x)
        np.testing.assert_array_equal(copy.sensordata, ref.sensordata)
