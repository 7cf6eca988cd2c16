"""mjtouch.attach on a user's robot: textures only where the user asks, and
texture names that follow MjSpec.attach's prefix and suffix."""

import mujoco
import numpy as np
import pytest

import mjtouch
from mjtouch.scene import scenes

SMALL = dict(nx=32, pitch=2e-4, pressure="winkler", outputs="force pressure")
PAD_R = 0.01  # m
DEPTH = 1e-4  # m, the pad's overlap with the floor


def bump(spec_body, name: str, group: int = 0):
    """A non-colliding box 50 um proud of the floor, right of the pole (x > 0)."""
    spec_body.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[8e-4, 2e-3, 5e-4],
        pos=[1.2e-3, 0, 5e-5 - 5e-4],
        contype=0,
        conaffinity=0,
        group=group,
    )


def finger(texture: bool = False, visual_group: int | None = None) -> mujoco.MjSpec:
    """A sphere pad pressed DEPTH into a colliding floor; optionally the bump
    `tex`, and a robot's non-colliding visual bump in `visual_group`."""
    spec = mujoco.MjSpec()
    spec.option.gravity = [0, 0, 0]
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.1, 0.1, 0.01])
    if texture:
        bump(spec.worldbody, "tex")
    if visual_group is not None:
        bump(spec.worldbody, "robot_visual", visual_group)
    body = spec.worldbody.add_body(name="finger", pos=[0, 0, PAD_R - DEPTH])
    body.add_joint(name="press", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    body.add_geom(name="pad", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[PAD_R, 0, 0])
    return spec


def finger_with_skin(**kw) -> mujoco.MjSpec:
    spec = finger(texture=True)
    mjtouch.attach(spec, "pad", texture="tex", **SMALL, **kw)
    return spec


def pressure_x_centroid(model: mujoco.MjModel, name: str = "skin_pad") -> float:
    """x of the pressure centroid in the pad frame, m (after one mj_forward)."""
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    lay = mjtouch.layouts(model)[name]
    assert lay.block(data.sensordata, "force")[0] > 0  # MuJoCo reports contact
    p = lay.block(data.sensordata, "pressure").reshape(lay.nx, lay.nx)
    x = (np.arange(lay.nx) - (lay.nx - 1) / 2) * lay.pitch_m
    return float((p.sum(axis=0) * x).sum() / p.sum())


def test_attach_sets_no_texture_group():
    spec = finger(visual_group=scenes.TEXTURE_GROUP)
    plugin = mjtouch.attach(spec, "pad", **SMALL)
    assert "texture_group" not in plugin.config
    # the robot's group-3 visual bump is no texture: the floor's symmetric
    # patch (centroid at the pole, well inside one cell)
    assert abs(pressure_x_centroid(spec.compile())) < 1e-6


def test_texture_group_is_opt_in():
    spec = finger(visual_group=scenes.TEXTURE_GROUP)
    mjtouch.attach(spec, "pad", texture_group=scenes.TEXTURE_GROUP, **SMALL)
    assert pressure_x_centroid(spec.compile()) > 4e-4  # pressure moves onto the bump


def test_texture_names_follow_spec_attach_prefix_and_suffix():
    alone = pressure_x_centroid(finger_with_skin().compile())
    assert alone > 4e-4  # the skin feels `tex`
    for prefix, suffix in (("h_", ""), ("h_", "_r")):
        parent = mujoco.MjSpec()
        parent.option.gravity = [0, 0, 0]
        parent.attach(
            finger_with_skin(), prefix=prefix, suffix=suffix, frame=parent.worldbody.add_frame()
        )
        assert parent.geom(f"{prefix}tex{suffix}") is not None
        model = parent.compile()  # `texture="tex"` resolves to the renamed geom
        assert pressure_x_centroid(model, f"{prefix}skin_pad{suffix}") == alone, (prefix, suffix)
    # nested attaches compose their prefixes
    middle = mujoco.MjSpec()
    middle.attach(finger_with_skin(), prefix="a_", frame=middle.worldbody.add_frame())
    outer = mujoco.MjSpec()
    outer.option.gravity = [0, 0, 0]
    outer.attach(middle, prefix="b_", frame=outer.worldbody.add_frame())
    assert pressure_x_centroid(outer.compile(), "b_a_skin_pad") == alone


def test_wrong_pad_geom_is_named():
    spec = finger(texture=True)
    mjtouch.attach(spec, "pad", texture="tex", pad_geom="thumb", **SMALL)
    with pytest.raises(ValueError, match="`pad_geom` = 'thumb' is not part of the pad geom's"):
        spec.compile()


def hand_with_unnamed_tips() -> mujoco.MjSpec:
    """Two fingers whose colliding tip geoms are unnamed (as in Shadow and
    Allegro MJCF), each with an unnamed non-colliding visual geom."""
    spec = mujoco.MjSpec()
    for k, x in enumerate((-0.02, 0.02)):
        b = spec.worldbody.add_body(name=f"distal{k}", pos=[x, 0, 0.01])
        b.add_geom(
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[3e-3, 3e-3, 3e-3],
            contype=0,
            conaffinity=0,
            group=3,
        )
        b.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[6e-3, 4e-3, 0])
    return spec


def test_body_picks_its_one_colliding_geom_and_names_it():
    spec = hand_with_unnamed_tips()
    plugins = [mjtouch.attach(spec, body=f"distal{k}", nx=16, pitch=2e-4) for k in range(2)]
    assert [p.name for p in plugins] == ["skin_distal0_pad", "skin_distal1_pad"]
    tip = spec.body("distal1").geoms[1]
    assert tip.name == "distal1_pad" and spec.body("distal1").geoms[0].name == ""
    model = spec.compile()
    lays = mjtouch.layouts(model)
    for k in range(2):
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, f"skin_distal{k}_pad")
        assert model.sensor_objid[sid] == model.geom(f"distal{k}_pad").id
        assert lays[f"skin_distal{k}_pad"].nx == 16
    # an MjsGeom works as `geom`, unnamed too
    spec = hand_with_unnamed_tips()
    mjtouch.attach(spec, spec.body("distal0").geoms[1], nx=16, pitch=2e-4)
    assert spec.body("distal0").geoms[1].name == "distal0_pad"


def test_body_errors_name_the_body():
    spec = hand_with_unnamed_tips()
    spec.body("distal1").geoms[1].contype = 0
    spec.body("distal1").geoms[1].conaffinity = 0
    with pytest.raises(ValueError, match="body 'distal1' has no colliding geom"):
        mjtouch.attach(spec, body="distal1")
    with pytest.raises(ValueError, match="body = 'palm' is not in the spec"):
        mjtouch.attach(spec, body="palm")
    with pytest.raises(ValueError, match="give exactly one"):
        mjtouch.attach(spec, "x", body="distal0")


def test_facing_from_a_site_is_its_minus_z_in_the_geom_frame():
    spec = hand_with_unnamed_tips()
    body = spec.body("distal0")
    body.geoms[1].quat = [np.sqrt(0.5), 0, np.sqrt(0.5), 0]  # geom z along body x
    # a site whose -z points along body -z (world down), i.e. geom +x
    body.add_site(name="pad_site", pos=[0, 0, -6e-3])
    plugin = mjtouch.attach(spec, body="distal0", facing="pad_site", nx=16, pitch=2e-4)
    f = np.array(plugin.config["facing"].split(), float)
    np.testing.assert_allclose(f, [1, 0, 0], atol=1e-9)
    spec.compile()
    with pytest.raises(ValueError, match="facing = 'nope' is not a site"):
        mjtouch.attach(spec, body="distal1", facing="nope")
