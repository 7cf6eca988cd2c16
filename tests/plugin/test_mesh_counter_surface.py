"""Mesh counter-surfaces (mj_rayMesh) are rendered anti-aliased, 4 x 4 rays
per taxel cell (surface/mesh_surface.cc), and press the skin like the
analytic geom they tessellate (issue 16)."""

import mujoco
import numpy as np
import pytest
import trimesh
from conftest import fast_tip

import mjtouch  # noqa: F401
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

R_PAD = 8e-3  # a sphere pad
DEPTH = 0.3e-3  # its overlap with the target's top
CAPSULE_QUAT = [np.sqrt(0.5), 0, np.sqrt(0.5), 0]  # the capsule's axis along x


def targets():
    """(name, analytic geom kwargs, trimesh of the same body, top z, pad x)."""
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=5e-3)
    capsule = trimesh.creation.capsule(height=8e-3, radius=3e-3, count=[96, 96])
    box = trimesh.creation.box([6e-3, 6e-3, 4e-3])
    return [
        ("sphere", dict(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[5e-3, 0, 0]), sphere, 5e-3, 0.0),
        (
            "capsule",
            dict(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[3e-3, 4e-3, 0], quat=CAPSULE_QUAT),
            capsule,
            3e-3,
            0.0,
        ),
        # the box's edge x = 3 mm runs through the contact patch
        ("box", dict(type=mujoco.mjtGeom.mjGEOM_BOX, size=[3e-3, 3e-3, 2e-3]), box, 2e-3, 2.6e-3),
    ]


