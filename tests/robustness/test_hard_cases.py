"""Hard cases stay numerically stable (issue: hard cases).

Every rollout checks the same invariants (`check`), each a law the pipeline
must obey whatever the scene:
- every output is finite;
- no MuJoCo warning;
- spikes per step <= dt / refractory + 1 (a refractory period bounds firing);
- force balance: the plugin's normal force equals MuJoCo's total contact
  normal force on the pad (computed here independently with
  mj_contactForce) to 1e-9 relative, and sum(p * A) equals it to 1e-9 (the
  pressure output is double precision, normalised to the load);
- stress is bounded: every receptor quantity <= 10 x the peak taxel
  pressure. For a half-space s_zz under any p >= 0 is bounded by max p (its
  kernel is positive and integrates to 1); 10x leaves room for the other
  measures and layered skins while catching any blow-up near the surface.
Where a case has a law of its own it is checked too (each test says which):
a closed form (Love's rectangle under a sharp edge), an exact identity (a
layer split in two; a layer over its own material), a limit (a thin film's
effect linear in its thickness; a far rigid base felt as F / H^2), or a
continuity condition (s_zz across an interface).
"""

import dataclasses

import mujoco
import numpy as np
import pytest
from conftest import assert_no_warnings

from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

REFRACTORY_S = 1e-3


def fast_tip(**kw):
    kw.setdefault("nx", 48)
    kw.setdefault("pitch_m", 1.5e-4)
    kw.setdefault("skin", {"outputs": "spikes stress force pressure"})
    return scenes.Fingertip(**kw)


@dataclasses.dataclass
class Run:
    spikes: np.ndarray
    stress: np.ndarray
    force: np.ndarray
    pressure_sum: np.ndarray
    pressure_max: np.ndarray
    contact_steps: int
    layout: SkinLayout | None = None
    # the final state, recomputed by mj_forward: taxel pressure image [j, i]
    # (Pa), receptor quantities, and the pad's world position
    final_pressure: np.ndarray | None = None
    final_stress: np.ndarray | None = None
    pad_pos: np.ndarray | None = None


def pad_normal_force(m, d, pad, pad_z):
    """MuJoCo's total contact force on the pad along the pad's z axis."""
    total = np.zeros(3)
    f6 = np.zeros(6)
    for i in range(d.ncon):
        c = d.contact[i]
        if pad not in (c.geom[0], c.geom[1]) or c.efc_address < 0:
            continue
        mujoco.mj_contactForce(m, d, i, f6)
        fw = c.frame.reshape(3, 3).T @ f6[:3]
        total += fw if c.geom[1] == pad else -fw
    return total @ pad_z


def simulate(m, ctrl_fn, steps, setup=None) -> Run:
    d = mujoco.MjData(m)
    if setup:
        setup(m, d)
    layout = SkinLayout.from_model(m)
    pad = m.geom("pad").id
    area = layout.pitch_m**2
    out = {k: [] for k in ("spikes", "stress", "force", "psum", "pmax")}
    contact_steps = 0
    for k in range(steps):
        ctrl_fn(d, k)
        mujoco.mj_step(m, d)
        sd = d.sensordata
        p = layout.block(sd, "pressure")
        out["spikes"].append(layout.block(sd, "spikes").copy())
        out["stress"].append(layout.block(sd, "stress").copy())
        out["force"].append(layout.block(sd, "force").copy())
        out["psum"].append(p.sum() * area)
        out["pmax"].append(p.max())
        contact_steps += bool(d.ncon)
    assert_no_warnings(d)
    # Force balance at the final state, evaluated consistently: mj_forward
    # recomputes contacts, forces and the plugin's output at the same time.
    mujoco.mj_forward(m, d)
    n = layout.nx
    r = Run(
        np.array(out["spikes"]),
        np.array(out["stress"]),
        np.array(out["force"]),
        np.array(out["psum"]),
        np.array(out["pmax"]),
        contact_steps,
        layout,
        layout.block(d.sensordata, "pressure").reshape(n, n).copy(),
        layout.block(d.sensordata, "stress").copy(),
        d.geom_xpos[pad].copy(),
    )
    f = layout.block(d.sensordata, "force")
    pad_z = d.geom_xmat[pad].reshape(3, 3)[:, 2]
    fn = pad_normal_force(m, d, pad, pad_z)
    if fn > 0:
        assert abs(f[0] - fn) <= 1e-9 * abs(fn), (f[0], fn)
        psum = layout.block(d.sensordata, "pressure").sum() * area
        assert abs(psum - fn) <= 1e-9 * fn, (psum, fn)
    return r


