"""Never a silent zero: the `coverage` output carries the share of MuJoCo's
normal force on the pad geom that lands on the skin's patch, and contact off
the patch is warned once (MuJoCo warning text; a Python OffPatchWarning from
SkinLayout.coverage)."""

import mujoco
import numpy as np
import pytest
from test_robot_facing import CAPSULE_SIDEWAYS, STIFFNESS, R, mujoco_normal_n, pressed

import mjtouch
from mjtouch import core
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


# A capsule fingertip pressed on its side by a neighbour: the patch is the
# part of the skin within 45 degrees of its facing (MuJoCo's contact normal
# there, and its point over a covered taxel); a contact beyond it is neither
# felt nor rendered, and `coverage` says so.
R_NEIGHBOUR = 3e-3


def pressed_by_neighbour(angle_deg: float, **skin) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The fingertip capsule (fixed, axis along world x, skin facing world
    down) pressed by a parallel capsule sliding towards its axis from
    `angle_deg` off the skin's facing, pushed by gravity along the slide."""
    a = np.radians(angle_deg)
    u = np.array([0.0, np.sin(a), -np.cos(a)])  # from the tip's axis to the neighbour's
    spec = mujoco.MjSpec()
    spec.option.timestep = 1e-3
    spec.option.gravity = -9.81 * u
    tip = spec.worldbody.add_body(name="finger")
    tip.add_geom(name="tip", mass=MASS_TIP, **CAPSULE_SIDEWAYS)
    rest = (R + R_NEIGHBOUR) * u
    body = spec.worldbody.add_body(name="neighbour", pos=rest)
    body.add_joint(name="slide", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=u)
    body.add_geom(
        name="other",
        type=mujoco.mjtGeom.mjGEOM_CAPSULE,
        size=[R_NEIGHBOUR, 0.8 * R, 0],
        euler=[0, 90, 0],
        mass=MASS_TIP,
        solref=[0.05, 1],  # soft: the neighbour sinks ~0.5 mm into the tip
    )
    attrs = dict(
        nx=64, pitch=2.5e-4, pressure="winkler", ridges=False, radius=4e-3, facing=(1, 0, 0)
    )
    attrs.update(skin)
    mjtouch.attach(spec, "tip", **attrs)
    model = spec.compile()
    data = mujoco.MjData(model)
    for _ in range(300):
        mujoco.mj_step(model, data)
    return model, data


MASS_TIP = 0.05


def force_on_tip_world(model, data) -> np.ndarray:
    """MuJoCo's contact force on the tip geom (world frame, N)."""
    g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "tip")
    total = np.zeros(3)
    for i in range(data.ncon):
        c = data.contact[i]
        if g in c.geom:
            f = np.zeros(6)
            mujoco.mj_contactForce(model, data, i, f)
            world = c.frame.reshape(3, 3).T @ f[:3]  # on geom[1]
            total += world if c.geom[1] == g else -world
    return total


def test_capsule_pressed_on_its_side_is_off_the_patch(capfd):
    # 65 degrees off the facing: MuJoCo's contact point lies over the skin's
    # grid (R sin 65 = 4.5 mm of the 5 mm the capsule's cylinder spans
    # across it), but it pushes the tip more sideways than into the skin
    model, data = pressed_by_neighbour(65.0, outputs="spikes force pressure coverage")
    lay = mjtouch.layouts(model)["skin_tip"]
    force = lay.block(data.sensordata, "force")
    cov = lay.block(data.sensordata, "coverage")
    mj = mujoco_normal_n(model, data)
    assert mj == pytest.approx(MASS_TIP * 9.81, rel=1e-3)  # settled: the neighbour's weight
    # the contact's point is over a covered cell: only its normal puts it off
    c = data.contact[0]
    assert abs(c.pos[1]) < R and abs(c.pos[0]) < 64 * 2.5e-4 / 2
    assert np.degrees(np.arccos(abs(c.frame[2]))) == pytest.approx(65.0, abs=0.5)
    assert cov[0] == 0.0 and cov[1] == pytest.approx(mj, rel=1e-12)
    np.testing.assert_array_equal(force, 0.0)  # no load: no force, no indentation
    np.testing.assert_array_equal(lay.block(data.sensordata, "pressure"), 0.0)
    assert OFF_PATCH in capfd.readouterr().err
    with pytest.warns(OffPatchWarning, match="carries 0 of MuJoCo's"):
        lay.coverage(data.sensordata)


