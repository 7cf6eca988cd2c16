"""Partial slip (mjtouch.tangential) against Cattaneo-Mindlin, CONTACT's example,
the Winkler counterpart and Mindlin-Deresiewicz unloading.

Grids: the contact radius a spans 32 cells (40 for CONTACT's example); the
stick radius is read from the stick map's area, c = sqrt(N_stick h^2 / pi)."""

import numpy as np
import pytest

from mjtouch import tangential as tg

A_M = 1e-3


def hertz(n, per_radius, fn=9.1954):
    """Hertz pressure of force fn (N) on radius A_M at the cell centres."""
    h = A_M / per_radius
    x = (np.arange(n) - (n - 1) / 2) * h
    X, Y = np.meshgrid(x, x)
    r2 = X * X + Y * Y
    p0 = 3 * fn / (2 * np.pi * A_M**2)
    p = np.where(r2 < A_M**2, p0 * np.sqrt(np.clip(1 - r2 / A_M**2, 0, None)), 0.0)
    return h, np.sqrt(r2), p, p0


def cattaneo(r, p0, mu, c):
    """Cattaneo's traction magnitude at radius r for stick radius c."""
    return (
        mu
        * p0
        / A_M
        * (np.sqrt(np.clip(A_M**2 - r * r, 0, None)) - np.sqrt(np.clip(c * c - r * r, 0, None)))
    )


def stick_radius(result, h):
    return np.sqrt(result["stick"].sum() * h * h / np.pi)


def half_space(n, h, shear_modulus_pa, nu):
    return tg.ElasticPartialSlip(n, h, 2 * shear_modulus_pa * (1 + nu), nu)


@pytest.mark.parametrize("nu", [0.0, 0.42])
@pytest.mark.parametrize("ratio", [0.2, 0.6, 0.98])
def test_cattaneo_mindlin_half_space(nu, ratio):
    n, per = 80, 32
    h, r, p, p0 = hertz(n, per)
    G, mu = 100e6, 0.5
    P = p.sum() * h * h
    Q = ratio * mu * P
    res, _ = half_space(n, h, G, nu).solve(
        p, mu, (Q, 0.0), tolerance=1e-8, max_iterations=500, precision="double"
    )
    c = A_M * (1 - ratio) ** (1 / 3)
    # The stick edge runs through cells: c to within half a cell.
    assert stick_radius(res, h) == pytest.approx(c, abs=0.5 * h)
    # Rigid plate on one elastic body (Johnson eq. 7.42 with G2 = inf).
    shift = 3 * mu * P * (2 - nu) / (16 * G * A_M) * (1 - (1 - ratio) ** (2 / 3))
    assert res["shift_x_m"] == pytest.approx(shift, rel=5e-3)
    # Traction magnitude within 2% of mu p0 away from the stick edge, where
    # Cattaneo's profile has an infinite slope, and from the rim (1.5 cells);
    # Mindlin's q neglects the small y slip nu causes, the magnitude not.
    q = np.hypot(res["shear_x_pa"], res["shear_y_pa"])
    err = np.abs(q - cattaneo(r, p0, mu, c)) / (mu * p0)
    away = (np.abs(r - c) > 1.5 * h) & (r < A_M - 1.5 * h)
    assert err[away].max() < 0.02
    assert np.sqrt(np.mean(err[p > 0] ** 2)) < 0.01
    if nu == 0.0:  # no x-y coupling: Cattaneo's traction is exactly along x
        assert np.abs(res["shear_y_pa"]).max() == 0.0
    # Coulomb: |q| <= mu p everywhere, = mu p on slip cells.
    slip = (p > 0) & (res["stick"] == 0)
    assert np.all(q <= mu * p * (1 + 1e-12))
    np.testing.assert_allclose(q[slip], mu * p[slip], rtol=1e-12)


