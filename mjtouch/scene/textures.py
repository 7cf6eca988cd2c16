"""Plate textures as height maps (numpy), for MuJoCo height fields.

Every generator returns heights in metres on a regular grid
(``nrow x ncol``; row r at y = -W/2 + W r / (nrow - 1), column c at
x = -L/2 + L c / (ncol - 1), MuJoCo's height-field convention) and is
deterministic for a given seed.

- :func:`grating`: raised plateaux along x (period D, plateau width, height,
  raised-cosine edges of a given half-width).
- :func:`random_rough`: isotropic Gaussian random surface with a given RMS
  height and either a Gaussian autocorrelation (correlation length) or a
  self-affine power spectrum (Hurst exponent between roll-off and cut-off
  wavelengths), made by filtering white noise in Fourier space.
- :func:`dots`: a square or hexagonal array of raised round dots (spherical
  caps).
- :func:`from_mesh`: the top surface of a mesh file (STL, OBJ, PLY, GLB, ...
  through trimesh) as exact cell means (:mod:`mjtouch.meshes`).
"""

from __future__ import annotations

import math

import numpy as np


def _check_positive(**kw) -> None:
    for k, v in kw.items():
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{k} = {v!r} must be a positive finite number")


def grid(length_m: float, width_m: float, resolution_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Sample coordinates (x of ncol columns, y of nrow rows)."""
    _check_positive(length_m=length_m, width_m=width_m, resolution_m=resolution_m)
    ncol = int(round(length_m / resolution_m)) + 1
    nrow = int(round(width_m / resolution_m)) + 1
    return (np.linspace(-length_m / 2, length_m / 2, ncol),
            np.linspace(-width_m / 2, width_m / 2, nrow))


def grating(x_m: np.ndarray, period_m: float, plateau_m: float, height_m: float,
            edge_m: float = 0.0) -> np.ndarray:
    """Height along x of plateaux centred on x = k * period."""
    _check_positive(period_m=period_m, plateau_m=plateau_m, height_m=height_m)
    if not plateau_m < period_m:
        raise ValueError(f"plateau_m = {plateau_m} must be < period_m = {period_m}")
    if not 0 <= edge_m <= min(plateau_m, period_m - plateau_m) / 2:
        raise ValueError(f"edge_m = {edge_m} is out of range; valid range "
                         f"[0, {min(plateau_m, period_m - plateau_m) / 2}]")
    D, w, e = period_m, plateau_m, edge_m
    u = np.abs((np.asarray(x_m, float) + 0.5 * D) % D - 0.5 * D)
    h = np.where(u <= w / 2 - e, 1.0, 0.0)
    if e > 0:
        ramp = (u > w / 2 - e) & (u < w / 2 + e)
        s = (u[ramp] - (w / 2 - e)) / (2 * e)
        h[ramp] = 0.5 * (1 + np.cos(math.pi * s))
    return height_m * h


def random_rough(nrow: int, ncol: int, resolution_m: float, rms_m: float, *,
                 corr_length_m: float | None = None, hurst: float | None = None,
                 rolloff_m: float | None = None, cutoff_m: float | None = None,
                 seed: int = 0) -> np.ndarray:
    """Isotropic Gaussian random height map with RMS height rms_m.

    Spectrum: either Gaussian ``C(q) ~ exp(-(q l)^2 / 4)`` (autocorrelation
    ``exp(-r^2 / l^2)``, l = corr_length_m), or self-affine
    ``C(q) ~ q^(-2(1+H))`` between ``2 pi / rolloff_m`` and
    ``2 pi / cutoff_m`` (flat below the roll-off, zero above the cut-off).
    The map is periodic over its extent; its sample RMS is exactly rms_m."""
    if not (isinstance(nrow, int) and isinstance(ncol, int) and nrow >= 2 and ncol >= 2):
        raise ValueError(f"nrow, ncol = {nrow}, {ncol} must be integers >= 2")
    _check_positive(resolution_m=resolution_m, rms_m=rms_m)
    if (corr_length_m is None) == (hurst is None):
        raise ValueError("give exactly one of corr_length_m (Gaussian) or hurst (self-affine)")
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((nrow, ncol))
    qy = 2 * np.pi * np.fft.fftfreq(nrow, d=resolution_m)
    qx = 2 * np.pi * np.fft.rfftfreq(ncol, d=resolution_m)
    q = np.hypot(qy[:, None], qx[None, :])
    if corr_length_m is not None:
        _check_positive(corr_length_m=corr_length_m)
        if corr_length_m < 2 * resolution_m:
            raise ValueError(f"corr_length_m = {corr_length_m} must be >= 2 x resolution_m "
                             f"({2 * resolution_m}) to be resolved")
        amplitude = np.exp(-(q * corr_length_m) ** 2 / 8)  # sqrt of the spectrum
    else:
        if not 0 < hurst <= 1:
            raise ValueError(f"hurst = {hurst} is out of range; valid range (0, 1]")
        rolloff_m = rolloff_m if rolloff_m is not None else ncol * resolution_m / 4
        cutoff_m = cutoff_m if cutoff_m is not None else 4 * resolution_m
        _check_positive(rolloff_m=rolloff_m, cutoff_m=cutoff_m)
        if not cutoff_m < rolloff_m:
            raise ValueError(f"cutoff_m = {cutoff_m} must be < rolloff_m = {rolloff_m}")
        q0, q1 = 2 * np.pi / rolloff_m, 2 * np.pi / cutoff_m
        amplitude = np.where(q < q0, 1.0, (np.maximum(q, q0) / q0) ** (-(1 + hurst)))
        amplitude[q > q1] = 0.0
    amplitude[0, 0] = 0.0  # zero mean
    h = np.fft.irfft2(np.fft.rfft2(noise) * amplitude, s=(nrow, ncol))
    h -= h.mean()
    return h * (rms_m / h.std())


def dots(x_m: np.ndarray, y_m: np.ndarray, spacing_m: float, radius_m: float, height_m: float,
         lattice: str = "hex") -> np.ndarray:
    """Raised dots (spherical caps of base radius radius_m and height
    height_m) on a square or hexagonal lattice of the given spacing."""
    _check_positive(spacing_m=spacing_m, radius_m=radius_m, height_m=height_m)
    if lattice not in ("hex", "square"):
        raise ValueError(f"lattice {lattice!r} is not 'hex' or 'square'")
    if not 2 * radius_m < spacing_m:
        raise ValueError(f"dot diameter {2 * radius_m} must be < spacing_m {spacing_m}")
    if height_m > radius_m:
        raise ValueError(f"height_m = {height_m} must be <= radius_m = {radius_m} (a cap)")
    X, Y = np.meshgrid(np.asarray(x_m, float), np.asarray(y_m, float))
    # cap of a sphere of radius R with base radius a and height h
    R = (radius_m**2 + height_m**2) / (2 * height_m)

    def nearest_r2(X, Y, dx, dy, ox=0.0):
        gx = np.round((X - ox) / dx) * dx + ox
        gy = np.round(Y / dy) * dy
        return (X - gx) ** 2 + (Y - gy) ** 2

    if lattice == "square":
        r2 = nearest_r2(X, Y, spacing_m, spacing_m)
    else:
        # two interleaved rectangular sub-lattices
        dy = spacing_m * math.sqrt(3)
        r2a = nearest_r2(X, Y, spacing_m, dy)
        r2b = nearest_r2(X, Y - dy / 2, spacing_m, dy, ox=spacing_m / 2)
        r2 = np.minimum(r2a, r2b)
    h = np.sqrt(np.maximum(R * R - r2, 0.0)) - (R - height_m)
    return np.maximum(h, 0.0)


def from_mesh(mesh, **placement):
    """The top surface of a mesh (file or ``trimesh.Trimesh``) as a height
    map of exact cell means: :func:`mjtouch.meshes.from_mesh` (``scale``,
    ``up``, ``rotate_deg``, ``resolution_m``, ``length_m``, ``width_m``).
    ``.texture()`` of the result is a ``scenes.Texture`` for the slide scene."""
    from mjtouch import meshes
    return meshes.from_mesh(mesh, **placement)
