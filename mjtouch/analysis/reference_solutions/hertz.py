"""Hertz contact of a rigid sphere on an elastic half-space (H. Hertz, J. reine
angew. Math. 92:156, 1882; K. L. Johnson, *Contact Mechanics*, Cambridge 1985,
sec. 4.2), and the measures that compare a computed pressure field with it."""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Hertz:
    """Rigid sphere (radius R) on a half-space (E, nu) under load W:
    a = (3 W R / 4 E*)^(1/3), p0 = 3 W / (2 pi a^2), delta = a^2 / R,
    p(r) = p0 sqrt(1 - r^2 / a^2), E* = E / (1 - nu^2)."""

    load_n: float
    radius_m: float
    young_pa: float
    poisson: float

    @property
    def e_star_pa(self) -> float:
        return self.young_pa / (1 - self.poisson**2)

    @property
    def contact_radius_m(self) -> float:
        return (3 * self.load_n * self.radius_m / (4 * self.e_star_pa)) ** (1 / 3)

    @property
    def peak_pa(self) -> float:
        a = self.contact_radius_m
        return 3 * self.load_n / (2 * np.pi * a * a)

    @property
    def indentation_m(self) -> float:
        return self.contact_radius_m**2 / self.radius_m


def hertz_errors(
    h: Hertz, pressure_pa: np.ndarray, pitch_m: float, indentation_m: float
) -> dict[str, float]:
    """Relative errors of a centred pressure field (n x n, Pa, cells of side
    pitch_m) and indentation against Hertz: peak pressure, contact radius
    (from the second moment, int p r^2 dA / W = 2 a^2 / 5, which does not
    depend on counting cells) and indentation."""
    p = np.asarray(pressure_pa, dtype=float)
    n = p.shape[0]
    x = (np.arange(n) - (n - 1) / 2) * pitch_m
    X, Y = np.meshgrid(x, x)
    load = p.sum() * pitch_m**2
    a = np.sqrt(2.5 * (p * (X**2 + Y**2)).sum() * pitch_m**2 / load)
    return {
        "peak": p.max() / h.peak_pa - 1,
        "radius": a / h.contact_radius_m - 1,
        "indentation": indentation_m / h.indentation_m - 1,
    }
