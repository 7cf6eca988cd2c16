"""`facing`: a skin on any side of its pad geom. The skin's frame is the
geom's turned so -z points along `facing`, and the pad's surface is the
geom's exact near side seen along it (a sideways capsule's cylinder)."""

import mujoco
import numpy as np
import pytest

import mjtouch

R, HALF = 5e-3, 5e-3  # capsule radius and half length, m
MASS = 0.05  # kg: the plate carries m g
N, PITCH = 64, 2.5e-4
STIFFNESS = 2e7  # Pa/m, the Winkler default


def pressed(geom_kw: dict, rest_z: float, **skin) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """A finger on a slide joint resting on a plate under gravity (settled)."""
    spec = mujoco.MjSpec()
    spec.option.timestep = 1e-3
    spec.worldbody.add_geom(
        name="plate", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.03, 0.03, 0.002], pos=[0, 0, -0.002]
    )
    body = spec.worldbody.add_body(name="finger", pos=[0, 0, rest_z])
    body.add_joint(name="z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    body.add_geom(name="tip", mass=MASS, **geom_kw)
    attrs = dict(
        nx=N, pitch=PITCH, pressure="winkler", outputs="force pressure", ridges=False, radius=4e-3
    )
    attrs.update(skin)
    mjtouch.attach(spec, "tip", **attrs)
    model = spec.compile()
    data = mujoco.MjData(model)
    for _ in range(400):
        mujoco.mj_step(model, data)
    return model, data


def mujoco_normal_n(model, data) -> float:
    g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "tip")
    total = 0.0
    for i in range(data.ncon):
        if g in data.contact[i].geom:
            f = np.zeros(6)
            mujoco.mj_contactForce(model, data, i, f)
            total += f[0]
    return total


def readout(model, data):
    lay = mjtouch.layouts(model)["skin_tip"]
    force = lay.block(data.sensordata, "force")
    p = lay.block(data.sensordata, "pressure").reshape(N, N)  # [y, x] in the skin frame
    return force, p


CAPSULE_SIDEWAYS = dict(
    type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[R, HALF, 0], euler=[0, 90, 0]
)  # axis along world x; world down = geom +x


def test_sideways_capsule_is_its_cylinder_pressed_on_a_plate():
    model, data = pressed(CAPSULE_SIDEWAYS, R, facing=(1, 0, 0))
    force, p = readout(model, data)
    mj = mujoco_normal_n(model, data)
    assert mj == pytest.approx(MASS * 9.81, rel=1e-3)  # settled
    assert force[0] == pytest.approx(mj, rel=0.05)
    assert p.sum() * PITCH**2 == pytest.approx(mj, rel=0.05)
    # Winkler: p = k * overlap, the overlap of the capsule's side at the
    # solved approach; the skin's x is the capsule axis (the smallest turn
    # from -z to geom +x maps skin x to geom z)
    approach = force[3]
    x = (np.arange(N) - (N - 1) / 2) * PITCH
    X, Y = np.meshgrid(x, x)
    r2 = np.maximum(np.abs(X) - HALF, 0) ** 2 + Y**2
    height = np.where(r2 < R * R, R - np.sqrt(np.maximum(R * R - r2, 0)), np.inf)
    overlap = np.maximum(approach - height, 0)
    # cell means vs centre values: curvature error ~ pitch^2 / (12 R) = 1 um
    assert np.abs(p / STIFFNESS - overlap).max() < PITCH**2 / (6 * R)
    assert overlap.max() > 100 * PITCH**2 / (6 * R)
    # the patch is the cylinder's line contact: long along x, narrow across
    cols, rows = np.nonzero(p.sum(0))[0], np.nonzero(p.sum(1))[0]
    assert (cols[-1] - cols[0] + 1) * PITCH > 2 * HALF
    assert (rows[-1] - rows[0] + 1) * PITCH < 2.2 * np.sqrt(2 * R * approach) + 2 * PITCH
    # the pressure centroid lies under MuJoCo's contact points' centre
    # (skin x = world x, skin y = world -y here; both centred at 0)
    centre = np.mean([data.contact[i].pos for i in range(data.ncon)], axis=0)
    cx = (p.sum(0) * x).sum() / p.sum()
    cy = (p.sum(1) * x).sum() / p.sum()
    assert abs(cx - centre[0]) < PITCH and abs(cy - centre[1]) < PITCH


def test_sideways_capsule_elastic_carries_mujocos_force():
    model, data = pressed(
        CAPSULE_SIDEWAYS, R, facing=(1, 0, 0), pressure="elastic", nx=48, pitch=3e-4
    )
    lay = mjtouch.layouts(model)["skin_tip"]
    force = lay.block(data.sensordata, "force")
    p = lay.block(data.sensordata, "pressure")
    mj = mujoco_normal_n(model, data)
    assert force[0] == pytest.approx(mj, rel=0.05)
    assert p.sum() * 3e-4**2 == pytest.approx(mj, rel=0.05)


def test_box_side_is_flat_and_uniform():
    # a box facing geom +y (turned so +y points down): its 8 x 6 mm side face
    # (x half 4 mm, z half 3 mm) lies flat: Winkler pressure is uniform
    box = dict(type=mujoco.mjtGeom.mjGEOM_BOX, size=[4e-3, 2e-3, 3e-3], euler=[-90, 0, 0])
    model, data = pressed(box, 2e-3, facing=(0, 1, 0), radius=2.5e-3)
    force, p = readout(model, data)
    mj = mujoco_normal_n(model, data)
    inside = np.isfinite(p) & (p > 0)
    # whole cells inside the 8 x 6 mm face: 32 x 24 of 0.25 mm
    assert inside.sum() == 32 * 24
    assert np.ptp(p[inside]) <= 1e-9 * p.max()
    assert p.sum() * PITCH**2 == pytest.approx(mj, rel=0.05)


def test_default_facing_is_todays_frame_bit_for_bit():
    sphere = dict(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[6e-3, 0, 0])
    _, a = pressed(sphere, 6e-3)
    _, b = pressed(sphere, 6e-3, facing=(0, 0, -1))
    _, c = pressed(sphere, 6e-3, facing=(0, 0, -2.5))  # normalised
    assert np.array_equal(a.sensordata, b.sensordata)
    assert np.array_equal(a.sensordata, c.sensordata)


@pytest.mark.parametrize("value", ["0 0 0", "1 0", "1 nan 0", "a b c"])
def test_bad_facing_is_named(value):
    spec = mujoco.MjSpec()
    b = spec.worldbody.add_body(name="finger")
    b.add_geom(name="tip", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[6e-3, 0, 0])
    plugin = mjtouch.attach(spec, "tip", nx=16, pitch=2e-4)
    plugin.config = {**plugin.config, "facing": value}  # (a str in attach() names a site)
    with pytest.raises(ValueError, match="attribute `facing` = .* must be 3 finite numbers"):
        spec.compile()
