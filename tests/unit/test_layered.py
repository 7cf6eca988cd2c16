"""Stage 3b: the layered elastic skin (plugin/core/substrate/layered.*) and the stress
stage (plugin/core/stress/stress_field.*), against an independent numpy/scipy
computation (mjtouch.analysis.reference_solutions.layered: Navier equations with Lame constants,
complex arithmetic, direct inverse 2D Fourier integration), closed forms and
physical laws; and its wiring into the plugin (attributes, errors, outputs)."""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys

import mujoco
import numpy as np
import pytest
from conftest import REPO, pad_scene
from numpy.testing import assert_allclose

from mjtouch import core
from mjtouch.analysis.reference_solutions import layered as oracle
from mjtouch.scene.sensor import SkinLayout

XX, YY, ZZ, XY, XZ, YZ = range(6)
SHAO = [(0.7e-3, 80e3, 0.48), (0.8e-3, 50e3, 0.48), (2.5e-3, 24e3, 0.4)]
# Two layers over an elastic half-space: stiff over soft over medium.
TWO = [(0.4e-3, 100e3, 0.3), (0.3e-3, 20e3, 0.49)]
TWO_BASE = (40e3, 0.35)


@pytest.fixture(scope="module")
def shao():
    return core.LayeredSkin(SHAO, "rigid")


@pytest.fixture(scope="module")
def two():
    return core.LayeredSkin(TWO, TWO_BASE)


def identical(nu, E=50e3):
    """Three identical layers over the same half-space: a homogeneous solid."""
    return core.LayeredSkin([(0.3e-3, E, nu), (0.6e-3, E, nu), (1.1e-3, E, nu)], (E, nu))


def test_default_skin_is_shao_fingertip(shao):
    layers, base = core.shao_fingertip()
    assert layers == SHAO and base == "rigid"
    assert core.LayeredSkin().describe() == shao.describe()
    assert shao.material(0.3e-3) == (80e3, 0.48)
    assert shao.material(0.7e-3) == (80e3, 0.48)  # on the interface: upper side
    assert shao.material(0.7e-3, "lower") == (50e3, 0.48)
    assert shao.material(2.0e-3) == (24e3, 0.4)


# -- the independent oracle -------------------------------------------------
# The C++ solves the same boundary-value problem with a different formulation
# (Papkovich-Neuber potentials, mu and nu only, real arithmetic); agreement to
# 1e-5 of the largest value is the bar, both are far better.


@pytest.mark.parametrize("stack", ["shao", "two"])
def test_transfer_functions_match_oracle(stack, shao, two):
    skin, layers, base = (shao, SHAO, None) if stack == "shao" else (two, TWO, TWO_BASE)
    k = np.array([10.0, 1e3, 1e4, 1e5])
    zi = layers[0][0]
    for z, side in [(0.2e-3, "upper"), (zi, "upper"), (zi, "lower"), (2.5e-3, "upper")]:
        got = skin.transfer(k, z, side)
        ref = oracle.transfer(k, z, layers, base, side == "upper")
        scale = np.max([np.abs(ref[name]) for name in core.TRANSFER_NAMES], axis=0)
        for name in core.TRANSFER_NAMES:
            assert np.all(np.abs(got[name] - ref[name]) <= 1e-5 * scale), (stack, z, side, name)


@pytest.mark.parametrize("stack", ["shao", "two"])
def test_surface_compliance_matches_oracle(stack, shao, two):
    skin, layers, base = (shao, SHAO, None) if stack == "shao" else (two, TWO, TWO_BASE)
    k = np.logspace(0, 6, 25)
    assert_allclose(skin.compliance(k), oracle.surface_compliance(k, layers, base), rtol=1e-5)


