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
- :class:`Texture`: a plate texture described by its parameters, whose
  ``heights()`` calls the generators above.

The top surface of a mesh file is a texture too: :func:`mjtouch.scene.meshes.from_mesh`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Literal

import numpy as np

from mjtouch._validate import positive

TextureKind = Literal["grating", "random", "dots", "flat", "mesh"]


def grid(length_m: float, width_m: float, resolution_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Sample coordinates (x of ncol columns, y of nrow rows)."""
    positive("length_m", length_m)
    positive("width_m", width_m)
    positive("resolution_m", resolution_m)
    ncol = int(round(length_m / resolution_m)) + 1
    nrow = int(round(width_m / resolution_m)) + 1
    return (
        np.linspace(-length_m / 2, length_m / 2, ncol),
        np.linspace(-width_m / 2, width_m / 2, nrow),
    )


def grating(
    x_m: np.ndarray, period_m: float, plateau_m: float, height_m: float, edge_m: float = 0.0
) -> np.ndarray:
    """Height along x of plateaux centred on x = k * period."""
    positive("period_m", period_m)
    positive("plateau_m", plateau_m)
    positive("height_m", height_m)
    if not plateau_m < period_m:
        raise ValueError(f"plateau_m = {plateau_m} must be < period_m = {period_m}")
    if not 0 <= edge_m <= min(plateau_m, period_m - plateau_m) / 2:
        raise ValueError(
            f"edge_m = {edge_m} is out of range; valid range "
            f"[0, {min(plateau_m, period_m - plateau_m) / 2}]"
        )
    D, w, e = period_m, plateau_m, edge_m
    u = np.abs((np.asarray(x_m, float) + 0.5 * D) % D - 0.5 * D)
    h = np.where(u <= w / 2 - e, 1.0, 0.0)
    if e > 0:
        ramp = (u > w / 2 - e) & (u < w / 2 + e)
        s = (u[ramp] - (w / 2 - e)) / (2 * e)
        h[ramp] = 0.5 * (1 + np.cos(math.pi * s))
    return height_m * h


def random_rough(
    nrow: int,
    ncol: int,
    resolution_m: float,
    rms_m: float,
    *,
    corr_length_m: float | None = None,
    hurst: float | None = None,
    rolloff_m: float | None = None,
    cutoff_m: float | None = None,
    seed: int = 0,
) -> np.ndarray:
    """Isotropic Gaussian random height map with RMS height rms_m.

    Spectrum: either Gaussian ``C(q) ~ exp(-(q l)^2 / 4)`` (autocorrelation
    ``exp(-r^2 / l^2)``, l = corr_length_m), or self-affine
    ``C(q) ~ q^(-2(1+H))`` between ``2 pi / rolloff_m`` and
    ``2 pi / cutoff_m`` (flat below the roll-off, zero above the cut-off).
    The map is periodic over its extent; its sample RMS is exactly rms_m."""
    if not (isinstance(nrow, int) and isinstance(ncol, int) and nrow >= 2 and ncol >= 2):
        raise ValueError(f"nrow, ncol = {nrow}, {ncol} must be integers >= 2")
    positive("resolution_m", resolution_m)
    positive("rms_m", rms_m)
    if (corr_length_m is None) == (hurst is None):
        raise ValueError("give exactly one of corr_length_m (Gaussian) or hurst (self-affine)")
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((nrow, ncol))
    qy = 2 * np.pi * np.fft.fftfreq(nrow, d=resolution_m)
    qx = 2 * np.pi * np.fft.rfftfreq(ncol, d=resolution_m)
    q = np.hypot(qy[:, None], qx[None, :])
    if corr_length_m is not None:
        positive("corr_length_m", corr_length_m)
        if corr_length_m < 2 * resolution_m:
            raise ValueError(
                f"corr_length_m = {corr_length_m} must be >= 2 x resolution_m "
                f"({2 * resolution_m}) to be resolved"
            )
        amplitude = np.exp(-((q * corr_length_m) ** 2) / 8)  # sqrt of the spectrum
    else:
        if not 0 < hurst <= 1:
            raise ValueError(f"hurst = {hurst} is out of range; valid range (0, 1]")
        rolloff_m = rolloff_m if rolloff_m is not None else ncol * resolution_m / 4
        cutoff_m = cutoff_m if cutoff_m is not None else 4 * resolution_m
        positive("rolloff_m", rolloff_m)
        positive("cutoff_m", cutoff_m)
        if not cutoff_m < rolloff_m:
            raise ValueError(f"cutoff_m = {cutoff_m} must be < rolloff_m = {rolloff_m}")
        q0, q1 = 2 * np.pi / rolloff_m, 2 * np.pi / cutoff_m
        amplitude = np.where(q < q0, 1.0, (np.maximum(q, q0) / q0) ** (-(1 + hurst)))
        amplitude[q > q1] = 0.0
    amplitude[0, 0] = 0.0  # zero mean
    h = np.fft.irfft2(np.fft.rfft2(noise) * amplitude, s=(nrow, ncol))
    h -= h.mean()
    return h * (rms_m / h.std())


def dots(
    x_m: np.ndarray,
    y_m: np.ndarray,
    spacing_m: float,
    radius_m: float,
    height_m: float,
    lattice: str = "hex",
) -> np.ndarray:
    """Raised dots (spherical caps of base radius radius_m and height
    height_m) on a square or hexagonal lattice of the given spacing."""
    positive("spacing_m", spacing_m)
    positive("radius_m", radius_m)
    positive("height_m", height_m)
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


@dataclasses.dataclass
class Texture:
    """A plate texture (generators below).

    - ``grating``: raised plateaux of width ``plateau_m`` every ``period_m``
      along x, ``height_m`` tall, edges rounded over ``edge_m``;
    - ``random``: isotropic Gaussian roughness of RMS height ``rms_m`` and
      Gaussian correlation length ``corr_length_m`` (seeded by ``seed``);
    - ``dots``: hexagonal array of spherical-cap dots (``dot_spacing_m``,
      ``dot_radius_m``, ``height_m``);
    - ``flat``: no texture;
    - ``mesh``: the top surface of a mesh file, ``mesh`` (a
      :class:`mjtouch.scene.meshes.MeshTexture`, from :func:`mjtouch.scene.meshes.from_mesh`).
    Gratings are 1D (a 2-row height field); random and dot textures are 2D
    height fields."""

    kind: TextureKind = "grating"
    period_m: float = 1.0e-3
    plateau_m: float | None = None  # default: half the period
    height_m: float = 0.1e-3
    edge_m: float = 0.05e-3
    length_m: float = 0.08
    width_m: float = 0.03
    resolution_m: float = 2e-5  # height-field sample spacing
    rms_m: float = 20e-6
    corr_length_m: float = 100e-6
    dot_spacing_m: float = 2.5e-3
    dot_radius_m: float = 0.6e-3
    seed: int = 0
    mesh: object | None = None  # kind "mesh": a meshes.MeshTexture

    def validate(self) -> None:
        if self.kind not in ("grating", "flat", "random", "dots", "mesh"):
            raise ValueError(
                f"texture kind {self.kind!r} is not one of "
                "'grating', 'random', 'dots', 'flat', 'mesh'"
            )
        if self.kind == "mesh" and self.mesh is None:
            raise ValueError("texture kind 'mesh' needs `mesh` (mjtouch.scene.meshes.from_mesh)")
        positive("height_m", self.height_m)
        positive("length_m", self.length_m)
        positive("width_m", self.width_m)
        positive("resolution_m", self.resolution_m)
        if self.kind == "grating":
            positive("period_m", self.period_m)
            plateau = self.plateau
            if not 0 < plateau < self.period_m:
                raise ValueError(
                    f"plateau_m = {plateau} is out of range; valid range "
                    f"(0, period_m = {self.period_m})"
                )
            if not 0 <= self.edge_m <= min(plateau, self.period_m - plateau) / 2:
                raise ValueError(
                    f"edge_m = {self.edge_m} is out of range; valid range "
                    f"[0, {min(plateau, self.period_m - plateau) / 2}]"
                )
            if self.period_m < 4 * self.resolution_m:
                raise ValueError(
                    f"period_m = {self.period_m} needs at least 4 height-field "
                    f"samples; lower resolution_m (now {self.resolution_m})"
                )
        if self.kind == "random":
            positive("rms_m", self.rms_m)
            positive("corr_length_m", self.corr_length_m)
        if self.kind == "dots":
            positive("dot_spacing_m", self.dot_spacing_m)
            positive("dot_radius_m", self.dot_radius_m)
        if self.kind != "flat" and self.nrow * self.ncol > 8_000_000:
            raise ValueError(
                f"texture needs {self.nrow} x {self.ncol} height-field samples; "
                "valid up to 8e6 (shrink the plate or coarsen resolution_m)"
            )

    @property
    def plateau(self) -> float:
        return self.period_m / 2 if self.plateau_m is None else self.plateau_m

    @property
    def ncol(self) -> int:
        if self.kind == "mesh":
            return self.mesh.heights.shape[1]
        return int(round(self.length_m / self.resolution_m)) + 1

    @property
    def nrow(self) -> int:
        if self.kind == "mesh":
            return self.mesh.heights.shape[0]
        if self.kind in ("grating", "flat"):
            return 2
        return int(round(self.width_m / self.resolution_m)) + 1

    def profile(self, x_m: np.ndarray) -> np.ndarray:
        """Height (m) along x of a grating: plateaux centred on x = k * period."""
        if self.kind == "flat":
            return np.zeros_like(x_m)
        if self.kind != "grating":
            raise ValueError("profile() is for gratings; use heights()")
        return grating(x_m, self.period_m, self.plateau, self.height_m, self.edge_m)

    def heights(self) -> np.ndarray:
        """Height map (m), nrow x ncol, MuJoCo height-field order."""
        if self.kind == "mesh":
            return self.mesh.heights
        x = np.linspace(-self.length_m / 2, self.length_m / 2, self.ncol)
        if self.kind in ("grating", "flat"):
            return np.tile(self.profile(x), (2, 1))
        if self.kind == "random":
            h = random_rough(
                self.nrow,
                self.ncol,
                self.resolution_m,
                self.rms_m,
                corr_length_m=self.corr_length_m,
                seed=self.seed,
            )
            return h - h.min()
        y = np.linspace(-self.width_m / 2, self.width_m / 2, self.nrow)
        return dots(x, y, self.dot_spacing_m, self.dot_radius_m, self.height_m)