def check(run: Run, dt: float) -> None:
    for name in ("spikes", "stress", "force", "pressure_sum", "pressure_max"):
        assert np.all(np.isfinite(getattr(run, name))), name
    assert run.spikes.min() >= 0
    assert run.spikes.max() <= dt / REFRACTORY_S + 1
    # sum(p A) equals the plugin's normal force whenever it reports contact
    fn = run.force[:, 0]
    touching = fn > 0
    assert np.all(np.abs(run.pressure_sum[touching] - fn[touching]) <= 1e-9 * fn[touching] + 1e-12)
    assert np.all(run.pressure_sum[~touching] == 0)
    bound = 10 * run.pressure_max[:, None] + 1e-9
    assert np.all(np.abs(run.stress) <= bound)


def press_slide(force=0.5, speed=0.025, t_press=0.05):
    def ctrl(d, k):
        d.ctrl[:] = [speed if d.time > t_press else 0.0, -force]

    return ctrl


def model(tip=None, texture=None, protocol=None, edit=None):
    """The sliding scene; ``edit(spec)`` changes its MjSpec before compiling."""
    spec = scenes.scene_spec(
        tip or fast_tip(),
        texture or scenes.Texture(period_m=0.6e-3),
        protocol or scenes.Protocol(timestep_s=2e-4),
    )
    if edit:
        edit(spec)
    return spec.compile()


def box(spec, name, half_m, pos_m, **kw):
    spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=half_m, pos=pos_m, **kw)


@pytest.mark.parametrize("solref", ["0.002 1", "0.05 1"], ids=["stiff", "soft"])
def test_very_stiff_and_very_soft_contact(solref):
    def edit(spec):
        spec.pairs[0].solref = [float(v) for v in solref.split()]

    m = model(edit=edit)
    assert list(m.pair_solref[0]) == [float(v) for v in solref.split()]
    r = simulate(m, press_slide(), 1000)
    check(r, m.opt.timestep)
    assert r.contact_steps > 500


def test_impact_at_half_a_metre_per_second():
    m = model()

    def setup(m, d):
        d.qpos[m.joint("press_z").qposadr[0]] = 2e-3  # 2.3 mm above the plate
        d.qvel[m.joint("press_z").dofadr[0]] = -0.5

    r = simulate(m, press_slide(speed=0.0), 1500, setup)
    check(r, m.opt.timestep)
    # the impact overshoots the static load, then settles to it
    assert r.force[:, 0].max() > 0.6
    assert abs(r.force[-50:, 0].mean() - 0.5) < 0.01


def test_sliding_at_one_metre_per_second():
    proto = scenes.Protocol(speed_m_s=1.0, timestep_s=1e-4, press_s=0.05)
    m = model(texture=scenes.Texture(period_m=1e-3, length_m=0.64), protocol=proto)
    r = simulate(m, press_slide(speed=1.0, t_press=0.05), 3000)
    check(r, m.opt.timestep)
    fn = r.force[-500:, 0]
    # Coulomb friction and a steady normal force while sliding fast
    assert abs(fn.mean() - 0.5) < 5e-3 and fn.std() < 5e-3
    assert abs(r.force[-500:, 1].mean() / fn.mean() + 0.5) < 0.01


def test_texture_finer_than_taxel_pitch():
    tex = scenes.Texture(period_m=0.1e-3, edge_m=0.01e-3, resolution_m=5e-6, length_m=0.06)
    m = model(texture=tex)
    r = simulate(m, press_slide(), 800)
    check(r, m.opt.timestep)