def test_lattice_and_disc_stress_match_oracle(shao, two):
    # Plugin table entries (uniform unit traction on one 0.2 mm cell) and disc
    # loads (radius 1 mm), all loads, against the oracle's direct 2D Fourier
    # integrals: within 1e-5 of the largest component.
    pitch, n = 0.2e-3, 16
    cases = [
        (shao, SHAO, None, 0.75e-3, "upper", (0, 0), "pressure"),
        (shao, SHAO, None, 0.7e-3, "lower", (2, -3), "shear_x"),
        (shao, SHAO, None, 2.0e-3, "upper", (-5, 4), "shear_y"),
        (two, TWO, TWO_BASE, 0.4e-3, "upper", (1, 2), "pressure"),
        (two, TWO, TWO_BASE, 1.5e-3, "upper", (-4, -1), "shear_x"),
    ]
    for skin, layers, base, z, side, (di, dj), load in cases:
        table = skin.lattice_table(z, pitch, n, side)
        got = table[core.LOADS[load], :, dj + n - 1, di + n - 1]
        ref = oracle.cell_stress(
            load, -di * pitch, -dj * pitch, z, pitch, layers, base, side == "upper"
        )
        assert np.max(np.abs(got - ref)) <= 1e-5 * np.max(np.abs(ref)), (z, side, load, got, ref)
    for skin, layers, base, (x, y, z), load in [
        (shao, SHAO, None, (0.5e-3, 0.3e-3, 0.3e-3), "shear_y"),
        (two, TWO, TWO_BASE, (-2e-3, 1e-3, 2.5e-3), "pressure"),
    ]:
        got = skin.disc_stress(x, y, z, 1e-3, load)
        ref = oracle.disc_stress(load, x, y, z, 1e-3, layers, base)
        assert np.max(np.abs(got - ref)) <= 1e-5 * np.max(np.abs(ref)), (load, got, ref)


def test_axisymmetric_disc_matches_oracle_hankel(shao):
    # Third route: the oracle's classical Hankel integrals (scipy j0/j1), on
    # the +x axis where s_xx = s_rr, s_yy = s_tt, s_xz = s_rz.
    for r, z in [(0.0, 0.3e-3), (0.8e-3, 0.7e-3), (1.5e-3, 1.2e-3), (0.4e-3, 3.0e-3)]:
        srr, stt, szz, srz = oracle.disc_pressure_axisym(r, z, 1e-3, SHAO, None)
        s = shao.disc_stress(r, 0.0, z, 1e-3)
        ref = np.array([srr, stt, szz, srz])
        assert_allclose(s[[XX, YY, ZZ, XZ]], ref, atol=1e-5 * np.abs(ref).max())


# -- homogeneous limits -----------------------------------------------------


@pytest.mark.parametrize("nu", [0.3, 0.5])
def test_identical_layers_reproduce_boussinesq_and_cerruti(nu):
    skin = identical(nu)
    pts = np.array(
        [
            (0.0, 0.0, 0.2e-3),
            (0.3e-3, 0.0, 0.3e-3),
            (0.25e-3, -0.4e-3, 0.9e-3),
            (3e-3, 1e-3, 2e-3),
            (-1e-3, 0.5e-3, 2.5e-3),
        ]
    )
    for load in core.LOADS:
        got = skin.point_stress(pts[:, 0], pts[:, 1], pts[:, 2], load)
        ref = core.halfspace_stress(pts[:, 0], pts[:, 1], pts[:, 2], load, nu)
        # rtol 1e-4; components that vanish by symmetry are held to 1e-6 of
        # the point's largest component.
        assert_allclose(got, ref, rtol=1e-4, atol=1e-6 * np.abs(ref).max(), err_msg=load)


@pytest.mark.parametrize("nu", [0.3, 0.5])
def test_identical_layers_reproduce_uniform_disc_on_axis(nu):
    # Johnson (1985) sec. 3.4: uniform pressure q on a disc of radius a, axis:
    # s_zz = -q [1 - z^3 / R^3], s_rr = s_tt = -q/2 [(1 + 2 nu) - 2 (1 + nu) z / R
    # + z^3 / R^3], R = sqrt(a^2 + z^2).
    skin, a = identical(nu), 1e-3
    for z in (0.1e-3, 0.3e-3, 0.9e-3, 2e-3):
        s = skin.disc_stress(0.0, 0.0, z, a)
        R = math.hypot(a, z)
        szz = -(1 - z**3 / R**3)
        srr = -0.5 * ((1 + 2 * nu) - 2 * (1 + nu) * z / R + z**3 / R**3)
        assert_allclose([s[ZZ], s[XX], s[YY]], [szz, srr, srr], rtol=1e-4)
        assert_allclose(s[[XY, XZ, YZ]], 0, atol=1e-10)


