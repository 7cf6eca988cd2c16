"""examples/menagerie_hands.py without mujoco_menagerie (not available
offline; the PyPI package `mujoco-menagerie` fetches the models at run
time): its logic on Gymnasium-Robotics' Shadow hand and on synthetic hands
built with trimesh meshes. Each plate pushes PUSH_N into a pad, so once
settled MuJoCo's normal force on the pad is PUSH_N (force balance along the
plate's slide joint), and each skin must report it."""

import importlib.util
import pathlib
import runpy
import types

import mujoco
import numpy as np
import pytest
import trimesh

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"
mh = types.SimpleNamespace(
    **runpy.run_path(str(EXAMPLES / "menagerie_hands.py"), run_name="example")
)

R_TIP, HALF_TIP = 8e-3, 5e-3  # fingertip capsule radius, half length (m)
JOINT = dict(damping=0.05, armature=2e-4)  # as Shadow's finger joints


def synthetic_hand(tmp_path, tip_bodies, mesh_tips: bool) -> mujoco.MjSpec:
    """A palm with one two-link finger per name in tip_bodies; the distal
    body (so named) holds an unnamed fingertip (a trimesh capsule mesh, or
    a capsule geom) and, for meshes, a colliding nail on its back. The
    hinges turn about x, flexion positive: the pads face -y."""
    spec = mujoco.MjSpec()
    spec.option.timestep = 1e-3
    if mesh_tips:
        path = tmp_path / "tip.stl"
        trimesh.creation.capsule(height=2 * HALF_TIP, radius=R_TIP, count=[24, 24]).export(path)
        spec.add_mesh(name="tip", file=str(path))
    palm = spec.worldbody.add_body(name="palm")
    palm.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.06, 0.01, 0.01], pos=[0, 0, -0.02])
    for k, name in enumerate(tip_bodies):
        prox = palm.add_body(name=f"prox_{k}", pos=[0.03 * k - 0.045, 0, 0])
        prox.add_joint(name=f"j{k}_1", axis=[1, 0, 0], range=[-0.2, 1.6], **JOINT)
        prox.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[7e-3, 0.015, 0], pos=[0, 0, 0.02])
        tip = prox.add_body(name=name, pos=[0, 0, 0.045])
        tip.add_joint(name=f"j{k}_2", axis=[1, 0, 0], range=[-0.2, 1.6], **JOINT)
        if mesh_tips:
            tip.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="tip", pos=[0, 0, 0.013])
            tip.add_geom(
                name=f"nail_{k}", type=mujoco.mjtGeom.mjGEOM_BOX, size=[4e-3, 1e-3, 4e-3],
                pos=[0, 8.5e-3, 0.015],
            )  # fmt: skip
        else:
            tip.add_geom(
                type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[R_TIP, HALF_TIP, 0], pos=[0, 0, 0.013]
            )
        for j in (f"j{k}_1", f"j{k}_2"):
            spec.add_actuator(
                name=j, target=j, trntype=mujoco.mjtTrn.mjTRN_JOINT, gainprm=[5] + [0] * 9,
                biasprm=[0, -5, -0.05] + [0] * 7, biastype=mujoco.mjtBias.mjBIAS_AFFINE,
                ctrlrange=[-0.2, 1.6], ctrllimited=True,
            )  # fmt: skip
    return spec


def assert_each_skin_reports_the_push(rows, n_tips):
    assert len(rows) == n_tips
    for r in rows:
        assert r["mujoco_n"] == pytest.approx(mh.PUSH_N, rel=0.05), r
        assert r["skin_n"] == pytest.approx(r["mujoco_n"], rel=0.05), r
        assert r["coverage"] == pytest.approx(1.0, abs=1e-9), r
        assert r["spikes"] > 0, r


def test_mesh_fingertips_of_a_synthetic_hand(tmp_path):
    names = ["tip_a", "tip_b", "tip_c"]
    rows = mh.press_fingertips(
        synthetic_hand(tmp_path, names, mesh_tips=True), [(n, {"body": n}) for n in names]
    )
    assert_each_skin_reports_the_push(rows, 3)
    # the unnamed mesh, not the nail on the back, is each pad
    assert [r["geom"] for r in rows] == [f"{n}_pad" for n in names]


def test_the_gymnasium_robotics_shadow_hand():
    found = importlib.util.find_spec("gymnasium_robotics")
    xml = pathlib.Path(found.submodule_search_locations[0]) / "envs/assets/hand/reach.xml"
    tips = [(f, {"body": f"robot0:{f}distal"}) for f in ("ff", "mf", "rf", "lf", "th")]
    rows = mh.press_fingertips(mujoco.MjSpec.from_file(str(xml)), tips)
    assert_each_skin_reports_the_push(rows, 5)


