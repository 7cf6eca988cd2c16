"""Texture generators and the height-field convention the skin relies on."""

import mujoco
import numpy as np
import pytest
from numpy.testing import assert_allclose

from mjtouch import core
from mjtouch.scene import scenes, textures


def test_hfield_orientation_matches_mujoco_ray():
    # An asymmetric height field: the skin's reading at (x, y) must equal the
    # height MuJoCo's own ray cast hits there (rows along y, columns along x).
    nrow, ncol = 7, 11
    rng = np.random.default_rng(3)
    data = rng.random((nrow, ncol))
    data[0, 0], data[-1, -1] = 0.0, 1.0  # MuJoCo normalises to [0, 1]
    rx, ry, hz = 0.01, 0.006, 0.002
    spec = mujoco.MjSpec()
    spec.add_hfield(
        name="h", nrow=nrow, ncol=ncol, size=[rx, ry, hz, 0.001], userdata=data.ravel().tolist()
    )
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname="h", pos=[0.1, -0.2, 0.3])
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    samples = m.hfield_data.reshape(nrow, ncol)
    geomid = np.array([-1], dtype=np.int32)
    for x, y in [(-0.007, 0.004), (0.003, -0.005), (0.0081, 0.0012), (-0.0099, -0.0059)]:
        dist = mujoco.mj_ray(
            m, d, np.array([0.1 + x, -0.2 + y, 1.0]), np.array([0, 0, -1.0]), None, 1, -1, geomid
        )
        ray_height = 1.0 - dist - 0.3
        ours = core.hfield_box_mean(samples, rx, ry, hz, x, x, y, y)
        # MuJoCo triangulates each cell (two planes); the skin's bilinear
        # interpolant agrees with it at the samples and differs inside a cell
        # by at most the cell's twist |h00 - h10 - h01 + h11| / 4.
        c = (x + rx) / (2 * rx) * (ncol - 1)
        r = (y + ry) / (2 * ry) * (nrow - 1)
        c0, r0 = min(int(c), ncol - 2), min(int(r), nrow - 2)
        twist = (
            abs(
                samples[r0, c0]
                - samples[r0, c0 + 1]
                - samples[r0 + 1, c0]
                + samples[r0 + 1, c0 + 1]
            )
            * hz
            / 4
        )
        assert abs(ours - ray_height) <= twist + 1e-9, (x, y, ours, ray_height)


def test_hfield_box_mean_is_exact_integral():
    rng = np.random.default_rng(0)
    s = rng.random((5, 9)).astype(np.float32)
    rx, ry, hz = 0.004, 0.002, 1e-3
    x0, x1, y0, y1 = -0.0031, 0.0017, -0.0013, 0.0009
    # fine midpoint quadrature of the bilinear interpolant
    n = 800
    xs = x0 + (np.arange(n) + 0.5) * (x1 - x0) / n
    ys = y0 + (np.arange(n) + 0.5) * (y1 - y0) / n
    cx = (xs + rx) / (2 * rx) * 8
    ry_ = (ys + ry) / (2 * ry) * 4
    c0 = np.minimum(cx.astype(int), 7)
    r0 = np.minimum(ry_.astype(int), 3)
    fx, fy = cx - c0, ry_ - r0
    S = s.astype(float)
    H = (1 - fy)[:, None] * ((1 - fx) * S[r0][:, c0] + fx * S[r0][:, c0 + 1]) + fy[:, None] * (
        (1 - fx) * S[r0 + 1][:, c0] + fx * S[r0 + 1][:, c0 + 1]
    )
    expect = hz * H.mean()
    # midpoint rule error ~ (1/n)^2 of the second derivative (piecewise
    # linear: kinks only) -> ~1e-6 relative here
    assert_allclose(core.hfield_box_mean(s, rx, ry, hz, x0, x1, y0, y1), expect, rtol=2e-5)


def test_grating_profile_geometry():
    x = np.linspace(-5e-3, 5e-3, 100001)
    h = textures.grating(x, 1e-3, 0.4e-3, 1e-4, edge_m=0.05e-3)
    assert h.max() == pytest.approx(1e-4) and h.min() == 0.0
    # duty cycle: the raised-cosine edge is symmetric about the nominal edge,
    # so the mean height is plateau / period exactly
    assert h.mean() / 1e-4 == pytest.approx(0.4, abs=2e-4)
    # periodic with period D
    assert_allclose(textures.grating(x + 1e-3, 1e-3, 0.4e-3, 1e-4, 0.05e-3), h, atol=1e-12)


def test_random_rough_rms_and_correlation_length():
    res, l, rms = 5e-6, 50e-6, 3e-6
    h = textures.random_rough(512, 512, res, rms, corr_length_m=l, seed=1)
    assert h.std() == pytest.approx(rms, rel=1e-12)
    # autocorrelation exp(-r^2 / l^2): at r = l it is 1/e (periodic estimate;
    # sampling error of a 512^2 map with ~50^2 correlation areas ~ a few %)
    F = np.fft.rfft2(h)
    acf = np.fft.irfft2(np.abs(F) ** 2, s=h.shape)
    acf /= acf[0, 0]
    k = int(round(l / res))
    assert acf[0, k] == pytest.approx(np.exp(-1), abs=0.05)
    assert acf[k, 0] == pytest.approx(np.exp(-1), abs=0.05)
    # deterministic per seed, different across seeds
    assert np.array_equal(h, textures.random_rough(512, 512, res, rms, corr_length_m=l, seed=1))
    assert not np.array_equal(h, textures.random_rough(512, 512, res, rms, corr_length_m=l, seed=2))


