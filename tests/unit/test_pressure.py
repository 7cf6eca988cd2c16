"""Stage 2 pressure models against analytic contact mechanics.

The `elastic` model's boundary-element solve (mjtouch.core.elastic_pressure,
the same C++ solver the plugin runs) against Hertz (non-periodic, DC-FFT)
and Westergaard (periodic); the half-space surface compliance against its
closed forms; exact load sums of every model.
"""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from mjtouch import core

E, NU = 8e4, 0.48  # skin (Shao et al. 2010 epidermis)
E_STAR = E / (1 - NU**2)


def test_compliance_centre_and_far_field():
    h, n = 1e-4, 41
    K = core.surface_compliance(n, h, E, NU)
    c = n - 1
    # Centre of a uniformly loaded square (Johnson, Contact Mechanics 3.25):
    # u = (4 / pi) ln(1 + sqrt 2) p h / E*.
    assert_allclose(K[c, c], 4 / math.pi * math.log(1 + math.sqrt(2)) * h / E_STAR, rtol=1e-6)
    # Far field: a point load h^2 p plus the square's second-moment
    # correction h^2 / (24 r^2); what is left is O((h/r)^4) ~ 1e-8, below
    # float32 storage (6e-8).
    for di, dj in [(20, 0), (15, 15), (7, 30), (40, 40)]:
        r = h * math.hypot(di, dj)
        point = h * h / (math.pi * E_STAR * r) * (1 + h * h / (24 * r * r))
        assert_allclose(K[c + dj, c + di], point, rtol=3e-7, err_msg=f"offset {di, dj}")
    # even in both offsets
    assert np.array_equal(K, K[::-1, :]) and np.array_equal(K, K[:, ::-1])


def _hertz_case(cells_per_radius: float, force: float = 0.5, R: float = 0.01):
    a = (3 * force * R / (4 * E_STAR)) ** (1 / 3)
    h = a / cells_per_radius
    n = 2 * int(math.ceil(1.4 * cells_per_radius)) + 1  # odd: a cell centred on the pole
    x = (np.arange(n) - (n - 1) / 2) * h
    X, Y = np.meshgrid(x, x)
    gap = (X**2 + Y**2) / (2 * R)  # paraboloid: Hertz's geometry
    p, info = core.elastic_pressure(gap, h, force, E, NU, tolerance=1e-10)
    return (
        p,
        info,
        dict(
            a=a, h=h, R=R, W=force, X=X, Y=Y, p0=3 * force / (2 * math.pi * a * a), delta=a * a / R
        ),
    )


def test_elastic_matches_hertz_at_32_cells_per_radius():
    p, info, H = _hertz_case(32)
    assert info["converged"], info
    # load: exact by construction of the solve (round-off only)
    assert_allclose(p.sum() * H["h"] ** 2, H["W"], rtol=1e-12)
    # 1e-3: the REFERENCE.md oracle for ~32 cells per contact radius
    # (piecewise-constant elements; the error falls as (h/a)^2 where p is
    # smooth and the edge's square-root tip dominates the rest).
    assert_allclose(info["approach_m"], H["delta"], rtol=1e-3, err_msg="load-indentation")
    assert_allclose(p.max(), H["p0"], rtol=1e-3, err_msg="peak pressure")
    # contact radius: p^2 = p0^2 (1 - r^2/a^2) is linear in r^2 inside the
    # contact; its zero is the radius (uses the whole field, not a count).
    r2 = (H["X"] ** 2 + H["Y"] ** 2).ravel()
    inner = r2 < (0.9 * H["a"]) ** 2
    slope, icpt = np.polyfit(r2[inner], p.ravel()[inner] ** 2, 1)
    assert_allclose(math.sqrt(-icpt / slope), H["a"], rtol=1e-3, err_msg="contact radius")
    # and nothing outside a (one cell of slack at the discrete edge)
    assert p.ravel()[r2 > (H["a"] + H["h"]) ** 2].max() == 0.0


def test_hertz_error_shrinks_with_resolution():
    # the discretisation error of the peak and the approach falls with h:
    # the check that the 1e-3 agreement is convergence, not luck.
    errs = []
    for cpr in (8, 16):
        p, info, H = _hertz_case(cpr)
        errs.append((abs(p.max() / H["p0"] - 1), abs(info["approach_m"] / H["delta"] - 1)))
    assert errs[1][0] < errs[0][0] and errs[1][1] < errs[0][1], errs