@pytest.mark.parametrize("precision, tolerance", [("double", 1e-8), ("float", 1e-4)])
def test_contact_cattaneo_example(precision, tolerance):
    # CONTACT's example: two identical bodies G 200 N/mm^2, nu 0.42; here one
    # half-space of G 100 N/mm^2 on a rigid plate has the same compliance.
    n, per = 96, 40
    h, r, p, p0 = hertz(n, per, fn=9.1954)
    P = p.sum() * h * h
    res, _ = half_space(n, h, 100e6, 0.42).solve(
        p,
        0.4,
        (3.218 * P / 9.1954, 0.0),
        tolerance=tolerance,
        max_iterations=500,
        precision=precision,
    )
    assert stick_radius(res, h) == pytest.approx(0.5e-3, abs=0.5 * h)
    # CONTACT 0.008155 mm, the formula 0.008171 mm: the grid (40 cells per
    # radius) moves the shift by < 0.3% (measured 32-64 cells per radius).
    assert res["shift_x_m"] == pytest.approx(8.171e-6, rel=5e-3)
    assert res["shift_x_m"] == pytest.approx(8.155e-6, rel=5e-3)


def parabolic(n, per, p0=1e5):
    h = A_M / per
    x = (np.arange(n) - (n - 1) / 2) * h
    X, Y = np.meshgrid(x, x)
    r = np.hypot(X, Y)
    return h, r, np.where(r < A_M, p0 * (1 - (r / A_M) ** 2), 0.0), p0


@pytest.mark.parametrize("ratio", [0.1, 0.5, 0.9])
def test_winkler_stick_radius(ratio):
    n, per, mu, k = 96, 40, 0.5, 1e7
    h, r, p, p0 = parabolic(n, per)
    P = p.sum() * h * h
    res, _ = tg.winkler_partial_slip(p, h, mu, (ratio * mu * P, 0.0), k)
    c = A_M * (1 - ratio) ** 0.25
    assert stick_radius(res, h) == pytest.approx(c, abs=0.5 * h)
    # Stick: q = k_t shift = mu p(c); the discrete c sits within a cell.
    shift = mu * p0 * (1 - (c / A_M) ** 2) / k
    assert res["shift_x_m"] == pytest.approx(shift, rel=0.02)
    stick = res["stick"] == 1
    np.testing.assert_allclose(res["shear_x_pa"][stick], k * res["shift_x_m"], rtol=1e-9)


def test_force_balance_oblique():
    n, per = 80, 32
    h, r, p, p0 = hertz(n, per)
    P = p.sum() * h * h
    F = (0.2 * P, -0.15 * P)
    for res, _ in (
        tg.winkler_partial_slip(p, h, 0.5, F, 1e7),
        half_space(n, h, 100e6, 0.45).solve(p, 0.5, F, tolerance=1e-4),
    ):
        assert 0 < res["stuck_share"] < 1
        np.testing.assert_allclose(res["shear_x_pa"].sum() * h * h, F[0], rtol=1e-12)
        np.testing.assert_allclose(res["shear_y_pa"].sum() * h * h, F[1], rtol=1e-12)


def test_mindlin_deresiewicz_unloading():
    n, per, mu, G, nu = 80, 32, 0.5, 100e6, 0.0
    h, r, p, p0 = hertz(n, per)
    P = p.sum() * h * h
    solver = half_space(n, h, G, nu)
    q_star, dq = 0.7 * mu * P, 0.6 * mu * P
    _, state = solver.solve(
        p, mu, (q_star, 0.0), tolerance=1e-8, max_iterations=500, precision="double"
    )
    res, _ = solver.solve(
        p,
        mu,
        (q_star - dq, 0.0),
        state=state,
        tolerance=1e-8,
        max_iterations=500,
        precision="double",
    )
    c = A_M * (1 - q_star / (mu * P)) ** (1 / 3)
    b = A_M * (1 - dq / (2 * mu * P)) ** (1 / 3)
    # Johnson 1985 sec. 7.2: stick inside b, reversed slip in b < r < a.
    assert stick_radius(res, h) == pytest.approx(b, abs=0.5 * h)
    slip = (p > 0) & (res["stick"] == 0)
    assert np.all(res["shear_x_pa"][slip] < 0)
    expected = cattaneo(r, p0, mu, c) - 2 * cattaneo(r, p0, mu, b)
    err = np.abs(res["shear_x_pa"] - expected) / (mu * p0)
    away = (np.abs(r - c) > 1.5 * h) & (np.abs(r - b) > 1.5 * h) & (r < A_M - 1.5 * h)
    assert err[away].max() < 0.02
    # Without memory the same force gives Cattaneo's loading profile instead.
    fresh, _ = solver.solve(
        p, mu, (q_star - dq, 0.0), tolerance=1e-8, max_iterations=500, precision="double"
    )
    assert np.all(fresh["shear_x_pa"][p > 0] >= 0)