@pytest.mark.parametrize("angle_deg", [0.0, 30.0])
def test_capsule_pressed_within_the_patch_carries_mujocos_force(angle_deg):
    model, data = pressed_by_neighbour(angle_deg, outputs="force pressure coverage")
    lay = mjtouch.layouts(model)["skin_tip"]
    force = lay.block(data.sensordata, "force")
    cov = lay.block(data.sensordata, "coverage")
    mj = mujoco_normal_n(model, data)
    assert mj == pytest.approx(MASS_TIP * 9.81, rel=1e-3)  # settled: the slide is along the normal
    assert cov[0] == 1.0 and lay.coverage(data.sensordata) == 1.0
    # the skin's force is MuJoCo's on the tip in the skin's frame: its z is
    # world up (facing is world down), its x the capsule's axis (world x)
    f = force_on_tip_world(model, data)
    assert force[0] == pytest.approx(f[2], rel=1e-9)
    assert force[1] == pytest.approx(f[0], abs=1e-9)
    if angle_deg == 0.0:
        assert force[0] == pytest.approx(mj, rel=0.05)  # MuJoCo's normal force
    p = lay.block(data.sensordata, "pressure")
    assert p.sum() * 2.5e-4**2 == pytest.approx(force[0], rel=0.05)
    assert force[4] == 0.0  # within the skin's range
    if angle_deg == 0.0:
        # Winkler on the exact geometry (cell centres): the skin's surface
        # and the neighbour's top along the skin's z (world up), the
        # approach c carrying the force; the skin's indentation is c minus
        # the smallest gap. Cell centres vs the plugin's 2 x 2 cell means:
        # ~pitch^2 / (12 R_neighbour) ~ 2 um in the gap.
        n, h = 64, 2.5e-4
        x = (np.arange(n) - (n - 1) / 2) * h
        X, Y = np.meshgrid(x, x)
        tip = R * R - Y**2 - np.maximum(np.abs(X) - R, 0) ** 2  # tip HALF = R
        zc = data.geom("other").xpos[2]
        other = R_NEIGHBOUR**2 - Y**2 - np.maximum(np.abs(X) - 0.8 * R, 0) ** 2
        ok = (tip > 0) & (other > 0)
        gap = np.where(
            ok, -np.sqrt(np.where(ok, tip, 0)) - zc - np.sqrt(np.where(ok, other, 0)), np.inf
        )
        lo, hi = gap.min(), gap.min() + 1e-2
        for _ in range(100):  # bisection on c
            c = 0.5 * (lo + hi)
            load = STIFFNESS * np.maximum(c - gap, 0).sum() * h * h
            lo, hi = (c, hi) if load < force[0] else (lo, c)
        depth = c - gap.min()
        assert force[3] == pytest.approx(depth, rel=0.05, abs=5e-6)


def test_render_skips_a_body_beside_the_pad_above_its_skin():
    # a sphere pad of radius 5 mm, its skin on 40 x 0.25 mm (to 4.9 mm off
    # the pole, 78 degrees round). A 1 mm ball at the pad's mid-plane,
    # poking out of its side 4.1 mm off the pole (a neighbour pressing the
    # fingertip's side): in every column it reaches it lies wholly above the
    # skin's surface (the skin rises to -1.1 mm at the grid's edge), so it
    # indents no cell. Moved down to straddle the skin's surface, it
    # indents the cells it crosses by its top's height over the skin there.
    n, h, r = 40, 2.5e-4, 1e-3
    z = core.pad_surface("sphere", (R, R, R), n, h)
    x = (np.arange(n) - (n - 1) / 2) * h
    xc = x[-4]
    assert -np.sqrt(R * R - x[-1] ** 2) < -r  # the skin at the edge lies below the ball
    for zc in (0.0, -np.sqrt(R * R - xc * xc)):
        ball = dict(type="sphere", pos=(xc, 0.0, zc), size=(r, 0, 0))
        gap, cov = core.render_gap(z, h, [ball])
        if zc == 0.0:
            assert np.all(np.isinf(gap)) and np.all(cov == 0.0)
            continue
        # cells whose 2 x 2 Gauss points all see the ball: gap is the
        # skin's cell mean z minus the mean of the ball's top there
        g = 0.5 * h / np.sqrt(3.0)
        j = n // 2
        for i in (n - 5, n - 4):
            pts = [(x[i] + a, x[j] + b) for a in (-g, g) for b in (-g, g)]
            q = [r * r - (px - xc) ** 2 - py**2 for px, py in pts]
            assert min(q) > 0 and cov[j, i] == 1.0
            top = np.mean([zc + np.sqrt(v) for v in q])
            assert gap[j, i] < 0.0
            assert gap[j, i] == pytest.approx(z[j, i] - top, rel=1e-12)