PLATE_HALF_M = (0.04, 0.015)  # the scenes' plate box half-sizes along x, y


def cell_centres(layout):
    """Taxel cell centres along one grid axis, pad frame (m)."""
    return (np.arange(layout.nx) - (layout.nx - 1) / 2) * layout.pitch_m


@pytest.mark.parametrize("grid_cycle", ["1", "4"])
@pytest.mark.parametrize("corner", [False, True], ids=["edge", "corner"])
def test_contact_at_plate_edge_and_corner(corner, grid_cycle):
    # The pad's pole sits over the plate's +x edge (and its +y edge): the
    # plate ends under the middle of the skin.
    def edit(spec):
        finger = spec.body("finger")
        finger.pos = [PLATE_HALF_M[0], PLATE_HALF_M[1] if corner else 0.0, finger.pos[2]]

    tip = fast_tip()
    tip.skin["grid_cycle"] = grid_cycle
    m = model(tip=tip, texture=scenes.Texture(kind="flat"), edit=edit)
    r = simulate(m, press_slide(speed=0.0), 800)
    check(r, m.opt.timestep)
    assert r.contact_steps > 400
    # The finger only slides and presses (no rotation): pad axes = world axes.
    p, h = r.final_pressure, r.layout.pitch_m
    X, Y = np.meshgrid(cell_centres(r.layout), cell_centres(r.layout))  # [j, i]
    edges = [(X, PLATE_HALF_M[0] - r.pad_pos[0])]
    if corner:
        edges.append((Y, PLATE_HALF_M[1] - r.pad_pos[1]))
    for coord, edge in edges:  # edge: the plate's edge in the pad frame
        assert abs(edge) < h / 2  # the edge is under the pole's cells
        # Cells wholly off the plate carry no load on one grid; the default
        # grid cycle deposits each offset grid's cells on the nearest taxel
        # cells, so an offset cell straddling the edge may put load on the
        # first cell past it, never farther (moves of at most half a cell).
        spill = 0 if grid_cycle == "1" else h
        beyond = coord - h / 2 - spill > edge
        assert np.all(p[beyond] == 0)
        # the contact reaches the edge: the last cells wholly on the plate
        # carry load
        last = (coord + h / 2 <= edge) & (coord + 1.5 * h > edge)
        assert p[last].max() > 0.1 * p.max()
        # The pressure is not symmetric about the pole: its centroid lies on
        # the plate side. Winkler pressure on a paraboloidal pad is
        # p ~ a^2 - r^2; cut at the pole its centroid is 16 a / (15 pi)
        # = 0.34 a into the plate (a: the contact's reach); a flatter
        # profile (here the contact is clipped by the grid) moves it further
        # in, and 0.25 a leaves room for the ridges and the ellipsoid's shape.
        reach = edge - coord[p > 0].min()
        centroid = (p * coord).sum() / p.sum()
        assert centroid < edge - 0.25 * reach, (centroid, reach)


def love_rectangle_szz(x1, x2, y1, y2, z):
    """-s_zz at depth z under the origin from a unit uniform pressure on the
    rectangle [x1, x2] x [y1, y2] of a homogeneous half-space (Love 1929,
    by superposition of corner rectangles; independent of nu)."""

    def corner(a, b):
        r = np.sqrt(a * a + b * b + z * z)
        return (
            np.arctan(a * b / (z * r)) + a * b * z / r * (1 / (a * a + z * z) + 1 / (b * b + z * z))
        ) / (2 * np.pi)

    return corner(x2, y2) - corner(x1, y2) - corner(x2, y1) + corner(x1, y1)


STEP_SKINS = {
    "halfspace": {"skin": "halfspace", "poisson": "0.48"},
    # identical incompressible layers over the same half-space: a homogeneous
    # solid through the layered code path
    "layered_homogeneous": {"layers": "0.7e-3 5e4 0.5; 0.8e-3 5e4 0.5", "base": "5e4 0.5"},
    "shao": {},  # the default layered fingertip over bone
}