def test_oblique_ramp_converges_and_the_default_tolerance_tracks_it():
    """A warm-started oblique ramp (the slip directions turn with nu's x-y
    coupling): a tight solve reaches its tolerance within the iteration cap at
    every step, and the default solve (1e-4, float) stays within 1% of it in
    traction RMS (its stop is a relative change of 1e-4 per step; the
    remainder of the increment left by the CG scales with it)."""
    n, per, mu, G, nu = 64, 20, 0.5, 100e6, 0.45
    h, r, p, p0 = hertz(n, per)
    P = p.sum() * h * h
    solver = half_space(n, h, G, nu)
    tight_state = loose_state = None
    for k in range(1, 13):
        F = (0.07 * k * mu * P, 0.03 * k * mu * P)
        tight, tight_state = solver.solve(
            p, mu, F, state=tight_state, tolerance=1e-10, max_iterations=500, precision="double"
        )
        assert tight["iterations"] < 500 and tight["change"] < 1e-10, (k, tight["iterations"])
        loose, loose_state = solver.solve(p, mu, F, state=loose_state, tolerance=1e-4)
        dq2 = (loose["shear_x_pa"] - tight["shear_x_pa"]) ** 2 + (
            loose["shear_y_pa"] - tight["shear_y_pa"]
        ) ** 2
        rms = np.sqrt(dq2.sum() / (tight["shear_x_pa"] ** 2 + tight["shear_y_pa"] ** 2).sum())
        assert rms < 0.01, (k, rms)
    q = np.hypot(tight["shear_x_pa"], tight["shear_y_pa"])
    assert np.all(q <= mu * p * (1 + 1e-12))
    assert 0 < tight["stuck_share"] < 1


@pytest.mark.parametrize("model", ["winkler", "elastic"])
@pytest.mark.parametrize("ratio", [1.0, 1.3])
def test_full_slip(model, ratio):
    n, per, mu = 64, 24, 0.4
    h, r, p, p0 = hertz(n, per)
    P = p.sum() * h * h
    F = (ratio * mu * P * 0.6, ratio * mu * P * 0.8)
    if model == "winkler":
        res, _ = tg.winkler_partial_slip(p, h, mu, F, 1e7)
    else:
        res, _ = half_space(n, h, 100e6, 0.45).solve(p, mu, F)
    assert res["full_slip"] and res["stick_cells"] == 0 and res["stuck_share"] == 0
    # q = p F / P: mu p along F at |F| = mu P.
    np.testing.assert_allclose(res["shear_x_pa"], p * F[0] / P, rtol=1e-12, atol=0)
    np.testing.assert_allclose(res["shear_y_pa"], p * F[1] / P, rtol=1e-12, atol=0)
    if ratio == 1.0:
        np.testing.assert_allclose(
            np.hypot(res["shear_x_pa"], res["shear_y_pa"]), mu * p, rtol=1e-12
        )


def test_deterministic():
    n, per = 64, 24
    h, r, p, p0 = hertz(n, per)
    P = p.sum() * h * h
    solver = half_space(n, h, 100e6, 0.45)
    F1, F2 = (0.2 * P, 0.05 * P), (0.1 * P, -0.02 * P)
    runs = []
    for _ in range(2):
        a1, s1 = solver.solve(p, 0.5, F1)
        a2, _ = solver.solve(p * 0.9, 0.5, F2, state=s1)
        w1, ws = tg.winkler_partial_slip(p, h, 0.5, F1, 1e7)
        w2, _ = tg.winkler_partial_slip(p, h, 0.5, F2, 1e7, state=ws)
        runs.append(
            [
                a2["shear_x_pa"],
                a2["shear_y_pa"],
                a2["stick"],
                np.array([a2["shift_x_m"]]),
                w2["shear_x_pa"],
                w2["shear_y_pa"],
                np.array([w2["shift_y_m"]]),
            ]
        )
    for x, y in zip(*runs):
        assert x.tobytes() == y.tobytes()


