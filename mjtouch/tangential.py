"""Partial slip: the skin's tangential contact under the force MuJoCo reports.

Given the normal solution (cell pressure, Pa), the friction coefficient and the
total tangential force (N), Coulomb's law per cell gives stick cells (the skin
surface moves with the counter-body, |q| <= mu p) and slip cells (|q| = mu p
along the slip). The tractions sum to the force; the state (last tractions and
rigid shift) carries from step to step, so a load reversal gives
Mindlin-Deresiewicz hysteresis. Wraps the C++ stage (plugin/core/contact/
tangential.h):

- ``winkler_partial_slip``: local tangential springs (Kalker's FASTSIM).
- ``ElasticPartialSlip``: a homogeneous half-space (Cerruti compliance by FFT,
  projected conjugate gradient).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mjtouch import _core


@dataclass
class TangentialState:
    """The memory between steps: last tractions (n x n, Pa) and shift (m)."""

    shear_x_pa: np.ndarray | None = None
    shear_y_pa: np.ndarray | None = None
    shift_x_m: float = 0.0
    shift_y_m: float = 0.0

    @classmethod
    def from_result(cls, result: dict) -> TangentialState:
        return cls(
            result["shear_x_pa"], result["shear_y_pa"], result["shift_x_m"], result["shift_y_m"]
        )

    def arguments(self) -> dict:
        return dict(
            shear_x_pa=self.shear_x_pa,
            shear_y_pa=self.shear_y_pa,
            shift_x_m=self.shift_x_m,
            shift_y_m=self.shift_y_m,
        )


def winkler_tangential_stiffness(normal_stiffness_pa_per_m: float, poisson: float) -> float:
    """Tangential spring stiffness per area (Pa/m) for a Winkler skin:
    k_n 2 (1 - nu) / (2 - nu), the half-space's punch stiffness ratio."""
    return _core.winkler_tangential_stiffness(normal_stiffness_pa_per_m, poisson)


def winkler_partial_slip(
    pressure_pa,
    pitch_m: float,
    mu: float,
    force_n,
    stiffness_pa_per_m: float,
    state: TangentialState | None = None,
):
    """One step on a Winkler skin. force_n: (fx, fy) N. Returns (result dict, new state);
    result: shear_x_pa, shear_y_pa, stick (uint8 map), stuck_share, shift_x_m, shift_y_m,
    loaded_cells, stick_cells, full_slip, iterations."""
    state = state or TangentialState()
    r = _core.tangential_winkler(
        np.ascontiguousarray(pressure_pa, dtype=np.float64),
        pitch_m,
        mu,
        float(force_n[0]),
        float(force_n[1]),
        stiffness_pa_per_m,
        **state.arguments(),
    )
    return r, TangentialState.from_result(r)


class ElasticPartialSlip:
    """Partial slip on a homogeneous half-space skin (n x n grid of pitch pitch_m)."""

    def __init__(self, n: int, pitch_m: float, young_pa: float, poisson: float):
        self.compliance = _core.TangentialCompliance(n, pitch_m, young_pa, poisson)

    def solve(
        self,
        pressure_pa,
        mu: float,
        force_n,
        state: TangentialState | None = None,
        tolerance: float = 1e-3,
        max_iterations: int = 200,
        precision: str = "float",
    ):
        """One step; as winkler_partial_slip, stopping at a relative L1 change of the
        tractions below tolerance; precision of the FFTs 'float' or 'double'."""
        state = state or TangentialState()
        r = self.compliance.solve(
            np.ascontiguousarray(pressure_pa, dtype=np.float64),
            mu,
            float(force_n[0]),
            float(force_n[1]),
            tolerance,
            max_iterations,
            **state.arguments(),
            precision=precision,
        )
        return r, TangentialState.from_result(r)

    def displacement(self, shear_x_pa, shear_y_pa):
        """Surface tangential displacement (ux, uy, m) under the tractions."""
        return self.compliance.displacement(
            np.ascontiguousarray(shear_x_pa, dtype=np.float64),
            np.ascontiguousarray(shear_y_pa, dtype=np.float64),
        )