@pytest.mark.parametrize("skin", list(STEP_SKINS))
def test_receptors_under_a_sharp_step_edge(skin):
    # The pad pressed on a 3 mm step (a box) whose edge lies under the pole:
    # the pressure jumps from zero to its peak across one taxel boundary.
    # Explicit receptor sites in the two cell columns either side of the edge
    # and one further out, at 20 um (well inside a taxel: the kernel's
    # near-surface regime), 0.15 mm and 0.75 mm; s_zz everywhere.
    h = 1.5e-4
    xs = (-1.5 * h, -0.5 * h, 0.5 * h, 1.5 * h)
    ys = (0.5 * h, 3.5 * h)
    sites = "; ".join(
        f"{c} {x!r} {y!r} {z!r}"
        for c, z in (("SA1", 20e-6), ("RA", 0.15e-3), ("PC", 0.75e-3))
        for x in xs
        for y in ys
    )
    # Winkler: the pressure is a plateau cut by the edge (elastic contact
    # would add the punch-edge singularity, not what this checks)
    cfg = {
        "outputs": "spikes stress force pressure",
        "shear": "false",
        "pressure": "winkler",
        "quantity": "szz szz szz",
        "sites": sites,
        **STEP_SKINS[skin],
    }

    def edit(spec):
        spec.body("finger").pos = [-0.02, 0, 0.0103]
        box(spec, "step", [0.01, 0.01, 0.0015], [-0.01, 0, 0.0015])

    m = model(
        tip=fast_tip(skin=cfg, ridges=False, pitch_m=h),
        texture=scenes.Texture(kind="flat"),
        edit=edit,
    )
    r = simulate(m, press_slide(speed=0.0), 600)
    check(r, m.opt.timestep)
    layout, p = r.layout, r.final_pressure
    c = cell_centres(layout)
    edge = -0.02 - r.pad_pos[0]  # the step's -x face, pad frame
    assert abs(edge) < 1e-3 * h  # on the cell boundary at the pole (the slide holds x)
    # a sharp edge: nothing beyond it, the first column on the step loaded
    # like the peak (the pad's curvature changes p by < 1% over one taxel)
    i_edge = layout.nx // 2
    assert np.all(p[:, :i_edge] == 0)
    assert p[:, i_edge].max() > 0.9 * p.max()
    got = r.final_stress
    pos = layout.positions_m
    assert len(got) == 3 * len(xs) * len(ys)
    if skin == "shao":
        # no closed form: the stress equals the kernel applied to the
        # rendered pressure (LayeredSkin: the same tables, evaluated outside
        # the plugin)
        from mjtouch import core

        stack = core.LayeredSkin()
        ij = np.rint(pos[:, :2] / h + (layout.nx - 1) / 2).astype(int)
        want = np.empty(len(got))
        for z in np.unique(pos[:, 2]):
            k = pos[:, 2] == z
            want[k] = -stack.field_stress(p.astype(np.float32), h, z, ij[k])[:, 2]
    else:
        want = np.array(
            [
                (
                    p
                    * love_rectangle_szz(
                        c[None, :] - h / 2 - x,
                        c[None, :] + h / 2 - x,
                        c[:, None] - h / 2 - y,
                        c[:, None] + h / 2 - y,
                        z,
                    )
                ).sum()
                for x, y, z in pos
            ]
        )
        # Boussinesq's s_zz kernel is positive and integrates to 1: 0 <= -s_zz <= max p
        assert np.all(got >= 0) and np.all(got <= p.max() * (1 + 1e-6))
    # kernel tables and pressures are float32 (6e-8 relative each); 1e-5 of
    # the peak covers their rounding summed over the ~1000 loaded cells
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-5 * p.max())
    # under the edge the shallow receptors see the jump: full load on the
    # step side, a small fraction of it beyond
    shallow = pos[:, 2] == 20e-6
    on_step = shallow & (pos[:, 0] > 0)
    off_step = shallow & (pos[:, 0] < 0)
    assert got[on_step].min() > 0.5 * p.max() and got[off_step].max() < 0.05 * p.max()


SHAO_LAYERS = [(0.7e-3, 8e4, 0.48), (0.8e-3, 5e4, 0.48), (2.5e-3, 2.4e4, 0.4)]  # over bone


