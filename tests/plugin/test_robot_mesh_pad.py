"""Mesh fingertips: a skin on a pad geom of type mesh. The pad's surface over
the patch is the mesh's convex hull (what MuJoCo collides), cast along the
skin's z per Gauss point at build time; `facing` is in the geom's frame as
written (the mesh file's axes), not MuJoCo's principal-axes frame.

Oracles: the same shape given as a primitive geom. A triangulated surface
lies inside the true one by at most its chord height (~ e^2 / (8 R) for
edges of length e); under Winkler contact (p = k * overlap) with the same
total force, the two pressure fields then differ by at most k times twice
that depth (once in the local gap, once in the solved approach)."""

import mujoco
import mujoco.rollout
import numpy as np
import pytest
import trimesh
from test_robot_facing import HALF, MASS, PITCH, STIFFNESS, N, R, mujoco_normal_n

import mjtouch
from mjtouch.scene.sensor import OffPatchWarning

OFF_PATCH = "lands off the skin's patch"
SIDEWAYS = [0, 90, 0]  # euler, degrees: geom z along world x; world down = geom +x


def pressed(tip, rest_z, mesh_file=None, site_euler=None, **skin):
    """A finger on a slide joint resting on a plate under gravity (settled);
    `tip`: the pad geom's attributes; `mesh_file` is loaded as mesh "tip"."""
    model = build(tip, rest_z, mesh_file, site_euler, **skin)
    data = mujoco.MjData(model)
    for _ in range(400):
        mujoco.mj_step(model, data)
    return model, data


def build(tip, rest_z, mesh_file=None, site_euler=None, **skin) -> mujoco.MjModel:
    spec = mujoco.MjSpec()
    spec.option.timestep = 1e-3
    if mesh_file is not None:
        spec.add_mesh(name="tip", file=str(mesh_file))
    spec.worldbody.add_geom(
        name="plate", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.03, 0.03, 0.002], pos=[0, 0, -0.002]
    )
    body = spec.worldbody.add_body(name="finger", pos=[0, 0, rest_z])
    body.add_joint(name="z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    body.add_geom(name="tip", mass=MASS, **tip)
    if site_euler is not None:
        body.add_site(name="pad_frame", euler=site_euler)
    attrs = dict(
        nx=N,
        pitch=PITCH,
        pressure="winkler",
        outputs="force pressure coverage",
        ridges=False,
        radius=4e-3,
    )
    attrs.update(skin)
    mjtouch.attach(spec, "tip", **attrs)
    return spec.compile()


def readout(model, data):
    lay = mjtouch.layouts(model)["skin_tip"]
    force = lay.block(data.sensordata, "force")
    p = lay.block(data.sensordata, "pressure").reshape(N, N)
    return lay, force, p


def mesh_tip(mesh: trimesh.Trimesh, path, **kw) -> dict:
    mesh.export(path)
    return dict(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="tip", **kw)


def chord_depth(mesh: trimesh.Trimesh, distance_inside) -> float:
    """The triangles' deepest point inside the true surface (m), sampled on
    a barycentric grid of each face; distance_inside(points) is the true
    body's radius minus the distance to its core (sphere centre, capsule
    axis)."""
    w = np.array([(a, b, 8 - a - b) for a in range(9) for b in range(9 - a)]) / 8.0
    tri = mesh.vertices[mesh.faces]  # (F, 3, 3)
    points = np.einsum("sk,fkc->fsc", w, tri).reshape(-1, 3)
    return float(distance_inside(points).max())


def assert_force_and_field_agree(mesh_run, primitive_run, depth_m):
    (m1, d1), (m2, d2) = mesh_run, primitive_run
    _, f1, p1 = readout(m1, d1)
    _, f2, p2 = readout(m2, d2)
    for (m, d), f in ((mesh_run, f1), (primitive_run, f2)):
        mj = mujoco_normal_n(m, d)
        assert mj == pytest.approx(MASS * 9.81, rel=0.01)  # settled
        assert f[0] == pytest.approx(mj, rel=0.05)
    # each field carries its own force: a force difference scales the field
    bound = 2 * STIFFNESS * depth_m + p2.max() * abs(f1[0] - f2[0]) / f2[0]
    err = np.abs(p1 - p2).max()
    assert err <= bound, f"max |p_mesh - p_primitive| = {err} Pa > {bound} Pa"
    assert bound < 0.05 * p2.max()  # the check has teeth: a 5% field error fails it
    assert p2.max() > 0 and (p1 > 0).sum() > 50


@pytest.mark.parametrize("subdivisions", [3, 4])
def test_icosphere_mesh_is_the_sphere(subdivisions, tmp_path):
    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=R)
    depth = chord_depth(ico, lambda x: R - np.linalg.norm(x, axis=1))
    assert depth > 0
    mesh = pressed(mesh_tip(ico, tmp_path / "ico.stl"), R, mesh_file=tmp_path / "ico.stl")
    sphere = pressed(dict(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[R, 0, 0]), R)
    assert_force_and_field_agree(mesh, sphere, depth)