def test_bad_input():
    h, r, p, p0 = hertz(16, 4)
    with pytest.raises(ValueError, match="friction mu = -0.1 must be finite, >= 0"):
        tg.winkler_partial_slip(p, h, -0.1, (0.1, 0.0), 1e7)
    with pytest.raises(ValueError, match="tangential stiffness 0 Pa/m must be > 0"):
        tg.winkler_partial_slip(p, h, 0.5, (0.1, 0.0), 0.0)
    with pytest.raises(ValueError, match="pressure_pa must be finite and >= 0"):
        tg.winkler_partial_slip(-p, h, 0.5, (0.1, 0.0), 1e7)
    with pytest.raises(ValueError, match="poisson = 0.6 must be in"):
        tg.ElasticPartialSlip(16, h, 1e5, 0.6)
    with pytest.raises(ValueError, match="give both shear_x_pa and shear_y_pa"):
        tg.winkler_partial_slip(p, h, 0.5, (0.1, 0.0), 1e7, state=tg.TangentialState(shear_x_pa=p))


def test_rough_contact_against_tamaas():
    # Tamaas's PolonskyKeerTan (periodic, coupled normal-tangential; no
    # coupling at nu 0.5) on a rough sphere in a window 4x the contact: its
    # pressure and mean traction in, our tractions against its. The periodic
    # images and its stalled residual (~3e-6) leave ~1% differences.
    import tamaas as tm

    n, L, E, nu, mu = 64, 12.8e-3, 8e4, 0.5, 0.5
    h = L / n
    x = (np.arange(n) - (n - 1) / 2) * h
    X, Y = np.meshgrid(x, x, indexing="ij")
    rng = np.random.default_rng(3)
    k2 = np.fft.fftfreq(n)[:, None] ** 2 + np.fft.fftfreq(n)[None, :] ** 2
    noise = np.real(
        np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n))) * np.exp(-k2 / (2 * 0.06**2)))
    )
    surface = -(X**2 + Y**2) / (2 * 0.01) + noise * (3e-6 / noise.std())
    model = tm.ModelFactory.createModel(tm.model_type.surface_2d, [L, L], [n, n])
    model.E, model.nu = E, nu
    solver = tm.PolonskyKeerTan(model, surface, 1e-12, mu)
    solver.max_iter = 300
    solver.solve([0.3 * mu * 0.5 / L**2, 0.0, 0.3 / L**2])
    t = np.array(model.traction).transpose(1, 0, 2)  # tamaas [i, j] -> ours [j, i]
    p, qx, qy = t[..., 2].copy(), t[..., 0], t[..., 1]
    res, _ = tg.ElasticPartialSlip(n, h, E, nu).solve(
        p,
        mu,
        (qx.sum() * h * h, qy.sum() * h * h),
        tolerance=1e-8,
        max_iterations=3000,
        precision="double",
    )
    load = p > 0
    diff = np.hypot(res["shear_x_pa"] - qx, res["shear_y_pa"] - qy)
    assert diff.sum() / np.hypot(qx, qy).sum() < 0.04
    tamaas_stick = load & (np.hypot(qx, qy) < mu * p * (1 - 1e-6))
    assert res["stick_cells"] == pytest.approx(tamaas_stick.sum(), rel=0.03)
    assert (tamaas_stick == (res["stick"] == 1))[load].mean() > 0.98


def test_winkler_unloading_superposition():
    # Local springs superpose exactly: unloading Q* -> Q* - dQ gives
    # q(Q*) - 2 q(dQ/2) and stick radius b/a = (1 - dQ/(2 mu P))^(1/4).
    n, per, mu, k = 96, 40, 0.5, 1e7
    h, r, p, p0 = parabolic(n, per)
    P = p.sum() * h * h
    q_star, dq = 0.7 * mu * P, 0.6 * mu * P
    loaded, state = tg.winkler_partial_slip(p, h, mu, (q_star, 0.0), k)
    res, _ = tg.winkler_partial_slip(p, h, mu, (q_star - dq, 0.0), k, state=state)
    half, _ = tg.winkler_partial_slip(p, h, mu, (dq / 2, 0.0), k)
    b = A_M * (1 - dq / (2 * mu * P)) ** 0.25
    assert stick_radius(res, h) == pytest.approx(b, abs=0.5 * h)
    np.testing.assert_allclose(
        res["shear_x_pa"],
        loaded["shear_x_pa"] - 2 * half["shear_x_pa"],
        rtol=0,
        atol=1e-9 * mu * p0,
    )
    assert res["shift_x_m"] == pytest.approx(loaded["shift_x_m"] - 2 * half["shift_x_m"], rel=1e-9)
