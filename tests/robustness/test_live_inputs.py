"""Inputs that go bad while a model runs: an indentation past the skin is
flagged in the force block and warned once; a height field edited after the
MjData exists is followed (an edit rebuilds its cache) and a non-finite
sample is warned once, the field left out, never silently zero."""

import pathlib

import mujoco
import numpy as np
import pytest

from mjtouch.sensor import SkinLayout

SCENE = pathlib.Path(__file__).resolve().parents[2] / "models" / "slide_grating.xml"
STACK_M = 0.7e-3 + 0.8e-3 + 2.5e-3  # the default layers over bone
BEYOND = "exceeds the skin stack over the rigid base"


def slide_model(xml_edit=lambda x: x, **skin) -> mujoco.MjModel:
    xml = xml_edit(SCENE.read_text())
    extra = "".join(f'<config key="{k}" value="{v}"/>' for k, v in skin.items())
    anchor = '<config key="texture_group" value="3"/>'
    return mujoco.MjModel.from_xml_string(xml.replace(anchor, anchor + extra))


def press(m, newtons, steps, d=None, edit=None):
    """Force blocks (steps x 5) of a press at `newtons` (no slide)."""
    layout = SkinLayout.from_model(m)
    d = d or mujoco.MjData(m)
    out = []
    for i in range(steps):
        if edit:
            edit(i, m, d)
        d.ctrl[:] = [0.0, -newtons]
        mujoco.mj_step(m, d)
        out.append(layout.block(d.sensordata, "force").copy())
    return np.array(out), d


@pytest.mark.parametrize("pressure", ["elastic", "winkler"])
def test_indentation_past_the_stack_is_flagged_and_warned_once(pressure, capfd):
    m = slide_model(pressure=pressure)
    capfd.readouterr()
    force, _ = press(m, 100.0, 1500)  # the shipped press allows 100 N
    depth, flag = force[:, 3], force[:, 4]
    assert depth.max() > STACK_M, depth.max()
    # the flag is exactly "touching deeper than the stack"
    np.testing.assert_array_equal(flag, (depth > STACK_M).astype(float))
    out = "".join(capfd.readouterr())
    assert out.count(BEYOND) == 1, out


def test_light_press_is_not_flagged(capfd):
    m = slide_model()
    capfd.readouterr()
    force, _ = press(m, 0.5, 1500)
    assert 0 < force[:, 3].max() < STACK_M
    assert not force[:, 4].any()
    assert BEYOND not in "".join(capfd.readouterr())


def test_height_field_z_size_1e30_is_flagged(capfd):
    # an absurd elevation scale gives an absurd indentation: flagged, warned
    m = slide_model(
        lambda x: x.replace('size="0.04 0.015 0.0001 0.001"', 'size="0.04 0.015 1e30 0.001"')
    )
    capfd.readouterr()
    force, _ = press(m, 0.5, 600)
    touching = force[:, 0] > 0
    assert touching.any()
    assert np.all(force[touching, 4] == (force[touching, 3] > STACK_M))
    assert force[:, 4].any()
    assert "".join(capfd.readouterr()).count(BEYOND) == 1


def test_non_finite_sample_edited_in_is_warned_once_and_left_out(capfd):
    # inf in a column under the pad after MjData exists: the texture is left
    # out (the plate alone) with one warning, as if it were not a texture
    m = slide_model()
    plain = slide_model(lambda x: x.replace('group="3" rgba="0.45', 'group="4" rgba="0.45'))
    d = mujoco.MjData(m)
    col = m.hfield_ncol[0] // 2
    m.hfield_data[col] = np.inf  # row 0, under the pad's start
    capfd.readouterr()
    edited, _ = press(m, 0.5, 300, d=d)
    out = "".join(capfd.readouterr())
    assert out.count(f"has sample inf at row 0, col {col}") == 1, out
    assert "edited after the MjData was made" in out
    ref, _ = press(plain, 0.5, 300)
    assert ref[:, 0].any()
    np.testing.assert_array_equal(edited, ref)


def test_finite_edit_rebuilds_the_height_field_cache():
    # after contact, halve the grating's relief: the running skin must see
    # the edited field as a fresh copy of the MjData (whose cache starts
    # empty) does
    m = slide_model()
    layout = SkinLayout.from_model(m)
    d = mujoco.MjData(m)
    press(m, 0.5, 300, d=d)
    m.hfield_data[:] *= 0.5
    fresh = mujoco.MjData(m)
    mujoco.mj_copyData(fresh, m, d)
    for _ in range(50):
        for x in (d, fresh):
            x.ctrl[:] = [0.0, -0.5]
            mujoco.mj_step(m, x)
        np.testing.assert_array_equal(d.sensordata, fresh.sensordata)
    assert layout.block(d.sensordata, "stress").any()


def test_local_edit_is_followed_within_the_checked_blocks():
    # ~20 samples under the pad changed (in both rows of the 2 x 4001 grating,
    # none of the evenly spread samples each step compares): the moving block
    # reaches it within ceil(8002 / 4096) = 2 steps, after which the running
    # skin renders what a fresh copy (cache built from the edited field)
    # renders. Winkler: the stress is a function of this step's field alone.
    m = slide_model(pressure="winkler")
    layout = SkinLayout.from_model(m)
    ncol = m.hfield_ncol[0]
    d = mujoco.MjData(m)
    press(m, 0.5, 300, d=d)
    unedited = slide_model(pressure="winkler")
    untouched = mujoco.MjData(unedited)
    press(unedited, 0.5, 300, d=untouched)
    half_x = m.hfield_size[0][0]
    pole = int(round((d.geom("pad").xpos[0] + half_x) / (2 * half_x) * (ncol - 1)))
    cols = np.arange(pole - 10, pole + 11)  # 0.4 mm under the pole
    stride = m.hfield_data.size // 256  # leave out the spread samples
    rows = np.arange(m.hfield_nrow[0])[:, None]
    cols = cols[np.all((rows * ncol + cols) % stride != 0, axis=0)]
    assert cols.size >= 15
    k = (rows * ncol + cols).ravel()
    m.hfield_data[k] = 1.0 - m.hfield_data[k]
    fresh = mujoco.MjData(m)
    mujoco.mj_copyData(fresh, m, d)
    stress = lambda x: layout.block(x.sensordata, "stress").copy()  # noqa: E731
    for step in range(20):
        for model, x in ((m, d), (m, fresh), (unedited, untouched)):
            x.ctrl[:] = [0.0, -0.5]
            mujoco.mj_step(model, x)
        if step >= 2:
            np.testing.assert_array_equal(stress(d), stress(fresh), err_msg=f"step {step}")
    # the edited sample is felt: the unedited field gives another stress
    assert not np.array_equal(stress(d), stress(untouched))