def press(geom_kwargs, mesh, top_z, pad_x):
    spec = mujoco.MjSpec()
    spec.option.gravity = [0, 0, 0]
    if mesh is not None:
        spec.add_mesh(
            name="target",
            uservert=np.asarray(mesh.vertices).ravel().tolist(),
            userface=np.asarray(mesh.faces).ravel().tolist(),
        )
        extra = {"quat": geom_kwargs["quat"]} if "quat" in geom_kwargs else {}
        spec.worldbody.add_geom(
            name="target", type=mujoco.mjtGeom.mjGEOM_MESH, meshname="target", **extra
        )
    else:
        spec.worldbody.add_geom(name="target", **geom_kwargs)
    finger = spec.worldbody.add_body(name="finger", pos=[pad_x, 0.0015, top_z + R_PAD - DEPTH])
    finger.add_joint(name="z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    finger.add_geom(name="pad", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[R_PAD, 0, 0], mass=0.01)
    cfg = scenes.skin_config(fast_tip(ridges=False))
    cfg.update(outputs="force pressure", pressure="winkler")
    scenes.add_skin_sensor(spec, "pad", cfg)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    layout = SkinLayout.from_model(model)
    p = layout.block(data.sensordata, "pressure").reshape(layout.nx, layout.nx)
    return p, layout.block(data.sensordata, "force")


@pytest.mark.parametrize("name,geom,mesh,top,x", targets(), ids=[t[0] for t in targets()])
def test_mesh_presses_like_the_analytic_geom(name, geom, mesh, top, x):
    p_ana, f_ana = press(geom, None, top, x)
    p_mesh, f_mesh = press(geom, mesh, top, x)
    assert f_ana[0] > 0 and f_mesh[0] > 0
    # Pressure per unit force: the rendering alone (MuJoCo collides meshes
    # by their convex hull, so the total force differs slightly too).
    a, m = p_ana / p_ana.sum(), p_mesh / p_mesh.sum()
    l1 = np.abs(m - a).sum() / np.abs(a).sum()
    # Tessellation: the sphere's facets (edge ~0.17 mm on r = 5 mm) sag
    # < 1 um and the capsule's (96 segments on r = 3 mm) < 0.5 um below
    # the analytic surface, < 0.4 % of the 0.3 mm overlap; a rim cell is
    # covered in 1/16 steps by the rays, in 1/4 steps by the analytic
    # bodies' 2 x 2 Gauss points or exactly on a box face: on the curved
    # bodies the rim carries ~nothing (the overlap vanishes there), on the
    # box's edge (cut through the patch) the rim cells carry ~10 % of the
    # load, their coverage off by up to 1/32 in the mean.
    assert l1 < {"sphere": 0.01, "capsule": 0.01, "box": 0.03}[name], (name, l1)
    # the solved approaches agree to the tessellation's sag plus the rim
    assert f_mesh[3] == pytest.approx(f_ana[3], rel=0.02, abs=5e-6)


def test_a_mesh_edge_sliding_under_a_cell_moves_the_load_smoothly():
    # The box's edge crosses the contact patch; shifting the pad across one
    # taxel cell (0.15 mm) in 9 steps moves the pressure centroid linearly
    # for the exact analytic face (measured 0.7 um off a line). One ray per
    # cell (the earlier mj_rayMesh path) switches whole rim cells on and
    # off: 46 um off; 4 x 4 rays switch sixteenths: 10 um. Bound: a tenth
    # of the cell.
    name, geom, mesh, top, x0 = targets()[2]
    pitch = fast_tip().pitch_m
    shifts = np.linspace(0.0, pitch, 9)
    for m in (None, mesh):
        cx = []
        for s in shifts:
            p, _ = press(geom, m, top, x0 + s)
            xs = (np.arange(p.shape[1]) - (p.shape[1] - 1) / 2) * pitch
            cx.append((p.sum(0) * xs).sum() / p.sum())
        fit = np.polyval(np.polyfit(shifts, cx, 1), shifts)
        assert np.abs(np.array(cx) - fit).max() < 0.1 * pitch


def test_mesh_rendering_is_deterministic_across_rollout_threads_copy_and_reset():
    import mujoco.rollout

    name, geom, mesh, top, x = targets()[2]  # the box, its edge under the patch
    spec = mujoco.MjSpec()
    spec.option.gravity = [0, 0, 0]
    spec.option.timestep = 1e-4  # one tactile evaluation per step (no oversampling)
    spec.add_mesh(
        name="target",
        uservert=np.asarray(mesh.vertices).ravel().tolist(),
        userface=np.asarray(mesh.faces).ravel().tolist(),
    )
    spec.worldbody.add_geom(name="target", type=mujoco.mjtGeom.mjGEOM_MESH, meshname="target")
    finger = spec.worldbody.add_body(name="finger", pos=[x, 0.0015, top + R_PAD - DEPTH])
    finger.add_joint(name="x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    finger.add_geom(name="pad", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[R_PAD, 0, 0], mass=0.01)
    model_cfg = scenes.skin_config(fast_tip())
    model_cfg.update(outputs="spikes stress force pressure")
    scenes.add_skin_sensor(spec, "pad", model_cfg)
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qvel[0] = 0.5  # the edge sweeps across cells: 5 um a step
    n = 40
    st = mujoco.mjtState.mjSTATE_FULLPHYSICS
    s0 = np.empty(mujoco.mj_stateSize(model, st))
    mujoco.mj_getState(model, data, s0, st)
    datas = [mujoco.MjData(model) for _ in range(2)]
    _, sd = mujoco.rollout.rollout(model, datas, np.stack([s0] * 2), np.zeros((2, n, 0)))
    assert np.array_equal(sd[0], sd[1])
    rows = []
    for k in range(n):
        mujoco.mj_step(model, data)
        rows.append(data.sensordata.copy())
        if k == n // 2:
            twin = mujoco.MjData(model)
            mujoco.mj_copyData(twin, model, data)
    assert np.array_equal(np.array(rows), sd[0])
    for _ in range(n - n // 2 - 1):
        mujoco.mj_step(model, twin)
    assert np.array_equal(twin.sensordata, rows[-1])
    assert np.abs(rows[-1]).sum() > 0