def capsule_depth(capsule: trimesh.Trimesh) -> float:
    def inside(x):
        z = np.clip(x[:, 2], -HALF, HALF)
        return R - np.linalg.norm(x - np.c_[0 * z, 0 * z, z], axis=1)

    return chord_depth(capsule, inside)


def test_sideways_mesh_capsule_is_the_capsule(tmp_path):
    capsule = trimesh.creation.capsule(height=2 * HALF, radius=R, count=[48, 48])
    tip = mesh_tip(capsule, tmp_path / "capsule.stl", euler=SIDEWAYS)
    mesh = pressed(tip, R, mesh_file=tmp_path / "capsule.stl", facing=(1, 0, 0))
    prim = dict(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[R, HALF, 0], euler=SIDEWAYS)
    capsule_run = pressed(prim, R, facing=(1, 0, 0))
    assert_force_and_field_agree(mesh, capsule_run, capsule_depth(capsule))
    for model, data in (mesh, capsule_run):
        lay, _, _ = readout(model, data)
        assert lay.block(data.sensordata, "coverage")[0] == 1.0


def test_elastic_contact_mesh_and_capsule_report_mujocos_force(tmp_path):
    # elastic contact (the default): a faceted surface's kinks spike the
    # pressure locally, so the fields are compared through their integrals:
    # the force, and the pressure centroid across the capsule (skin y)
    capsule = trimesh.creation.capsule(height=2 * HALF, radius=R, count=[48, 48])
    tip = mesh_tip(capsule, tmp_path / "capsule.stl", euler=SIDEWAYS)
    skin = dict(facing=(1, 0, 0), pressure="elastic")
    runs = [
        pressed(tip, R, mesh_file=tmp_path / "capsule.stl", **skin),
        pressed(dict(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[R, HALF, 0], euler=SIDEWAYS), R, **skin),
    ]  # fmt: skip
    y = (np.arange(N) - (N - 1) / 2) * PITCH
    for model, data in runs:
        _, force, p = readout(model, data)
        assert force[0] == pytest.approx(mujoco_normal_n(model, data), rel=0.05)
        assert p.sum() * PITCH**2 == pytest.approx(force[0], rel=0.05)
        assert abs((p.sum(axis=1) * y).sum() / p.sum()) < PITCH  # centred on the cylinder


def test_mesh_contact_off_the_patch_is_reported(tmp_path, capfd):
    # the skin on the mesh capsule's -z end cap, the capsule lying on its
    # side: MuJoCo's contact is on the cylinder, off the patch
    capsule = trimesh.creation.capsule(height=2 * HALF, radius=R, count=[24, 24])
    tip = mesh_tip(capsule, tmp_path / "capsule.stl", euler=SIDEWAYS)
    model, data = pressed(tip, R, mesh_file=tmp_path / "capsule.stl")
    lay, force, _ = readout(model, data)
    cov = lay.block(data.sensordata, "coverage")
    mj = mujoco_normal_n(model, data)
    assert mj > 0.4
    assert cov[0] < 1.0 and cov[1] == pytest.approx(mj, rel=1e-12)
    err = capfd.readouterr().err
    assert err.count(OFF_PATCH) == 1 and "pad geom 'tip'" in err
    with pytest.warns(OffPatchWarning, match="of MuJoCo's"):
        lay.coverage(data.sensordata)


def test_a_mesh_turned_off_its_principal_axes_faces_as_written(tmp_path):
    # an ellipsoid mesh with semi-axes (R, 2R, 1.5R) along the file's x, y,
    # z: MuJoCo turns its compiled frame to the principal axes (mesh_quat),
    # yet facing (0, 0, -1) is still the file's -z pole, the primitive's
    axes = np.array([R, 2 * R, 1.5 * R])
    ell = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    ell.apply_scale(axes)
    tip = mesh_tip(ell, tmp_path / "ell.stl")
    mesh = pressed(tip, axes[2], mesh_file=tmp_path / "ell.stl", facing=(0, 0, -1))
    assert not np.allclose(mesh[0].mesh_quat[0], [1, 0, 0, 0])
    prim = dict(type=mujoco.mjtGeom.mjGEOM_ELLIPSOID, size=axes)
    ellipsoid = pressed(prim, axes[2])

    def inside(x):  # radial depth below the ellipsoid (>= the normal depth)
        r = np.linalg.norm(x, axis=1)
        return r * (1 / np.linalg.norm(x / axes, axis=1) - 1)

    assert_force_and_field_agree(mesh, ellipsoid, chord_depth(ell, inside))
    # a site with the body's axes names the same side: its -z
    by_site = pressed(
        tip, axes[2], mesh_file=tmp_path / "ell.stl", site_euler=[0, 0, 0], facing="pad_frame"
    )
    np.testing.assert_array_equal(mesh[1].sensordata, by_site[1].sensordata)


def compile_error(tip, mesh_file, **skin) -> str:
    with pytest.raises(ValueError) as info:
        pressed(tip, R, mesh_file=mesh_file, **skin)
    return str(info.value)


