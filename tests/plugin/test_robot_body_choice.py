"""attach(spec, body=...) on a body with several colliding geoms (a pad and
a nail, say): the geom whose surface reaches farthest along `facing` at the
initial pose is the pad; a tie within 0.1 mm, or a vector `facing` that
names a different side of each geom, is an error listing them."""

import mujoco
import pytest

import mjtouch

R, HALF = 6e-3, 4e-3  # pad capsule radius and half length, m
NAIL = [3e-3, 3e-3, 1e-3]  # nail box half sizes, m


def fingertip(nail_z: float, capsule_euler=(0, 0, 0)) -> mujoco.MjSpec:
    """A distal body with an unnamed pad capsule at its origin and a nail box
    on its +z side at nail_z, both colliding; site "down" faces world -z and
    site "up" world +z."""
    spec = mujoco.MjSpec()
    b = spec.worldbody.add_body(name="distal", pos=[0, 0, 0.05])
    b.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[R, HALF, 0], euler=capsule_euler)
    b.add_geom(name="nail", type=mujoco.mjtGeom.mjGEOM_BOX, size=NAIL, pos=[0, 0, nail_z])
    b.add_site(name="down")  # its -z: world -z
    b.add_site(name="up", euler=[180, 0, 0])  # its -z: world +z
    return spec


def pad_of(spec, **kw) -> str:
    plugin = mjtouch.attach(spec, body="distal", nx=16, pitch=2e-4, radius=1e-3, **kw)
    model = spec.compile()  # the skin compiles on the picked geom
    sensor = model.sensor(plugin.name)
    return model.geom(sensor.objid[0]).name


def test_the_geom_reaching_farthest_along_facing_is_the_pad():
    # capsule along z reaches R + HALF = 10 mm down and up; the nail at
    # 10 mm reaches 11 mm up, -9 mm down
    assert pad_of(fingertip(10e-3), facing=(0, 0, -1)) == "distal_pad"
    assert pad_of(fingertip(10e-3), facing=(0, 0, 1)) == "nail"
    assert pad_of(fingertip(10e-3)) == "distal_pad"  # the default, -z


def test_a_site_chooses_among_geoms_turned_differently():
    # capsule along x: it reaches R = 6 mm up and down; the nail at 6 mm
    # reaches 7 mm up
    turned = dict(capsule_euler=(0, 90, 0))
    assert pad_of(fingertip(6e-3, **turned), facing="down") == "distal_pad"
    assert pad_of(fingertip(6e-3, **turned), facing="up") == "nail"
    with pytest.raises(ValueError, match="turned differently: facing = \\(0, 0, -1\\)"):
        mjtouch.attach(fingertip(6e-3, **turned), body="distal", facing=(0, 0, -1))


def test_a_tie_is_an_error_listing_the_geoms():
    # the nail at 9.05 mm reaches 10.05 mm up, the capsule 10 mm: within 0.1 mm
    with pytest.raises(
        ValueError,
        match=r"body 'distal' has 2 colliding geoms and two reach within 0.0001 m of each "
        r"other along facing \(\(unnamed geom 0 of the body, a mjGEOM_CAPSULE\) "
        r"-5.00e-05 m, 'nail' \+0.00e\+00 m\); valid: pass geom=",
    ):
        mjtouch.attach(fingertip(9.05e-3), body="distal", facing=(0, 0, 1))
