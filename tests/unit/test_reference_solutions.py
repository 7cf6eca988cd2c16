"""The reference solutions against laws they must obey, computed here by
other routes (numerical integration, closed forms of limiting cases)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from mjtouch.analysis.reference_solutions import Hertz, hertz_errors, layered

SHAO = [(0.7e-3, 80e3, 0.48), (0.8e-3, 50e3, 0.48), (2.5e-3, 24e3, 0.4)]


def _hertz_field(h: Hertz, n: int, pitch_m: float) -> np.ndarray:
    """Hertz pressure sampled at cell centres of an n x n centred grid."""
    x = (np.arange(n) - (n - 1) / 2) * pitch_m
    X, Y = np.meshgrid(x, x)
    r2 = (X**2 + Y**2) / h.contact_radius_m**2
    return h.peak_pa * np.sqrt(np.clip(1 - r2, 0, None))


def test_hertz_pressure_integrates_to_the_load():
    h = Hertz(load_n=0.5, radius_m=0.01, young_pa=50e3, poisson=0.45)
    a = h.contact_radius_m
    r = np.linspace(0, a, 200_001)
    p = h.peak_pa * np.sqrt(1 - (r / a) ** 2)
    load = np.trapezoid(2 * np.pi * r * p, r)
    assert_allclose(load, h.load_n, rtol=1e-6, err_msg="int p dA != W")
    # E* a^3 = 3 W R / 4, indentation a^2 / R (Johnson 1985, eq. 4.22-4.23)
    assert_allclose(4 * h.e_star_pa * a**3 / (3 * h.radius_m), h.load_n, rtol=1e-12)
    assert_allclose(h.indentation_m * h.radius_m, a**2, rtol=1e-12)


def test_hertz_scaling_laws():
    base = Hertz(load_n=0.5, radius_m=0.01, young_pa=50e3, poisson=0.45)
    eight = Hertz(load_n=4.0, radius_m=0.01, young_pa=50e3, poisson=0.45)
    # a ~ W^(1/3), p0 ~ W^(1/3), delta ~ W^(2/3)
    assert_allclose(eight.contact_radius_m / base.contact_radius_m, 2.0, rtol=1e-12)
    assert_allclose(eight.peak_pa / base.peak_pa, 2.0, rtol=1e-12)
    assert_allclose(eight.indentation_m / base.indentation_m, 4.0, rtol=1e-12)


@pytest.mark.parametrize("cells_per_radius", [16, 64])
def test_hertz_errors_vanish_on_the_sampled_solution(cells_per_radius):
    h = Hertz(load_n=0.5, radius_m=0.01, young_pa=50e3, poisson=0.45)
    pitch = h.contact_radius_m / cells_per_radius
    n = 4 * cells_per_radius
    err = hertz_errors(h, _hertz_field(h, n, pitch), pitch, h.indentation_m)
    assert err["indentation"] == 0.0
    # an even grid has no cell at the centre: the highest samples sit at
    # r^2 = 2 (pitch / 2)^2, so the peak reads sqrt(1 - pitch^2 / (2 a^2));
    # the radius (second moment) converges as the edge cells shrink
    assert_allclose(err["peak"], math.sqrt(1 - 0.5 / cells_per_radius**2) - 1, rtol=1e-9)
    assert abs(err["radius"]) < 0.5 / cells_per_radius**1.5
    # a field 10% too strong reads as a 10% peak error, the radius unchanged
    more = hertz_errors(h, 1.1 * _hertz_field(h, n, pitch), pitch, h.indentation_m)
    assert_allclose(more["peak"], 1.1 * (1 + err["peak"]) - 1, rtol=1e-12)
    assert_allclose(more["radius"], err["radius"], rtol=1e-9)


@pytest.mark.parametrize("z", [0.2e-3, 0.3e-3, 1.5e-3])
def test_layered_homogeneous_stack_is_the_half_space(z):
    # identical layers over a half-space of the same material: the uniform
    # disc's axial stress s_zz = -q [1 - z^3 / (a^2 + z^2)^(3/2)] (Johnson 3.3)
    nu, young, a = 0.45, 50e3, 1e-3
    layers = [(0.3e-3, young, nu), (0.9e-3, young, nu)]
    closed = -(1 - z**3 / (a * a + z * z) ** 1.5)
    s = layered.disc_stress("pressure", 0.0, 0.0, z, a, layers, (young, nu))
    hankel = layered.disc_pressure_axisym(0.0, z, a, layers, (young, nu))
    assert_allclose(s[2], closed, atol=1e-8, err_msg="Fourier route")
    assert_allclose(hankel[2], closed, atol=1e-8, err_msg="Hankel route")


def test_layered_fourier_and_hankel_routes_agree_off_axis():
    # Shao's three layers on bone; at y = 0, s_xx is s_rr and s_xz is s_rz
    s = layered.disc_stress("pressure", 0.8e-3, 0.0, 0.7e-3, 1e-3, SHAO, None)
    h = layered.disc_pressure_axisym(0.8e-3, 0.7e-3, 1e-3, SHAO, None)
    assert_allclose([s[0], s[1], s[2], s[4]], h, atol=1e-8)


@pytest.mark.parametrize("nu", [0.3, 0.49])
def test_layered_layer_on_bone_compliance(nu):
    # one layer bonded to a rigid base under a pressure wave: closed-form
    # surface compliance (Carbone & Mangialardi 2008, J. Mech. Phys. Solids 56:684)
    young, thickness = 50e3, 1.5e-3
    kh = np.array([0.1, 1.0, 5.0, 20.0])
    k3 = 3 - 4 * nu
    closed = (
        2
        * (1 - nu * nu)
        / (young * kh / thickness)
        * (k3 * np.sinh(2 * kh) - 2 * kh)
        / (k3 * np.cosh(2 * kh) + 2 * kh**2 + 5 - 12 * nu + 8 * nu * nu)
    )
    got = layered.surface_compliance(kh / thickness, [(thickness, young, nu)], None)
    assert_allclose(got, closed, rtol=1e-10)
    # thick-layer limit: the half-space's 2 (1 - nu^2) / (E k)
    deep = layered.surface_compliance(np.array([50.0 / thickness]), [(thickness, young, nu)], None)
    assert_allclose(deep, 2 * (1 - nu**2) / (young * 50.0 / thickness), rtol=1e-12)


def test_layered_self_check_passes(capsys):
    assert layered._self_check()
    assert capsys.readouterr().out.rstrip().endswith("PASS")


def test_pressure_stress_does_not_depend_on_young_modulus():
    # under prescribed pressure a homogeneous half-space's stress depends on
    # nu only (REFERENCE.md sec. 2): scaling E changes nothing
    soft = layered.disc_stress(
        "pressure", 0.5e-3, 0.2e-3, 0.7e-3, 1e-3, [(1e-3, 20e3, 0.45)], (20e3, 0.45)
    )
    stiff = layered.disc_stress(
        "pressure", 0.5e-3, 0.2e-3, 0.7e-3, 1e-3, [(1e-3, 2e6, 0.45)], (2e6, 0.45)
    )
    assert_allclose(soft, stiff, rtol=1e-9, atol=1e-12)
    assert math.isfinite(float(np.sum(soft)))