def test_dots_are_spherical_caps_on_a_lattice():
    x = np.linspace(-2e-3, 2e-3, 801)
    y = np.linspace(-2e-3, 2e-3, 801)
    h = textures.dots(x, y, 1e-3, 0.3e-3, 0.1e-3, lattice="square")
    assert h.max() == pytest.approx(1e-4, rel=1e-6)
    # fraction covered by dots: pi a^2 / spacing^2
    assert (h > 0).mean() == pytest.approx(np.pi * 0.3**2, abs=0.01)


def test_2d_texture_model_holds_the_heights():
    tex = scenes.Texture(
        kind="random",
        length_m=0.02,
        width_m=0.01,
        resolution_m=5e-5,
        rms_m=10e-6,
        corr_length_m=2e-4,
        seed=4,
    )
    m = scenes.build_model(scenes.Fingertip(nx=32, pitch_m=2e-4), tex, scenes.Protocol())
    h = tex.heights()
    assert (m.hfield_nrow[0], m.hfield_ncol[0]) == h.shape
    relief = h.max() - h.min()
    assert m.hfield_size[0][2] == pytest.approx(relief)
    assert_allclose(m.hfield_data.reshape(h.shape) * relief, h, atol=1e-7 * relief)


@pytest.mark.parametrize(
    "kw,msg",
    [
        (dict(kind="wood"), "not one of"),
        (dict(kind="random", rms_m=-1), "rms_m"),
        (dict(kind="grating", plateau_m=2e-3), "plateau_m"),
        (dict(kind="dots", dot_radius_m=0), "dot_radius_m"),
    ],
)
def test_bad_texture_parameters(kw, msg):
    with pytest.raises(ValueError, match=msg):
        scenes.Texture(**kw).validate()


def test_analytic_counter_surfaces_render_their_exact_tops():
    # Stage 1 against closed forms: a flat skin (z = 0, pad frame = world)
    # over each analytic body below it; the gap at a cell centre (point
    # sampling) is the distance down the pad's -z axis to the body's top.
    n, h = 33, 2e-4
    x = (np.arange(n) - (n - 1) / 2) * h
    X, Y = np.meshgrid(x, x)
    r2 = X**2 + Y**2
    R, d, hh = 2e-3, 1e-4, 1e-3  # radius, clearance, half length (capsule, cylinder)
    a, b, c = 2.5e-3, 1.5e-3, 1e-3  # ellipsoid semi-axes
    cases = {
        "sphere": (
            dict(pos=(0, 0, -R - d), size=(R, 0, 0)),
            R + d - np.sqrt(np.clip(R * R - r2, 0, None)),
            r2 < R * R,
        ),
        "capsule": (
            dict(pos=(0, 0, -R - hh - d), size=(R, hh, 0)),
            R + d - np.sqrt(np.clip(R * R - r2, 0, None)),
            r2 < R * R,
        ),
        "cylinder": (dict(pos=(0, 0, -hh - d), size=(R, hh, 0)), np.full_like(r2, d), r2 < R * R),
        "ellipsoid": (
            dict(pos=(0, 0, -c - d), size=(a, b, c)),
            c + d - c * np.sqrt(np.clip(1 - X**2 / a**2 - Y**2 / b**2, 0, None)),
            X**2 / a**2 + Y**2 / b**2 < 1,
        ),
    }
    for name, (surface, expect, inside) in cases.items():
        gap, cov = core.render_gap(
            np.zeros((n, n)), h, [dict(type=name, **surface)], area_average=False
        )
        # cells whose centre is off the body see no surface (centres exactly
        # on the rim graze it: left out)
        rim = np.isclose(
            r2 if name != "ellipsoid" else X**2 / a**2 + Y**2 / b**2,
            R * R if name != "ellipsoid" else 1.0,
            rtol=1e-9,
        )
        outside = ~inside & ~rim
        assert np.all(np.isinf(gap[outside])) and np.all(cov[outside] == 0), name
        np.testing.assert_allclose(gap[inside], expect[inside], rtol=0, atol=1e-12, err_msg=name)
        assert np.all(cov[inside] == 1), name
    # Area averaging: the 2 x 2 Gauss mean of a sphere's top over a cell; at
    # the pole the top is r^2 / 2R to leading order, whose cell mean exceeds
    # the centre value by h^2 / 12R: the averaged gap is larger by that.
    gap, _ = core.render_gap(
        np.zeros((n, n)), h, [dict(type="sphere", pos=(0, 0, -R - d), size=(R, 0, 0))]
    )
    assert gap[16, 16] - d == pytest.approx(h * h / (12 * R), rel=1e-2)
