"""Stage 3: homogeneous half-space kernel against closed forms and laws."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from mjtouch import core

XX, YY, ZZ, XY, XZ, YZ = range(6)


def boussinesq_polar(P, r, z, nu):
    """Johnson (1985) eq. 3.21 in polar form (REFERENCE section 3)."""
    rho = np.hypot(r, z)
    szz = -3 * P * z**3 / (2 * np.pi * rho**5)
    trz = -3 * P * r * z**2 / (2 * np.pi * rho**5)
    srr = P / (2 * np.pi) * ((1 - 2 * nu) / r**2 * (1 - z / rho) - 3 * z * r**2 / rho**5)
    stt = -P / (2 * np.pi) * (1 - 2 * nu) * (1 / r**2 * (1 - z / rho) - z / rho**3)
    return srr, stt, szz, trz


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.48, 0.5])
def test_point_force_matches_boussinesq_polar(nu):
    r = np.array([1e-4, 5e-4, 1e-3, 3e-3])
    z = np.array([2e-4, 7.5e-4, 1e-3, 2e-3])
    s = core.halfspace_stress(r, 0.0, z, "pressure", nu)  # on the +x axis: xx = rr, yy = tt
    srr, stt, szz, trz = boussinesq_polar(1.0, r, z, nu)
    assert_allclose(s[:, XX], srr, rtol=1e-12, atol=1e-9)
    assert_allclose(s[:, YY], stt, rtol=1e-12, atol=1e-9)
    assert_allclose(s[:, ZZ], szz, rtol=1e-12)
    assert_allclose(s[:, XZ], trz, rtol=1e-12)
    assert_allclose(s[:, [XY, YZ]], 0, atol=1e-12)


def test_point_force_on_axis_limit():
    z = 1e-3
    on = core.halfspace_stress(0.0, 0.0, z, "pressure", 0.3)
    near = core.halfspace_stress(1e-12, 0.0, z, "pressure", 0.3)
    assert_allclose(on, near, rtol=1e-6, atol=1e-8 * np.abs(on).max())
    assert_allclose(on[XX], (1 - 2 * 0.3) / (4 * np.pi * z**2), rtol=1e-12)


def test_cerruti_closed_forms():
    # Normal and shear components of Cerruti (REFERENCE section 3), Q = 1 N along +x.
    x, y, z = 3e-4, -2e-4, 5e-4
    rho = np.sqrt(x * x + y * y + z * z)
    s = core.halfspace_stress(x, y, z, "shear_x", 0.4)
    assert_allclose(s[ZZ], -3 * x * z**2 / (2 * np.pi * rho**5), rtol=1e-12)
    assert_allclose(s[XZ], -3 * x**2 * z / (2 * np.pi * rho**5), rtol=1e-12)
    assert_allclose(s[YZ], -3 * x * y * z / (2 * np.pi * rho**5), rtol=1e-12)
    # +y load is the +x load rotated by 90 degrees.
    sy = core.halfspace_stress(-y, x, z, "shear_y", 0.4)
    assert_allclose([sy[YY], sy[XX], sy[ZZ], sy[YZ]], [s[XX], s[YY], s[ZZ], s[XZ]], rtol=1e-12)


def divergence(load, nu, p, h=1e-7):
    """d s_ij / d x_j at point p by central differences (equilibrium: 0)."""
    x, y, z = p

    def S(dx, dy, dz):
        v = core.halfspace_stress(x + dx, y + dy, z + dz, load, nu)
        return np.array([[v[XX], v[XY], v[XZ]], [v[XY], v[YY], v[YZ]], [v[XZ], v[YZ], v[ZZ]]])

    d = [
        (S(h, 0, 0) - S(-h, 0, 0)) / (2 * h),
        (S(0, h, 0) - S(0, -h, 0)) / (2 * h),
        (S(0, 0, h) - S(0, 0, -h)) / (2 * h),
    ]
    return np.array([sum(d[j][i, j] for j in range(3)) for i in range(3)])


@pytest.mark.parametrize("load", ["pressure", "shear_x", "shear_y"])
@pytest.mark.parametrize("nu", [0.25, 0.5])
def test_equilibrium_everywhere(load, nu):
    # Each term of the divergence is ~ |s| / rho ~ 1 / (2 pi rho^3); central
    # differences with h = 1e-7 m leave ~1e-7 relative of that.
    for p in [(3e-4, 1e-4, 5e-4), (-1e-3, 4e-4, 2e-3), (2e-4, -6e-4, 3e-4)]:
        rho = np.linalg.norm(p)
        scale = 1 / (2 * np.pi * rho**3)
        assert np.max(np.abs(divergence(load, nu, p))) < 1e-5 * scale, (load, nu, p)


@pytest.mark.parametrize("load,comp", [("pressure", ZZ), ("shear_x", XZ), ("shear_y", YZ)])
def test_force_balance_on_every_plane(load, comp):
    # The traction on any plane z = const balances the applied 1 N load:
    # integral of s_zz (normal) or s_xz / s_yz (shear) over the plane = -1 N.
    # Tail beyond R: ~ (z/R)^3 for s_zz, ~ z/R for the shear integrands; use a
    # large disc in polar coordinates with Gauss-Legendre in log r.
    for z in [2e-4, 1e-3, 3e-3]:
        R = 4000 * z
        t, w = np.polynomial.legendre.leggauss(200)
        lr = 0.5 * (np.log(R) - np.log(1e-6 * z)) * t + 0.5 * (np.log(R) + np.log(1e-6 * z))
        r = np.exp(lr)
        wr = w * 0.5 * (np.log(R) - np.log(1e-6 * z)) * r
        th, wth = np.linspace(0, 2 * np.pi, 64, endpoint=False), np.full(64, 2 * np.pi / 64)
        Rr, Th = np.meshgrid(r, th, indexing="ij")
        s = core.halfspace_stress(Rr * np.cos(Th), Rr * np.sin(Th), z, load, 0.45)
        total = np.einsum("i,j,ij->", wr, wth, s[..., comp] * Rr)
        tail = 3 * z / R if load != "pressure" else (z / R) ** 3
        assert abs(total + 1.0) < 2 * tail + 1e-6, (load, z, total)


def love_corner(q, a, b, z):
    """s_zz under the corner of a uniformly loaded a x b rectangle (Love 1929;
    Johnson 1985 eq. 3.44 form), compressive negative."""
    R = np.sqrt(a * a + b * b + z * z)
    return (
        -q
        / (2 * np.pi)
        * (np.arctan(a * b / (z * R)) + a * b * z / R * (1 / (a * a + z * z) + 1 / (b * b + z * z)))
    )


@pytest.mark.parametrize(
    "x,y,z", [(0, 0, 5e-5), (0, 0, 3e-4), (1e-4, 5e-5, 2e-4), (3e-4, 0, 1e-4), (0, 0, 2e-3)]
)
def test_single_cell_matches_love_rectangle(x, y, z):
    # Uniform 1 Pa on a square cell of side h centred at the origin, by
    # superposing four corner solutions. The quadrature is adaptive, so it
    # must hold to ~1e-6 even for a receptor shallower than the cell.
    h = 1e-4

    def corner_sum(X, Y):
        tot = 0.0
        for ax in (h / 2 - X, h / 2 + X):
            for by in (h / 2 - Y, h / 2 + Y):
                sgn = np.sign(ax) * np.sign(by)
                tot += sgn * love_corner(1.0, abs(ax), abs(by), z)
        return tot

    s = core.halfspace_stress(x, y, z, "pressure", 0.3, cell_m=h)
    assert_allclose(s[ZZ], corner_sum(x, y), rtol=2e-6)


@pytest.mark.parametrize("z", [5e-4, 1e-3, 2e-3])
def test_single_cell_tends_to_boussinesq_at_depth(z):
    # A cell of side h carrying force h^2 differs from the point force by the
    # load's second moment: relative O((h/z)^2). For s_zz on the axis the
    # exact factor is 1 - (5/4)(h/z)^2 / ... ; bound it by (h/z)^2.
    h = 1e-4
    cell = core.halfspace_stress(0.0, 0.0, z, "pressure", 0.5, cell_m=h)
    point = core.halfspace_stress(0.0, 0.0, z, "pressure", 0.5) * h * h
    assert abs(cell[ZZ] / point[ZZ] - 1) < (h / z) ** 2
    assert abs(cell[ZZ] / point[ZZ] - 1) > 0.01 * (h / z) ** 2  # the cell is not a point


def test_uniform_disc_on_axis_from_field_stress():
    # Pressure q on a disc of radius a rendered on the taxel grid (cells fully
    # inside the disc get q, edge cells their exact-ish covered fraction by
    # 16x16 supersampling). On the axis s_zz = -q (1 - z^3 / (a^2 + z^2)^1.5).
    n, h, a, q = 96, 1e-4, 3e-3, 1e4
    c = (np.arange(n) - (n - 1) / 2) * h
    sub = (np.arange(16) + 0.5) / 16 - 0.5
    X = c[None, :, None, None] + sub[None, None, None, :] * h
    Y = c[:, None, None, None] + sub[None, None, :, None] * h
    frac = ((X**2 + Y**2) <= a * a).mean(axis=(2, 3))
    p = q * frac
    i0 = n // 2  # cell centre at +h/2: the disc is centred between cells
    for z in [3e-4, 7.5e-4, 2e-3]:
        s = core.field_stress(p, h, z, [[i0, i0]], poisson=0.5)[0]
        r_off = np.hypot(c[i0], c[i0])
        # exact s_zz at a point slightly off axis: superpose rings; use the
        # axis formula with the offset as a second-order correction bound.
        expect = -q * (1 - z**3 / (a * a + z * z) ** 1.5)
        # discretisation of the edge (area error ~ 2 pi a h / 16 / (pi a^2))
        # and the off-axis offset (r_off / a)^2 bound the difference.
        tol = 2 * h / (16 * a) + (r_off / a) ** 2 + 1e-3
        assert abs(s[ZZ] / expect - 1) < tol, (z, s[ZZ], expect)


def test_superposition_of_traction_fields(rng):
    n, h, z = 32, 1e-4, 4e-4
    p1, p2 = rng.random((n, n)), rng.random((n, n))
    q1 = rng.standard_normal((n, n))
    ij = [[3, 5], [16, 16], [30, 2]]
    a = core.field_stress(p1, h, z, ij, shear_x_pa=q1, poisson=0.45)
    b = core.field_stress(p2, h, z, ij, poisson=0.45)
    ab = core.field_stress(p1 + 2 * p2, h, z, ij, shear_x_pa=q1, poisson=0.45)
    # float32 tables and tractions: ~1e-6 relative per term
    assert_allclose(ab, a + 2 * b, rtol=1e-5, atol=1e-5 * np.abs(ab).max())