def allegro_folder(tmp_path):
    """A menagerie folder whose wonik_allegro/right_hand.xml is a synthetic
    hand with the table's tip bodies; returns the folder and the tips."""
    xml_name, tips = mh.HANDS["wonik_allegro"]
    spec = synthetic_hand(tmp_path, [where["body"] for _, where in tips], mesh_tips=False)
    folder = tmp_path / "menagerie" / "wonik_allegro"
    folder.mkdir(parents=True)
    (folder / xml_name).write_text(spec.to_xml())
    return tmp_path / "menagerie", tips


def test_main_reads_a_menagerie_folder(tmp_path, capsys):
    menagerie, tips = allegro_folder(tmp_path)
    mh.main([str(menagerie), "--hands", "wonik_allegro", "--steps", "300"])
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("wonik_allegro:")
    table = [line.split() for line in lines[2:]]
    assert [row[0] for row in table] == [label for label, _ in tips]
    mj, skin, cov = (np.array([float(row[k]) for row in table]) for k in (2, 3, 4))
    np.testing.assert_allclose(mj, mh.PUSH_N, rtol=0.05)
    np.testing.assert_allclose(skin, mj, rtol=0.05)
    np.testing.assert_array_equal(cov, 1.0)
    with pytest.raises(SystemExit, match="is not a file: give the mujoco_menagerie folder"):
        mh.main([str(tmp_path), "--hands", "leap_hand"])


def test_flexion_facing_is_the_side_flexion_moves(tmp_path):
    from mjtouch.scene.robot import flexion_facing

    spec = synthetic_hand(tmp_path, ["tip"], mesh_tips=True)
    model = spec.compile()
    g = model.body("tip").geomadr[0]  # the fingertip mesh
    assert model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH
    # hinge about +x at the tip's base: the centre 13 mm up moves to -y
    np.testing.assert_allclose(flexion_facing(model, g), [0, -1, 0], atol=1e-9)
    # a joint whose range reaches farther negative flexes negative
    spec.joint("j0_2").range = [-1.6, 0.2]
    np.testing.assert_allclose(flexion_facing(spec.compile(), g), [0, 1, 0], atol=1e-9)


def test_a_start_outside_a_joint_range_is_clipped_into_it(tmp_path):
    # the Allegro's thumb base starts (qpos0 0) outside its range; its servo
    # must not swing the tip away from the plate placed on it
    def hand():
        spec = synthetic_hand(tmp_path, ["tip"], mesh_tips=False)
        spec.compiler.degree = False
        spec.joint("j0_1").range = [0.3, 1.6]
        return spec

    model, data, labels = mh.pressed_hand(hand(), [("t", {"body": "tip"})], skin=None)
    assert labels == ["t"]
    assert model.qpos0[model.joint("j0_1").qposadr[0]] == 0
    assert data.qpos[model.joint("j0_1").qposadr[0]] == 0.3
    assert data.ctrl[model.actuator("j0_1").id] == 0.3
    spec = hand()
    assert_each_skin_reports_the_push(mh.press_fingertips(spec, [("t", {"body": "tip"})]), 1)


def test_time_prints_bare_and_skinned_cost_per_step(tmp_path, capsys):
    menagerie, tips = allegro_folder(tmp_path)
    args = ["--hands", "wonik_allegro", "--steps", "20", "--time", "--repeats", "2"]
    mh.main([str(menagerie), *args])
    lines = capsys.readouterr().out.splitlines()
    head = next(k for k, line in enumerate(lines) if "tips pressed, timestep" in line)
    assert lines[head].startswith(f"wonik_allegro: {len(tips)} tips pressed, timestep 1 ms")
    rows = {line.split()[0]: line.split() for line in lines[head + 1 :]}
    assert set(rows) == {"bare", "rl"}
    bare_min, bare_med = float(rows["bare"][1]), float(rows["bare"][2])
    rl_min, rl_med = float(rows["rl"][2]), float(rows["rl"][3])
    assert 0 < bare_min <= bare_med and 0 < rl_min <= rl_med
    assert rows["bare"][-2:] == ["1.00", "1.00"]
    # the printed times are rounded to 0.1 us: their ratio to ~1% of ~5 us
    assert float(rows["rl"][-2]) == pytest.approx(rl_min / bare_min, rel=0.02)
    with pytest.raises(SystemExit):
        mh.main([str(menagerie), "--repeats", "0"])