def layers_attr(layers):
    return "; ".join(f"{t!r} {e!r} {nu!r}" for t, e, nu in layers)


def skin_rollout(skin, steps=400):
    """The grating slide (press 0.5 N, slide at 25 mm/s) with the given
    elastic skin; the skin changes no dynamics and the Winkler pressure does
    not depend on the skin, so every call sees the same contact and pressure
    (the stress stage alone is compared)."""
    cfg = {"outputs": "spikes stress force pressure", "pressure": "winkler", **skin}
    m = model(tip=fast_tip(skin=cfg))
    r = simulate(m, press_slide(), steps)
    check(r, m.opt.timestep)
    return r


def assert_same_contact(a: Run, b: Run):
    # the plugin is a sensor: different skins, bit-identical contact; and
    # the same receptors (class, x, y) to compare
    np.testing.assert_array_equal(a.pressure_max, b.pressure_max)
    np.testing.assert_array_equal(a.final_pressure, b.final_pressure)
    np.testing.assert_array_equal(a.layout.classes, b.layout.classes)
    np.testing.assert_array_equal(a.layout.positions_m[:, :2], b.layout.positions_m[:, :2])


def film_stack(thickness_m, young_pa):
    """Shao's fingertip with its top `thickness_m` replaced by a film."""
    (t0, e0, nu0), *rest = SHAO_LAYERS
    return [(thickness_m, young_pa, nu0), (t0 - thickness_m, e0, nu0), *rest]


def test_very_thin_10um_layer():
    ref = skin_rollout({})  # Shao's stack
    peak = np.abs(ref.stress).max()
    assert peak > 0
    # Splitting the epidermis into a 10 um layer and the rest, same
    # material, changes nothing (float32 tables: 1e-5 of the peak).
    split = skin_rollout({"layers": layers_attr(film_stack(10e-6, SHAO_LAYERS[0][1]))})
    assert_same_contact(ref, split)
    np.testing.assert_allclose(split.stress, ref.stress, rtol=0, atol=1e-5 * peak)
    # A 10x stiffer film (stratum corneum-like), 10 um and 5 um thick, with
    # the SA1 receptors exactly on the 10 um film's lower interface. The
    # film's effect on the RA (0.75 mm) and PC (2 mm) stresses is first
    # order in its thickness (membrane stiffness E t): halving t halves it,
    # up to O(t^2) (measured ratio 1.9).
    stiff = 10 * SHAO_LAYERS[0][1]
    film10 = skin_rollout(
        {"layers": layers_attr(film_stack(10e-6, stiff)), "depth": "1e-5 0.75e-3 2e-3"}
    )
    film5 = skin_rollout({"layers": layers_attr(film_stack(5e-6, stiff))})
    deep = ~ref.layout.mask("SA1")
    effect10 = np.abs(film10.stress[:, deep] - ref.stress[:, deep]).max()
    effect5 = np.abs(film5.stress[:, deep] - ref.stress[:, deep]).max()
    assert effect10 > 1e-3 * peak  # the film is felt ...
    assert 1.5 < effect10 / effect5 < 2.5, (effect10, effect5)  # ... linearly in t
    assert_same_contact(ref, film10)