def test_an_open_mesh_is_read_as_its_hull(tmp_path):
    # the lower part of an icosphere, open at the top: MuJoCo collides its
    # hull (the cap closed by a flat disc), and the skin's -z side of it is
    # the sphere's, as for the closed mesh
    ico = trimesh.creation.icosphere(subdivisions=3, radius=R)
    cup = trimesh.Trimesh(ico.vertices, ico.faces[ico.triangles_center[:, 2] < 0.6 * R])
    assert not cup.is_watertight
    closed = pressed(mesh_tip(ico, tmp_path / "ico.stl"), R, mesh_file=tmp_path / "ico.stl")
    opened = pressed(mesh_tip(cup, tmp_path / "cup.stl"), R, mesh_file=tmp_path / "cup.stl")
    _, f1, p1 = readout(*closed)
    _, f2, p2 = readout(*opened)
    assert f2[0] == pytest.approx(mujoco_normal_n(*opened), rel=0.05)
    # the same triangles under the patch, stored in float32 after MuJoCo
    # moves them to each mesh's own centre of mass: ~1e-7 R apart
    bound = STIFFNESS * 2 * 1e-7 * R + p1.max() * abs(f1[0] - f2[0]) / f1[0]
    assert np.abs(p1 - p2).max() <= bound + 1e-6 * p1.max()


def test_a_mesh_pad_that_cannot_collide_is_refused_naming_the_geom(tmp_path):
    # no contact, no hull (MuJoCo builds one only for colliding meshes)
    ico = trimesh.creation.icosphere(subdivisions=2, radius=R)
    tip = mesh_tip(ico, tmp_path / "ico.stl", contype=0, conaffinity=0)
    msg = compile_error(tip, tmp_path / "ico.stl")
    assert "pad geom 'tip' (mesh 'tip') has no convex hull" in msg


def test_a_patch_wider_than_the_mesh_is_refused_naming_the_geom(tmp_path):
    # receptors out to 6 mm on a 5 mm sphere: not under the mesh
    ico = trimesh.creation.icosphere(subdivisions=2, radius=R)
    msg = compile_error(mesh_tip(ico, tmp_path / "ico.stl"), tmp_path / "ico.stl", radius=6e-3)
    assert "attribute `radius` = 0.006 m" in msg and "pad geom 'tip', a mesh" in msg
    # the inscribed radius of the icosphere's outline: at most R, at least
    # the inscribed radius of its coarsest face ring
    footprint = float(msg.split("radius ")[-1].split(" m)")[0])
    assert 0.95 * R < footprint <= R


def test_mesh_pads_are_deterministic_in_threaded_rollouts(tmp_path):
    ico = trimesh.creation.icosphere(subdivisions=3, radius=R)
    model = build(mesh_tip(ico, tmp_path / "ico.stl"), R, mesh_file=tmp_path / "ico.stl")
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    s0 = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, mujoco.MjData(model), s0, spec)
    s0 = np.repeat(s0[None], 3, axis=0)
    s0[:, 1] += [0.0, 2e-4, 5e-4]  # qpos of the slide: dropped from three heights
    _, one = mujoco.rollout.rollout(model, mujoco.MjData(model), s0, nstep=150)
    threads = [mujoco.MjData(model), mujoco.MjData(model)]
    _, two = mujoco.rollout.rollout(model, threads, s0, nstep=150)
    assert np.array_equal(one, two) and one[:, -1].any()
    # a serial run from the same start, copied half way, ends the same
    d = mujoco.MjData(model)
    mujoco.mj_setState(model, d, s0[2], spec)
    for _ in range(75):
        mujoco.mj_step(model, d)
    copy = mujoco.MjData(model)
    mujoco.mj_copyData(copy, model, d)
    d = copy
    for _ in range(75):
        mujoco.mj_step(model, d)
    assert np.array_equal(d.sensordata, one[2, -1])


def test_meshes_with_equal_extents_are_different_pads(tmp_path):
    # a sphere and a cube mesh with the same bounding box: the model cache
    # must key on the mesh, not its extents (a cube's flat face presses
    # evenly: Winkler pressure constant where it touches)
    ico = trimesh.creation.icosphere(subdivisions=3, radius=R)
    cube = trimesh.creation.box(extents=[2 * R, 2 * R, 2 * R])
    sphere_run = pressed(mesh_tip(ico, tmp_path / "ico.stl"), R, mesh_file=tmp_path / "ico.stl")
    cube_run = pressed(mesh_tip(cube, tmp_path / "cube.stl"), R, mesh_file=tmp_path / "cube.stl")
    p_sphere = readout(*sphere_run)[2]
    p_cube = readout(*cube_run)[2]
    pressed_cells = p_cube[p_cube > 0]
    assert pressed_cells.size > 100
    assert pressed_cells.std() < 1e-6 * pressed_cells.mean()
    assert p_sphere[p_sphere > 0].std() > 0.1 * p_sphere.max()