@pytest.mark.parametrize("fraction", [0.5, 1 / 3])
def test_elastic_periodic_westergaard_contact_fraction(fraction):
    # 1D wavy surface, amplitude D, wavelength L: full contact at
    # p* = pi E* D / L; at mean pressure pm the contact half-width a obeys
    # pm / p* = sin^2(pi a / L) (Westergaard 1939; Johnson 13.2), so
    # pm = p*/2 gives contact fraction 2a/L = 1/2.
    nx, ny, L, D = 512, 4, 1e-3, 2e-6
    h = L / nx
    p_star = math.pi * E_STAR * D / L
    pm = p_star * math.sin(math.pi * fraction / 2) ** 2
    x = (np.arange(nx) + 0.5) * h
    gap = np.tile(D * (1 - np.cos(2 * math.pi * x / L)), (ny, 1))
    force = pm * (nx * h) * (ny * h)
    p, info = core.elastic_pressure(gap, h, force, E, NU, periodic=True, tolerance=1e-10)
    assert info["converged"], info
    measured = (p[0] > 0).mean()
    # 1%: the bound; the cell count quantises the fraction by
    # 2 / nx = 0.4%.
    assert abs(measured / fraction - 1) < 0.01, (measured, fraction)
    # Westergaard's peak pressure: pm / sin^2(pi a / L) * ... at x = 0:
    # p(0) = 2 pm sin(pi a / L) / sin^2(pi a / L) = 2 pm / sin(pi a / L).
    s = math.sin(math.pi * fraction / 2)
    assert_allclose(p.max(), 2 * pm / s, rtol=5e-3)
    assert np.all(p == p[:1])  # uniform along y


def test_elastic_warm_start_reaches_same_solution():
    # a warm start changes the path, not the answer (to the tolerance)
    p_cold, info_cold, H = _hertz_case(12)
    guess = np.sqrt(np.clip(H["delta"] / 2 - (H["X"] ** 2 + H["Y"] ** 2) / (2 * H["R"]), 0, None))
    gap = (H["X"] ** 2 + H["Y"] ** 2) / (2 * H["R"])
    p_warm, info_warm = core.elastic_pressure(
        gap, H["h"], H["W"], E, NU, tolerance=1e-10, initial_pa=guess
    )
    assert info_warm["iterations"] < info_cold["iterations"]
    assert_allclose(p_warm, p_cold, atol=1e-6 * p_cold.max())


def test_elastic_rejects_bad_arguments():
    g = np.zeros((8, 8))
    with pytest.raises(ValueError, match="square"):
        core.elastic_pressure(np.zeros((8, 6)), 1e-4, 1.0, E, NU)
    with pytest.raises(ValueError, match="products of 2, 3 and 5"):
        core.elastic_pressure(np.zeros((7, 7)), 1e-4, 1.0, E, NU, periodic=True)
    with pytest.raises(ValueError, match="carry the load"):
        core.elastic_pressure(np.full((8, 8), np.inf), 1e-4, 1.0, E, NU)
    with pytest.raises(ValueError, match="invalid arguments"):
        core.elastic_pressure(g, -1e-4, 1.0, E, NU)