def test_very_thick_20mm_layer():
    E, nu, H = 5e4, 0.45, 20e-3
    half = skin_rollout({"skin": "halfspace", "poisson": repr(nu)})
    peak = np.abs(half.stress).max()
    # a 20 mm layer over a half-space of the same material is a half-space
    # (the layered transfer functions at k H up to ~400 vs Boussinesq)
    same = skin_rollout({"layers": f"{H!r} {E!r} {nu!r}", "base": f"{E!r} {nu!r}"})
    assert_same_contact(half, same)
    np.testing.assert_allclose(same.stress, half.stress, rtol=0, atol=1e-5 * peak)
    # Over bone, with the PC receptors on the bone surface (20 mm). Seen
    # from the bone the load is a point force F, so the bone's reaction
    # field near the skin surface is of order F / H^2 (measured 0.13 F/H^2,
    # against stresses ~ 20x larger): SA1 and RA (0.75 mm) within F / H^2.
    bone = skin_rollout({"layers": f"{H!r} {E!r} {nu!r}", "depth": f"0.75e-3 0.75e-3 {H!r}"})
    assert_same_contact(half, bone)
    near = ~half.layout.mask("PC")
    fn = half.force[:, :1]
    assert np.all(np.abs(bone.stress[:, near] - half.stress[:, near]) <= fn / H**2 + 1e-9)
    # On the bone surface the stress is set by F / H^2 too (Boussinesq's
    # 3 F / (2 pi H^2) = 0.48 F / H^2 in a half-space; the bonded bone raises
    # it, measured 0.8 F / H^2): an order of magnitude either way.
    pc = bone.final_stress[bone.layout.mask("PC")]
    scale = bone.force[-1, 0] / H**2
    assert np.all((pc > 0.1 * scale) & (pc < 10 * scale)), (pc.min(), pc.max(), scale)


def test_receptor_exactly_on_an_interface():
    # Sites on Shao's epidermis/dermis interface (0.7 mm) and 0.5 um above
    # and below it, with interface_side upper and lower.
    z, eps, h = 0.7e-3, 0.5e-6, 1.5e-4
    xy = [(0.0, 0.0), (3 * h, 0.0), (0.0, 6 * h), (-9 * h, 3 * h)]
    sites = "; ".join(
        f"{c} {x!r} {y!r} {d!r}"
        for c, d in (("SA1", z - eps), ("RA", z), ("PC", z + eps))
        for x, y in xy
    )
    for quantity in ("szz", "maxcomp"):
        got = {}
        for side in ("upper", "lower"):
            r = skin_rollout(
                {
                    "sites": sites,
                    "interface_side": side,
                    "quantity": f"{quantity} {quantity} {quantity}",
                }
            )
            got[side] = {c: r.stress[:, r.layout.mask(c)] for c in ("SA1", "RA", "PC")}
        above, below = got["upper"]["SA1"], got["upper"]["PC"]
        peak = np.abs(above).max()
        assert peak > 0
        # 0.5 um off the interface moves a field that varies over ~z by
        # about eps / z of the peak
        tol = 2 * eps / z * peak
        if quantity == "szz":
            # traction continuity: s_zz is the same from both sides (float32
            # tables: 1e-5 of the peak) ...
            np.testing.assert_allclose(
                got["upper"]["RA"], got["lower"]["RA"], rtol=0, atol=1e-5 * peak
            )
            # ... and so is d s_zz / dz (equilibrium: -d s_xz / dx - d s_yz / dy,
            # both continuous), so the interface value is the mean of its
            # neighbours up to O(eps^2): within a tenth of their difference
            mid, spread = (above + below) / 2, np.abs(above - below)
            assert np.all(np.abs(got["upper"]["RA"] - mid) <= 0.1 * spread + 1e-5 * peak)
        else:
            # in-plane stresses jump (different materials): each side takes
            # the limit from its own layer
            np.testing.assert_allclose(got["upper"]["RA"], above, rtol=0, atol=tol)
            np.testing.assert_allclose(got["lower"]["RA"], below, rtol=0, atol=tol)
            assert np.abs(above - below).max() > 10 * tol


