"""Never a silent zero: the `coverage` output carries the share of MuJoCo's
normal force on the pad geom that lands on the skin's patch, and contact off
the patch is warned once (MuJoCo warning text; a Python OffPatchWarning from
SkinLayout.coverage)."""

import mujoco
import numpy as np
import pytest
from test_robot_facing import CAPSULE_SIDEWAYS, R, mujoco_normal_n, pressed

import mjtouch
from mjtouch.scene.sensor import OffPatchWarning

OFF_PATCH = "lands off the skin's patch"


def coverage(model, data):
    lay = mjtouch.layouts(model)["skin_tip"]
    return lay, lay.block(data.sensordata, "coverage")


def test_sideways_contact_on_the_skins_side_is_covered(capfd):
    model, data = pressed(CAPSULE_SIDEWAYS, R, facing=(1, 0, 0), outputs="force coverage")
    lay, cov = coverage(model, data)
    assert cov[0] == 1.0
    assert cov[1] == pytest.approx(mujoco_normal_n(model, data), rel=1e-12)
    assert lay.coverage(data.sensordata) == 1.0  # no warning (filterwarnings = error)
    assert OFF_PATCH not in capfd.readouterr().err


def test_contact_on_the_far_side_is_reported_and_warned_once(capfd):
    # the skin on the capsule's -z end cap, the capsule lying on its side:
    # MuJoCo's contact is on the cylinder, which the skin does not cover
    model, data = pressed(CAPSULE_SIDEWAYS, R, outputs="force coverage")
    lay, cov = coverage(model, data)
    mj = mujoco_normal_n(model, data)
    assert mj > 0.4
    assert cov[0] == 0.0 and cov[1] == pytest.approx(mj, rel=1e-12)
    err = capfd.readouterr().err
    assert err.count(OFF_PATCH) == 1  # once over the 400 steps
    assert "'skin_tip'" in err and "pad geom 'tip'" in err
    with pytest.warns(OffPatchWarning, match="carries 0 of MuJoCo's"):
        lay.coverage(data.sensordata)


@pytest.mark.parametrize("nx, covered", [(16, False), (160, True)])
def test_contact_beyond_the_grid(nx, covered, capfd):
    # a sphere turned 30 degrees about x: it touches the plate 30 degrees
    # off its pole, R sin 30 = 3 mm across the skin; a 1.6 mm grid misses
    # it, a 16 mm grid holds it
    sphere = dict(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[2 * R / 1.6, 0, 0], euler=[30, 0, 0])
    model, data = pressed(
        sphere, 2 * R / 1.6, outputs="force coverage", nx=nx, pitch=1e-4, radius=5e-4
    )
    lay, cov = coverage(model, data)
    assert cov[1] == pytest.approx(mujoco_normal_n(model, data), rel=1e-12) and cov[1] > 0.4
    assert cov[0] == (1.0 if covered else 0.0)
    assert (OFF_PATCH in capfd.readouterr().err) != covered


def test_coverage_reads_a_rollout_and_warns_from_python():
    model, _ = pressed(CAPSULE_SIDEWAYS, R, outputs="coverage")
    lay = mjtouch.layouts(model)["skin_tip"]
    sd = np.zeros((3, model.nsensordata))
    sd[:, lay.sensor_adr + lay.blocks["coverage"].start :][:, :2] = [[1, 0], [1, 0.2], [0.25, 0.4]]
    with pytest.warns(OffPatchWarning, match=r"carries 0.25 of MuJoCo's 0.4 N"):
        share = lay.coverage(sd)
    np.testing.assert_array_equal(share, [1, 1, 0.25])