def test_contact_along_the_capsule_past_the_grid_is_felt_by_its_share():
    # the sideways capsule (cylinder 10 mm long) lying on the plate: MuJoCo
    # puts its two contacts at the cylinder's ends, 5 mm off the skin's
    # centre, outside a 5 x 5 mm grid, but the plate presses the grid's
    # middle half of the cylinder. The patch carries the share of the
    # plate's overlap with the pad that lies on it: the 5 mm of the 10 mm
    # cylinder against the whole, end caps included (each overlaps the
    # plate by half a spherical cap of height d). The share is rendered on
    # the pad's footprint grid (32 cells over 20 mm: the grid's edges fall
    # on its cells' edges); its sampling of the caps' small overlap moves
    # the share by well under 2%.
    model, data = pressed(
        CAPSULE_SIDEWAYS,
        R,
        facing=(1, 0, 0),
        nx=20,
        pitch=2.5e-4,
        radius=1e-3,
        outputs="force coverage",
    )
    lay, cov = coverage(model, data)
    mj = mujoco_normal_n(model, data)
    assert mj > 0.4 and cov[1] == pytest.approx(mj, rel=1e-12)
    d = R - data.geom("tip").xpos[2]  # overlap depth with the plate (its top at z = 0)
    area = R * R * np.arccos((R - d) / R) - (R - d) * np.sqrt(2 * R * d - d * d)  # segment
    caps = 2 * np.pi * d * d * (3 * R - d) / 6
    share = 5e-3 * area / (10e-3 * area + caps)
    assert cov[0] == pytest.approx(share, rel=0.02)
    force = lay.block(data.sensordata, "force")
    assert force[0] == pytest.approx(cov[0] * mj, rel=1e-9)  # the plate's normal is the skin's z


def test_capsule_on_a_box_edge_renders_the_edge():
    # the sideways capsule resting along the top edge of a box turned 45
    # degrees about x: MuJoCo's contact normal is 45 degrees off both faces,
    # so the skin renders the box as a body (its top along each column),
    # not one face. Winkler on the exact geometry: the gap along the skin's
    # z (world up) from the skin, z_c - sqrt(R^2 - y^2) on the cylinder,
    # down to the edge's ridge, -|y|.
    spec = mujoco.MjSpec()
    spec.option.timestep = 1e-3
    spec.worldbody.add_geom(
        name="wedge",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.03, 0.01, 0.01],
        euler=[45, 0, 0],
        pos=[0, 0, -0.01 * np.sqrt(2)],
    )
    body = spec.worldbody.add_body(name="finger", pos=[0, 0, R])
    body.add_joint(name="z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    body.add_geom(name="tip", mass=0.05, **CAPSULE_SIDEWAYS)
    n, h = 64, 2.5e-4
    mjtouch.attach(
        spec,
        "tip",
        nx=n,
        pitch=h,
        pressure="winkler",
        ridges=False,
        radius=4e-3,
        facing=(1, 0, 0),
        outputs="force pressure coverage",
    )
    model = spec.compile()
    data = mujoco.MjData(model)
    for _ in range(400):
        mujoco.mj_step(model, data)
    lay, cov = coverage(model, data)
    force = lay.block(data.sensordata, "force")
    mj = mujoco_normal_n(model, data)
    assert mj == pytest.approx(0.05 * 9.81, rel=1e-3)
    assert cov[0] == 1.0 and force[0] == pytest.approx(mj, rel=1e-6)
    x = (np.arange(n) - (n - 1) / 2) * h
    X, Y = np.meshgrid(x, x)
    inside = R * R - Y**2 - np.maximum(np.abs(X) - R, 0) ** 2  # tip HALF = R
    zc = data.geom("tip").xpos[2]
    gap = np.where(inside > 0, zc - np.sqrt(np.maximum(inside, 0)) + np.abs(Y), np.inf)
    lo, hi = gap.min(), gap.min() + 1e-2
    for _ in range(100):  # bisection on the approach c
        c = 0.5 * (lo + hi)
        load = STIFFNESS * np.maximum(c - gap, 0).sum() * h * h
        lo, hi = (c, hi) if load < force[0] else (lo, c)
    # cell centres vs the plugin's 2 x 2 cell means: |y| is linear in every
    # cell (the ridge lies on cell edges), the skin's curvature ~1 um
    assert force[3] == pytest.approx(c - gap.min(), rel=0.05)
    p = lay.block(data.sensordata, "pressure").reshape(n, n)
    np.testing.assert_allclose(p, STIFFNESS * np.maximum(c - gap, 0), atol=0.05 * p.max())