def _hertz_cells(n, h, a, p0, m=16):
    """Exact cell averages of the Hertz pressure p0 sqrt(1 - r^2/a^2) (Gauss,
    m x m per cell) on an n x n grid centred on the contact."""
    x, w = np.polynomial.legendre.leggauss(m)
    c = (np.arange(n) - (n - 1) / 2) * h
    X = (c[:, None] + 0.5 * h * x[None, :]).ravel()
    W = np.tile(w, n) * 0.5
    p = p0 * np.sqrt(np.clip(1 - (X[None, :] ** 2 + X[:, None] ** 2) / a**2, 0, None))
    return (p * W[None, :] * W[:, None]).reshape(n, m, n, m).sum(axis=(1, 3))


def test_identical_layers_reproduce_hertz_subsurface_field():
    # Hertz pressure (a = 1 mm) loaded cell by cell on the lattice, stress on
    # the axis vs REFERENCE.md sec. 3. A piecewise-uniform load differs from
    # the smooth one by O(h^2) in its second moments, so the lattice result
    # converges as h^2: checked (error ratio ~4 from h = 50 to 25 um), then
    # Richardson's extrapolation (4 s(h/2) - s(h)) / 3 removes that term and
    # must meet the closed form to 1e-4 of p0.
    nu, a, p0 = 0.45, 1e-3, 1e4
    skin = identical(nu)
    depths = [0.25e-3, 0.5e-3, 1e-3, 2e-3]
    res = {}
    for h in (0.05e-3, 0.025e-3):
        n = int(np.ceil(2 * a / h)) + 3
        n += 1 - n % 2  # odd: a centre cell on the axis
        p = _hertz_cells(n, h, a, p0)
        res[h] = np.array([skin.field_stress(p, h, z, [[n // 2, n // 2]])[0] for z in depths])
    zz = np.array(depths)
    szz = -p0 / (1 + zz**2 / a**2)
    srr = p0 * (-(1 + nu) * (1 - zz / a * np.arctan(a / zz)) + 0.5 / (1 + zz**2 / a**2))
    err_coarse = res[0.05e-3][:, ZZ] - szz
    err_fine = res[0.025e-3][:, ZZ] - szz
    assert np.all((3.5 < err_coarse / err_fine) & (err_coarse / err_fine < 4.5)), (
        err_coarse / err_fine
    )
    rich = (4 * res[0.025e-3] - res[0.05e-3]) / 3
    assert_allclose(rich[:, ZZ], szz, atol=1e-4 * p0)
    assert_allclose(rich[:, XX], srr, atol=1e-4 * p0)
    assert_allclose(rich[:, YY], srr, atol=1e-4 * p0)


def test_poisson_half_exact():
    # nu = 0.5 (incompressible) has no special case: the transfer functions of
    # identical layers equal the closed form to round-off, and the oracle
    # (Lame lambda, so nu < 0.5 only) tends to it: at nu = 0.5 - 1e-7 it
    # differs by O(1e-7).
    skin = identical(0.5)
    k = np.array([0.0, 1e2, 1e3, 1e4, 1e5])
    z = 0.9e-3
    t = skin.transfer(k, z)
    e = np.exp(-k * z)
    assert_allclose(t["p_zz"], -(1 + k * z) * e, atol=1e-12)
    assert_allclose(t["p_etaeta"], -e, atol=1e-12)  # -2 nu e
    assert_allclose(t["q_etaeta"], e, atol=1e-12)
    layers = [(0.3e-3, 50e3, 0.5 - 1e-7), (0.6e-3, 20e3, 0.5 - 1e-7)]
    near = oracle.transfer(k[1:], z, layers, (30e3, 0.5 - 1e-7))
    exact = core.LayeredSkin([(0.3e-3, 50e3, 0.5), (0.6e-3, 20e3, 0.5)], (30e3, 0.5))
    got = exact.transfer(k[1:], z)
    for name in core.TRANSFER_NAMES:
        assert np.all(np.abs(got[name] - near[name]) < 1e-5), name


def test_large_kh_compliance_and_transfer_finite():
    # k h up to 1e4 (and 1.7e4 within a 20 mm layer): no overflow; a layer's
    # compliance tends to the half-space's 2 (1 - nu^2) / (E k).
    skin = core.LayeredSkin([(0.7e-3, 80e3, 0.48), (20e-3, 20e3, 0.45)], "rigid")
    k = np.array([1e2, 1e3, 1e4]) / 0.7e-3
    assert_allclose(skin.compliance(k), 2 * (1 - 0.48**2) / (80e3 * k), rtol=1e-8)
    for z in (0.3e-3, 0.7e-3, 15e-3):
        t = skin.transfer(k, z)
        assert all(np.all(np.isfinite(v)) for v in t.values())
    # identical layers at k h = 1e4 still equal the closed form
    t = identical(0.45).transfer(1e4 / 0.3e-3, 0.2e-3)
    kz = 1e4 / 0.3e-3 * 0.2e-3
    assert_allclose(t["p_zz"], -(1 + kz) * np.exp(-kz), rtol=1e-8, atol=1e-300)


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.49])
def test_layer_on_rigid_base_compliance(nu):
    # Carbone & Mangialardi (2008) / Johnson: one layer of thickness H bonded
    # to a rigid base.
    E, H = 50e3, 1.5e-3
    kh = np.array([0.1, 0.5, 1.0, 2.0, 5.0, 20.0])
    k3 = 3 - 4 * nu
    ref = (
        2
        * (1 - nu * nu)
        / (E * kh / H)
        * (k3 * np.sinh(2 * kh) - 2 * kh)
        / (k3 * np.cosh(2 * kh) + 2 * kh**2 + 5 - 12 * nu + 8 * nu**2)
    )
    assert_allclose(core.LayeredSkin([(H, E, nu)]).compliance(kh / H), ref, rtol=1e-8)


def test_compliance_table_half_space_centre_is_love():
    # Love (1929): centre of a uniformly loaded square of side h on a
    # half-space sinks 4 h ln(1 + sqrt 2) (1 - nu^2) / (pi E) per Pa.
    E, nu, h = 50e3, 0.45, 0.1e-3
    t = core.LayeredSkin([(0.5e-3, E, nu), (1e-3, E, nu)], (E, nu)).compliance_table(h, 16)
    ref = 4 * h * math.log(1 + math.sqrt(2)) * (1 - nu**2) / (math.pi * E)
    assert_allclose(t[15, 15], ref, rtol=1e-6)
    assert_allclose(t, t[::-1, ::-1])  # symmetric


# -- laws -------------------------------------------------------------------


def test_load_integral_over_every_plane(shao):
    # Equilibrium of the slab above depth z: the integral of s_zz over the
    # plane is minus the applied normal load, of s_xz (s_yz) the shear load.
    # k = 0 transfer functions are that integral, exactly, at any depth:
    for skin, zs in [
        (shao, [0.05e-3, 0.7e-3, 1.5e-3, 3.9e-3]),
        (core.LayeredSkin(SHAO, (24e3, 0.4)), [0.7e-3, 4e-3, 6e-3]),
    ]:
        for z in zs:
            for side in ("upper", "lower"):
                t = skin.transfer(0.0, z, side)
                assert_allclose(
                    [t["p_zz"], t["q_xiz"], t["a_etaz"], t["p_xiz"], t["q_zz"]],
                    [-1, 1, -1, 0, 0],
                    atol=1e-13,
                )
    # ... and the plugin's lattice tables sum to it. A table's sum is the
    # stress under a uniform traction on its whole square, so it falls short
    # of the load by the field outside. Over bone at 4 mm the shear field
    # decays as exp(-r / ~7 mm) (measured: the shortfall is 6e-3 at +-25 mm,
    # 1.6e-4 at +-51 mm), so a +-100 mm table (0.8 mm pitch) leaves < 1e-7;
    # entries are accurate to ~1e-7 of the peak, so 1e-5 bounds the float32
    # sums.
    for z in (0.3e-3, 0.75e-3, 2.0e-3):
        t = shao.lattice_table(z, 0.8e-3, 128)
        sums = [t[0, ZZ].sum(), t[1, XZ].sum(), t[2, YZ].sum()]
        assert_allclose(sums, [-1, -1, -1], atol=1e-5)


def test_superposition_and_fft_equals_direct(shao, rng):
    n, h, z = 40, 0.15e-3, 0.75e-3
    p1 = np.zeros((n, n))
    p1[10:30, 8:28] = rng.uniform(0, 2e4, (20, 20))
    p2 = np.zeros((n, n))
    p2[15:25, 18:33] = rng.uniform(0, 1e4, (10, 15))
    q1 = 0.3 * p1
    ij = rng.integers(0, n, (25, 2))
    engine = core.StressEngine(shao, n, h, [z], ij, method="fft")
    a = engine.stress(p1, q1, None, method="direct")
    b = engine.stress(p2, None, None, method="direct")
    ab = engine.stress(p1 + 2 * p2, q1, None, method="direct")
    scale = np.abs(ab).max()
    # float32 tables and tractions: sums over ~600 cells round at ~1e-6
    assert_allclose(ab, a + 2 * b, atol=1e-5 * scale)
    for method in ("fft", "auto"):
        assert_allclose(engine.stress(p1 + 2 * p2, q1, None, method=method), ab, atol=1e-5 * scale)
    # the lattice is the cell-by-cell superposition of CellStress
    single = np.zeros((n, n))
    single[12, 30] = 1.0
    s = engine.stress(single, method="direct")
    ref = np.array([shao.cell_stress((i - 30) * h, (j - 12) * h, z, h) for i, j in ij])
    assert_allclose(s, ref, atol=1e-6 * np.abs(ref).max())


def test_stress_path_choice_follows_cost_model(shao):
    # auto takes the cheaper path by the cost model; both give the same stress.
    n, h = 64, 0.15e-3
    ij = [(i, j) for i in range(0, n, 2) for j in range(0, n, 2)]  # 1024 sites
    engine = core.StressEngine(shao, n, h, [0.75e-3], ij, method="fft")
    small = np.zeros((n, n))
    small[30:33, 30:33] = 1e3
    big = np.full((n, n), 1e3)
    for p in (small, big):
        active = int((p != 0).sum())
        direct_s, fft_s = engine.estimated_cost(active, shear=False)
        _, _, used, act = engine.stress(p, method="auto", timing=True)
        assert act == active
        assert used == ("fft" if fft_s < direct_s else "direct")
    assert engine.estimated_cost(9, False)[0] < engine.estimated_cost(9, False)[1]
    assert engine.estimated_cost(n * n, False)[0] > engine.estimated_cost(n * n, False)[1]


def test_thin_top_layer_tends_to_substrate():
    # A 5x stiffer top layer of thickness t -> 0 leaves the substrate's own
    # (homogeneous) field; the difference shrinks ~linearly with t.
    Eb, nub, h, z, n = 30e3, 0.45, 0.1e-3, 0.5e-3, 24
    ref = identical(nub, Eb).lattice_table(z, h, n)
    errs = []
    for t in (10e-6, 1e-6, 0.1e-6):
        skin = core.LayeredSkin([(t, 5 * Eb, 0.3), (1e-3, Eb, nub)], (Eb, nub))
        errs.append(np.abs(skin.lattice_table(z, h, n) - ref).max() / np.abs(ref).max())
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1e-2, errs
    assert 5 < errs[0] / errs[1] < 20 and 5 < errs[1] / errs[2] < 20, errs


def test_interface_side(shao):
    # On the epidermis/dermis interface (0.7 mm): s_zz, s_xz, s_yz are
    # continuous; s_xx, s_yy, s_xy jump (materials differ). Each side is the
    # limit of the field from its own layer.
    h, n = 0.1e-3, 12
    up = shao.lattice_table(0.7e-3, h, n, "upper")
    lo = shao.lattice_table(0.7e-3, h, n, "lower")
    peak = np.abs(up).max()
    assert np.abs(up[:, [ZZ, XZ, YZ]] - lo[:, [ZZ, XZ, YZ]]).max() < 1e-6 * peak
    assert np.abs(up[:, [XX, YY, XY]] - lo[:, [XX, YY, XY]]).max() > 1e-2 * peak
    eps = 0.5e-6  # the field's gradient is O(peak / z): 1e-3 of peak moves it O(1e-3)
    above = shao.lattice_table(0.7e-3 - eps, h, n)
    below = shao.lattice_table(0.7e-3 + eps, h, n)
    assert np.abs(above - up).max() < 1e-2 * np.abs(up - lo).max()
    assert np.abs(below - lo).max() < 1e-2 * np.abs(up - lo).max()
    default_lower = core.LayeredSkin(SHAO, "rigid", interface_side="lower")
    assert_allclose(
        default_lower.cell_stress(0.1e-3, 0, 0.7e-3, h),
        shao.cell_stress(0.1e-3, 0, 0.7e-3, h, side="lower"),
    )
    shao.check_depth(4e-3)  # bone surface, from above: valid
    with pytest.raises(ValueError, match="rigid base"):
        shao.check_depth(4e-3, "lower")
    with pytest.raises(ValueError, match="rigid base"):
        shao.check_depth(5e-3)


@pytest.mark.parametrize(
    "layers,base,msg",
    [
        ([], "rigid", "non-empty sequence"),
        ([(0.0, 1e3, 0.3)], "rigid", "thickness"),
        ([(1e-3, -1.0, 0.3)], "rigid", "young: must be > 0"),
        ([(1e-3, 1e3, 0.51)], "rigid", "(-1, 0.5]"),
        ([(1e-3, 1e3, -1.0)], "rigid", "(-1, 0.5]"),
        ([(1e-3, 1e3, 0.3)], (0.0, 0.3), "base young"),
        ([(1e-3, 1e3, 0.3)], (1e3, 0.7), "base poisson"),
    ],
)
def test_python_bad_stack(layers, base, msg):
    with pytest.raises(ValueError, match=msg.replace("(", r"\(").replace("]", r"\]")):
        core.LayeredSkin(np.array(layers).reshape(-1, 3), base)


# -- the plugin --------------------------------------------------------------


def _run(skin: dict, steps: int = 250):
    model = mujoco.MjModel.from_xml_string(pad_scene(skin))
    data = mujoco.MjData(model)
    for _ in range(steps):
        mujoco.mj_step(model, data)
    return model, data, SkinLayout.from_model(model)


def test_plugin_default_skin_layered_and_build_time_reported():
    model = mujoco.MjModel.from_xml_string(pad_scene())
    layout = SkinLayout.from_model(model)
    assert layout.substrate == core.LayeredSkin().describe()
    assert layout.kernel_build_s > 0
    half = SkinLayout.from_model(
        mujoco.MjModel.from_xml_string(pad_scene({"skin": "halfspace", "poisson": "0.45"}))
    )
    assert half.substrate == "homogeneous half-space (nu=0.45)"


def test_plugin_stress_equals_layered_recomputation():
    # The plugin's receptor quantities equal an offline evaluation of the same
    # tractions (its own pressure output, shear off) through LayeredSkin:
    # tables, receptor cells, and the material (E, nu of the receptor's layer)
    # for strain and SED.
    layers = "0.5e-3 80e3 0.45; 0.6e-3 40e3 0.48; 1.5e-3 20e3 0.4"
    skin = {
        "outputs": "stress force pressure",
        "shear": "false",
        "layers": layers,
        "base": "30e3 0.45",
        "quantity": "sed strain maxcomp",
        "depth": "0.4e-3 0.8e-3 2.5e-3",
        "stress_method": "direct",
    }
    model, data, layout = _run(skin)
    n, h = layout.nx, layout.pitch_m
    p = layout.block(data.sensordata, "pressure").reshape(n, n)
    assert p.sum() * h * h == pytest.approx(layout.block(data.sensordata, "force")[0], rel=1e-6)
    got = layout.block(data.sensordata, "stress")
    stack = core.LayeredSkin(
        [(0.5e-3, 80e3, 0.45), (0.6e-3, 40e3, 0.48), (1.5e-3, 20e3, 0.4)], (30e3, 0.45)
    )
    ij = np.rint(layout.positions_m[:, :2] / h + (n - 1) / 2).astype(int)
    for cls, z, (E, nu) in [
        ("SA1", 0.4e-3, (80e3, 0.45)),
        ("RA", 0.8e-3, (40e3, 0.48)),
        ("PC", 2.5e-3, (30e3, 0.45)),
    ]:
        m = layout.mask(cls)
        s = stack.field_stress(p.astype(np.float32), h, z, ij[m][:, ::1])
        tr = s[:, :3].sum(axis=1)
        if cls == "SA1":  # strain energy density
            ss = (s[:, :3] ** 2).sum(axis=1) + 2 * (s[:, 3:] ** 2).sum(axis=1)
            ref = ((1 + nu) * ss - nu * tr**2) / (2 * E)
        else:
            t = np.zeros((m.sum(), 3, 3))
            iu = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
            for c, (a, b) in enumerate(iu):
                t[:, a, b] = t[:, b, a] = s[:, c]
            lam = np.linalg.eigvalsh(t)[:, 0]  # most compressive principal stress
            if cls == "RA":  # principal strain: (1 + nu) l - nu tr, over E
                ref = np.maximum(0, -((1 + nu) * lam - nu * tr) / E)
            else:
                ref = np.maximum(0, -lam)
        assert np.abs(ref).max() > 0
        assert_allclose(got[m], ref, rtol=1e-5, atol=1e-6 * np.abs(ref).max(), err_msg=cls)


def test_plugin_fft_and_direct_paths_agree():
    out = {}
    for method in ("direct", "fft"):
        _, data, layout = _run({"stress_method": method, "outputs": "stress"}, steps=150)
        out[method] = layout.block(data.sensordata, "stress").copy()
    assert np.abs(out["direct"]).max() > 0
    assert_allclose(out["fft"], out["direct"], atol=1e-5 * np.abs(out["direct"]).max())


def test_plugin_interface_side():
    # SA1 and RA at the epidermis/dermis interface: s_zz (RA) is continuous
    # across it; the most compressive principal stress (SA1) is not.
    res = {}
    for side in ("upper", "lower"):
        _, data, layout = _run(
            {
                "interface_side": side,
                "depth": "0.7e-3 0.7e-3 2e-3",
                "quantity": "maxcomp szz szz",
                "outputs": "stress",
            },
            steps=150,
        )
        res[side] = layout.block(data.sensordata, "stress").copy()
    ra, sa1 = layout.mask("RA"), layout.mask("SA1")
    assert_allclose(res["upper"][ra], res["lower"][ra], atol=1e-5 * np.abs(res["upper"][ra]).max())
    assert (
        np.abs(res["upper"][sa1] - res["lower"][sa1]).max() > 1e-3 * np.abs(res["upper"][sa1]).max()
    )


BAD = [
    ({"layers": "0.7e-3 -80e3 0.48"}, "`layers`", "layer 1 E", "[100, 2e+10] Pa"),
    ({"layers": "0.7e-3 80e3 0.48; 0.8e-3 0 0.48"}, "`layers`", "layer 2 E", "[100, 2e+10] Pa"),
    ({"layers": "0.7e-3 80e3 0.6"}, "`layers`", "layer 1 nu", "(-1, 0.5]"),
    ({"layers": "0.7e-3 80e3 -1"}, "`layers`", "layer 1 nu", "(-1, 0.5]"),
    ({"layers": "0 80e3 0.48"}, "`layers`", "layer 1 thickness", "[1e-06, 1] m"),
    ({"layers": "-1e-3 80e3 0.48"}, "`layers`", "layer 1 thickness", "[1e-06, 1] m"),
    ({"layers": ";"}, "`layers`", "entry 1 is empty", "1 to 64 layers"),
    ({"layers": "0.7e-3 80e3"}, "`layers`", "needs 3 numbers", "thickness (m)"),
    ({"base": "0 0.3"}, "`base`", "E", "[100, 2e+10] Pa"),
    ({"base": "30e3 0.5001"}, "`base`", "nu", "(-1, 0.5]"),
    ({"base": "bone"}, "`base`", "'rigid'", "E in [100, 2e+10] Pa"),
    ({"depth": "0.75e-3 0.75e-3 5e-3"}, "`depth` entry 3", "rigid base", "(0, 0.004] m"),
    (
        {"depth": "0.75e-3 0.75e-3 4e-3", "interface_side": "lower"},
        "`depth` entry 3",
        "rigid base",
        "(0, 0.004) m",
    ),
    (
        {"layers": "1e-3 50e3 0.45", "depth": "0.75e-3 1.5e-3 0.5e-3"},
        "`depth` entry 2",
        "rigid base",
        "(0, 0.001] m",
    ),
    ({"interface_side": "middle"}, "`interface_side`", "middle", "upper lower"),
    ({"skin": "foam"}, "`skin`", "foam", "layered halfspace"),
    ({"poisson": "0.45"}, "`poisson`", 'skin="halfspace" only', "`layers`"),
    (
        {"skin": "halfspace", "layers": "1e-3 50e3 0.45"},
        "`layers`",
        'skin="layered" only',
        "halfspace",
    ),
    (
        {"skin": "halfspace", "quantity": "sed szz szz"},
        "`quantity`",
        "'sed' for SA1",
        "szz maxcomp vonmises maxshear",
    ),
    ({"quantity": "maxcomp energy szz"}, "`quantity`", "energy", "sed strain"),
    ({"stress_method": "gpu"}, "`stress_method`", "gpu", "tree direct fft auto"),
]


@pytest.mark.parametrize(
    "attrs,name,what,valid", BAD, ids=[";".join(f"{k}={v}" for k, v in b[0].items()) for b in BAD]
)
def test_bad_elastic_skin_fails_at_compile(attrs, name, what, valid):
    with pytest.raises(ValueError) as e:
        mujoco.MjModel.from_xml_string(pad_scene(attrs))
    msg = str(e.value)
    assert name in msg and what in msg and valid in msg, msg


def test_cpp_layered_checks(tmp_path):
    # The standalone C++ checks of layered.* (tests/cpp/test_layered.cc),
    # built by CMake (option MJTOUCH_BUILD_TESTS) in a fresh build tree.
    cmake = shutil.which("cmake")
    assert cmake, "cmake (>= 3.18, as for building mjtouch) not on PATH"
    build_dir = tmp_path / "build"
    generator = ["-G", "Ninja"] if shutil.which("ninja") else []
    configure = subprocess.run(
        [
            cmake,
            "-S",
            str(REPO),
            "-B",
            str(build_dir),
            *generator,
            "-DSKBUILD=1",
            "-DMJTOUCH_BUILD_TESTS=ON",
            "-DMJTOUCH_PYTHON_MODULE=OFF",
            "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython_EXECUTABLE={sys.executable}",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert configure.returncode == 0, configure.stdout[-2000:] + configure.stderr[-4000:]
    build = subprocess.run(
        [
            cmake,
            "--build",
            str(build_dir),
            "--target",
            "mjtouch_cpp_tests",
            "--parallel",
            str(os.cpu_count() or 2),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert build.returncode == 0, build.stdout[-4000:] + build.stderr[-4000:]
    # test_layered: the layered kernel; test_membrane: the afferents' exact
    # LIF integrator (first spike = first threshold crossing); test_fft_threads:
    # the elastic solve's convolution, the same bits for threads 1-4 and equal
    # to a direct sum; test_fft_radix: the FFT's fused radix-6 / radix-9
    # stages against a naive DFT; test_receptor_batch: the receptors' four-lane
    # path (AdvanceBatch) the same bits as Advance receptor by receptor;
    # test_exact_fma: the stress sums' fma without an FMA unit against std::fma
    for exe in (
        "test_layered",
        "test_membrane",
        "test_fft_threads",
        "test_fft_radix",
        "test_receptor_batch",
        "test_exact_fma",
    ):
        run = subprocess.run(
            [str(build_dir / "tests" / "cpp" / exe)], capture_output=True, text=True, timeout=300
        )
        assert run.returncode == 0, exe + ":\n" + run.stdout[-4000:]
        assert "PASS: 0 failure(s)" in run.stdout, exe