def test_elastic_solver_on_layered_compliance_tables():
    # Identical layers over a half-space of the same material are that
    # half-space: the solver on the layered skin's compliance table must give
    # the closed-form half-space's contact (the table's radial route is
    # accurate to ~1e-6 of its peak, far below the 1e-4 tolerance).
    n, h = 48, 0.1e-3
    x = (np.arange(n) - (n - 1) / 2) * h
    X, Y = np.meshgrid(x, x)
    gap = (X**2 + Y**2) / (2 * 0.05)
    same = core.LayeredSkin([(1e-3, 80e3, 0.48), (2e-3, 80e3, 0.48)], (80e3, 0.48))
    p_ref, st_ref = core.elastic_pressure(gap, h, 0.05, 80e3, 0.48, tolerance=1e-10)
    p, st = core.elastic_pressure(
        gap, h, 0.05, tolerance=1e-10, compliance_m_per_pa=same.compliance_table(h, n)
    )
    np.testing.assert_allclose(p, p_ref, atol=1e-4 * p_ref.max())
    assert st["approach_m"] == pytest.approx(st_ref["approach_m"], rel=1e-4)
    # Stiffening any material can only reduce the indentation under a set
    # load: the Shao skin (every layer at least 24 kPa and nu 0.4, over rigid
    # bone) indents less than a half-space of its softest layer.
    shao = core.LayeredSkin()
    _, st_shao = core.elastic_pressure(
        gap, h, 0.05, tolerance=1e-10, compliance_m_per_pa=shao.compliance_table(h, n)
    )
    _, st_soft = core.elastic_pressure(gap, h, 0.05, 24e3, 0.4, tolerance=1e-10)
    assert 0 < st_shao["approach_m"] < st_soft["approach_m"]
    with pytest.raises(ValueError, match="compliance_m_per_pa must be a finite"):
        core.elastic_pressure(gap, h, 0.05, compliance_m_per_pa=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="either compliance_m_per_pa or young_pa"):
        core.elastic_pressure(
            gap, h, 0.05, 80e3, 0.48, compliance_m_per_pa=same.compliance_table(h, n)
        )


def test_shear_tractions_sum_to_mujocos_tangential_force():
    # Full-slip shear (q = p F_t / F_n) and contact splats carry MuJoCo's
    # forces exactly: sum(q A) is the tangential force, sum(p A) the normal
    # one, to double round-off.
    rng = np.random.default_rng(3)
    n, h = 40, 1.5e-4
    p = np.clip(rng.normal(1e4, 5e3, (n, n)), 0, None)
    fn = p.sum() * h * h
    qx, qy = core.slip_shear(p, h, fn, (-0.31 * fn, 0.12 * fn))
    assert qx.sum() * h * h == pytest.approx(-0.31 * fn, rel=1e-12)
    assert qy.sum() * h * h == pytest.approx(0.12 * fn, rel=1e-12)
    contacts = np.c_[
        rng.uniform(-2e-3, 2e-3, (5, 2)), rng.normal(0, 0.1, (5, 2)), rng.uniform(0.05, 0.2, 5)
    ]
    ps, sx, sy = core.splat_contacts(contacts, n, h)
    total = contacts[:, 2:].sum(axis=0)
    assert [sx.sum() * h * h, sy.sum() * h * h, ps.sum() * h * h] == pytest.approx(
        list(total), rel=1e-12
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_winkler_fast_solve_matches_reference_bit_for_bit(seed):
    # The fast solve (passes restricted to the cells below the first Newton
    # point, the load normalised over the touching cells) must give the
    # reference solve's pressure and approach exactly, cold or warm-started
    # from either side of the root, and carry the load (sum p A = F).
    rng = np.random.default_rng(seed)
    n, h, k, force = 40, 1e-4, 1e9, 0.3
    c = (np.arange(n) - (n - 1) / 2) * h
    X, Y = np.meshgrid(c, c)
    gap = (X**2 + Y**2) / (2 * 5e-3) + 2e-6 * rng.standard_normal((n, n))
    cov = np.where(rng.random((n, n)) < 0.1, rng.random((n, n)), 1.0)
    cov[rng.random((n, n)) < 0.05] = 0.0
    gap[rng.random((n, n)) < 0.02] = np.inf
    p_ref, a_ref = core.winkler_pressure(gap, h, k, force, cov, reference=True)
    assert_allclose(p_ref.sum() * h * h, force, rtol=1e-6)
    assert np.count_nonzero(p_ref) > 50
    for guess in (math.nan, a_ref, a_ref + 1e-7, a_ref + 2e-5, a_ref - 1e-7, 1.0):
        runs = [
            core.winkler_pressure(gap, h, k, force, cov, approach_guess_m=guess, reference=ref)
            for ref in (True, False)
        ]
        (p0, a0), (p1, a1) = runs
        assert a0 == a1 == a_ref, f"approach differs with guess {guess}"
        assert p0.tobytes() == p1.tobytes() == p_ref.tobytes(), (
            f"pressure differs with guess {guess}"
        )