def test_lift_off_and_recontact_every_few_ms():
    m = model()

    def ctrl(d, k):
        # 6 ms pressed with 2 N, 6 ms pulled up with 1.5 N (gravity
        # compensated): the pad leaves the plate and falls back each cycle
        # (a symmetric pull would ratchet it upwards, out of reach)
        d.ctrl[:] = [0.02, -2.0 if (k // 30) % 2 == 0 else 1.5]

    r = simulate(m, ctrl, 1000)
    check(r, m.opt.timestep)
    touching = r.force[:, 0] > 0
    transitions = np.count_nonzero(np.diff(touching.astype(int)))
    assert transitions >= 10


def test_fifty_newton_load():
    proto = scenes.Protocol(force_n=50.0, timestep_s=2e-4)
    m = model(protocol=proto)
    r = simulate(m, press_slide(force=50.0), 1000)
    check(r, m.opt.timestep)
    assert abs(r.force[-100:, 0].mean() - 50) < 0.5


def test_grazing_contact_with_near_zero_force():
    # 0.1 mN held: the pad rests on the plate with ~1e-5 m of overlap.
    proto = scenes.Protocol(force_n=1e-4, timestep_s=2e-4)
    m = model(protocol=proto)

    def setup(m, d):  # start with the pad just touching the plate
        d.qpos[m.joint("press_z").qposadr[0]] = -3e-4

    r = simulate(m, press_slide(force=1e-4, speed=0.0), 1500, setup)
    check(r, m.opt.timestep)
    assert r.contact_steps == 1500
    assert r.force[-100:, 0].mean() == pytest.approx(1e-4, rel=0.05)


def test_light_touch_sliding():
    # 10 mN sliding on a flat plate stays in contact with a steady load.
    # (Below ~5 mN the start of sliding pops MuJoCo's soft contact off the
    # plate; see the hard-case issue note.)
    proto = scenes.Protocol(force_n=1e-2, timestep_s=2e-4)
    m = model(protocol=proto, texture=scenes.Texture(kind="flat"))
    r = simulate(m, press_slide(force=1e-2, speed=0.02), 1500)
    check(r, m.opt.timestep)
    fn = r.force[-300:, 0]
    assert np.all(fn > 0)
    assert abs(fn.mean() - 1e-2) < 1e-4


@pytest.mark.parametrize("skin", ["halfspace", "layered"])
@pytest.mark.parametrize("nu", ["0.4999", "0.5"])
def test_incompressible_skin(nu, skin):
    cfg = {"outputs": "spikes stress force pressure", "skin": skin}
    if skin == "halfspace":
        cfg["poisson"] = nu
    else:  # Shao's stack, every layer and the base at nu
        cfg["layers"] = f"7e-4 8e4 {nu}; 8e-4 5e4 {nu}"
        cfg["base"] = f"2.4e4 {nu}"
    m = model(tip=fast_tip(skin=cfg))
    r = simulate(m, press_slide(), 600)
    check(r, m.opt.timestep)


@pytest.mark.parametrize("dt", [1e-5, 1e-4, 1e-3, 2e-3])
def test_timesteps_from_1e5_to_2e3(dt):
    proto = scenes.Protocol(timestep_s=dt, press_s=0.05)
    m = model(protocol=proto)
    steps = int(round(0.1 / dt)) if dt >= 1e-4 else 3000
    r = simulate(m, press_slide(t_press=0.05 if dt >= 1e-4 else 0.01), steps)
    check(r, dt)


def test_fingertip_rotated_ninety_degrees_side_contact():
    # The finger lies on its side: the pad's -z pole faces +x, pressed
    # against a vertical wall by the press actuator.
    def edit(spec):
        finger = spec.body("finger")
        finger.pos = [-0.02, 0, 0.02]
        finger.alt.type = mujoco.mjtOrientation.mjORIENTATION_EULER
        finger.alt.euler = [0, -90, 0]  # degrees (compiler.degree)
        box(spec, "wall", [0.002, 0.02, 0.02], [-0.0107, 0, 0.02], rgba=[0.5, 0.5, 0.5, 1])

    m = model(texture=scenes.Texture(kind="flat"), edit=edit)
    # After the -90 degree turn about y the finger's local z is world -x, so
    # the press actuator's ctrl < 0 drives the pad towards +x, into the wall.
    r = simulate(m, lambda d, k: d.ctrl.__setitem__(slice(None), [0.0, -0.5]), 800)
    check(r, m.opt.timestep)
    assert abs(r.force[-100:, 0].mean() - 0.5) < 0.02


def test_several_objects_touching_at_once():
    # Two raised blocks under the pad, both in contact with it.
    def edit(spec):
        box(spec, "block_a", [0.002, 0.01, 0.0002], [-0.0225, 0, 0.0002])
        box(spec, "block_b", [0.002, 0.01, 0.0002], [-0.0175, 0, 0.0002])

    m = model(texture=scenes.Texture(kind="flat"), edit=edit)
    seen = set()

    def ctrl(d, k):
        d.ctrl[:] = [0.0, -0.5]
        for i in range(d.ncon):
            seen.update({m.geom(g).name for g in d.contact[i].geom})

    r = simulate(m, ctrl, 800)
    check(r, m.opt.timestep)
    assert {"block_a", "block_b"} <= seen


def test_long_time_without_contact_then_contact():
    m = model()

    def ctrl(d, k):
        d.ctrl[:] = [0.0, 1e-3 if k < 5000 else -0.5]  # hover for 1 s, then press

    r = simulate(m, ctrl, 5600)
    check(r, m.opt.timestep)
    assert np.all(r.force[:4000, 0] == 0)
    assert r.force[-50:, 0].mean() > 0.4
    # spikes at the contact onset, none while hovering
    assert r.spikes[:4000].sum() == 0 and r.spikes[5000:].sum() > 0


# Largest adaptation current (threshold units) of the default afferents:
# jump x 1.4 (the largest variant multiplier) / (1 - exp(-refractory / tau_a))
# for (jump, tau_a) of SA1, RA, PC (receptors.h ReceptorParams::adapt).
W_MAX_ADAPT = max(
    j * 1.4 / (1 - np.exp(-1e-3 / tau)) for j, tau in ((0.1, 0.05), (1.0, 0.03), (1.0, 0.02))
)


def test_million_steps_without_drift_or_state_growth():
    # A small skin pressed with a periodic load: after 10^6 steps the
    # response to one load cycle equals the response to an early cycle, and
    # the plugin state stays bounded (membranes below threshold, refractory
    # clocks within the refractory period).
    # Noise off: a periodic steady state is a property of the noise-free
    # model (the noisy membrane's bound: test_afferent_tuning.py,
    # test_noisy_membranes_stay_below_threshold).
    tip = scenes.Fingertip(
        nx=16,
        pitch_m=4e-4,
        ridges=False,
        skin={"outputs": "spikes voltage force", "radius": "2.5e-3", "noise": "0 0 0"},
    )
    proto = scenes.Protocol(timestep_s=1e-3, speed_m_s=0.0)
    m = model(tip=tip, texture=scenes.Texture(kind="flat"), protocol=proto)
    period = 100  # steps
    nsteps = 1_000_000
    import mujoco.rollout

    d = mujoco.MjData(m)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    s0 = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, s0, spec)
    k = np.arange(nsteps)
    ctrl = np.zeros((nsteps, 2))
    ctrl[:, 1] = -(0.5 + 0.3 * np.sin(2 * np.pi * k / period))
    layout = SkinLayout.from_model(m)
    chunk = 100_000
    counts = []
    state = s0[None]
    for c in range(nsteps // chunk):
        st, sd = mujoco.rollout.rollout(m, d, state, ctrl[None, c * chunk : (c + 1) * chunk])
        state = st[:, -1]
        spikes = layout.block(sd[0], "spikes")
        assert np.all(np.isfinite(sd))
        counts.append(spikes[-10 * period :].sum(axis=0))
        fn = layout.block(sd[0], "force")[:, 0]
        assert np.all(fn[-period:] > 0)
        # membranes stay below threshold and above minus the largest
        # adaptation current (issue 14: the inhibitory adaptation current holds
        # a membrane below reset after spikes; it grows by a jump per spike, at
        # most one spike per 1 ms refractory period, and decays with tau_a);
        # indentation bounded
        v = layout.block(sd[0], "voltage")
        assert v.min() >= -W_MAX_ADAPT and v.max() <= 1
        assert np.all(layout.block(sd[0], "force")[:, 3] < 1e-2)
    # the same 10 load cycles at 0.1 s and at the end: identical spike counts
    # per receptor (deterministic periodic steady state, up to one spike of
    # phase slip over 10 cycles)
    first, last = counts[0], counts[-1]
    assert np.max(np.abs(last - first)) <= 1
    assert first.sum() > 0
