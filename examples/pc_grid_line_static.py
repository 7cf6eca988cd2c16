"""Where the `elastic` contact's V / pitch line comes from (issue 13): the
sliding scene made quasi-static, without MuJoCo.

    python examples/pc_grid_line_static.py            # 128 x 0.1 mm, ~1-2 min
    python examples/pc_grid_line_static.py --small    # 64 x 0.2 mm, texture x2, ~10 s
    python examples/pc_grid_line_static.py --json

The ridged pad (the default Fingertip's skin surface, layered Shao 2010 skin)
is pressed with 0.5 N on the 1 mm grating, which is shifted under it by s in
`samples` steps over one period D; at each step the elastic contact is solved
(core.elastic_pressure, the plugin's solver) and -s_zz at 2 mm (PC depth)
under a 0.6 mm lattice of sites (core.StressEngine, full-slip shear 0.5 p).
The stress is periodic in s with period D, so its spectrum has lines at the
grating harmonics m / D only; sliding at V, harmonic m is m V / D, and the
taxel grid's line V / pitch is harmonic D / pitch (10 here: 250 Hz at
25 mm/s). Printed: the mean power over the sites (Pa^2) at that harmonic and
its neighbours, for

- `default`: the shipped grating (edges rounded over edge_m = 50 um, a
  100 um ramp: one cell);
- `edges resolved`: the same grating with its edges rounded over
  2 pitch (the ramp spans 4 cells);
- `grid shift average`: the default, solved on the taxel grid and on the grid
  shifted by half a cell in x and y, the two stresses at the same sites
  averaged (the line is the first Fourier component of an error periodic in
  the grid's offset against the texture; half a cell flips its sign).

The line follows the texture's edges, not the contact solve: the pressure
peaks at the grating edges are narrower than a cell, so the load's sub-cell
position, which cell-uniform loads cannot carry, moves with the texture
(README "What accuracy costs", issue 13 note)."""

import argparse
import json
import sys

import numpy as np

from mjtouch import core
from mjtouch.scene import textures

FORCE_N = 0.5
PC_DEPTH_M = 2e-3
SITE_SPACING_M = 0.6e-3
SLIP = (0.5, 0.0)


def skin_surface(n: int, pitch_m: float) -> np.ndarray:
    cfg = {
        "nx": str(n),
        "pitch": repr(pitch_m),
        "ridges": "true",
        "ridge_pitch": "0.00045",
        "ridge_height": "5e-05",
    }
    return core.skin_surface((0.008, 0.007, 0.007), cfg)


def grating_cells(
    n: int, pitch_m: float, shift_m: float, period_m: float, edge_m: float, sub: int = 16
) -> np.ndarray:
    """Grating height (plateaux along y, half the period wide, 0.1 mm tall)
    averaged over each cell of an n-cell grid centred on the origin (as the
    plugin renders it: exact cell means; here by sub-sampling along x)."""
    x = (np.arange(n) - (n - 1) / 2) * pitch_m
    o = ((np.arange(sub) + 0.5) / sub - 0.5) * pitch_m
    g = textures.grating(x[:, None] + o[None, :] - shift_m, period_m, period_m / 2, 1e-4, edge_m)
    return np.broadcast_to(g.mean(1), (n, n))


def sites_on(nf: int, hf: float) -> np.ndarray:
    """Fine-grid cells (i, j) nearest a SITE_SPACING_M lattice within 3 mm."""
    x = (np.arange(nf) - (nf - 1) / 2) * hf
    step = int(round(SITE_SPACING_M / hf))
    c = int(np.argmin(np.abs(x - hf / 2)))
    idx = np.arange(c % step, nf, step)
    i, j = np.meshgrid(idx, idx)
    keep = np.hypot(x[i], x[j]) < 3e-3
    return np.stack([i[keep], j[keep]], 1)


def run(
    n: int, pitch_m: float, period_m: float, edge_m: float, samples: int, shift_average: bool
) -> np.ndarray:
    """-s_zz (samples x sites, Pa) over one period of the grating. Grid A: n
    cells; grid B (shift_average): n + 1 cells, i.e. A shifted by half a cell
    in x and y. Both grids' pressures are evaluated on a grid of half the pitch
    (each cell's uniform load split exactly over its 2 x 2 sub-cells), so the
    sites are the same points for both."""
    nf, hf = 2 * n + 2, pitch_m / 2
    eng = core.StressEngine(
        core.LayeredSkin(), nf, hf, [PC_DEPTH_M], sites_on(nf, hf), components=[2]
    )
    grids = [(n, 1)] + ([(n + 1, 0)] if shift_average else [])  # (cells, offset in sub-cells)
    skins = {m: skin_surface(m, pitch_m) for m, _ in grids}
    z0 = min(z[np.isfinite(z)].min() for z in skins.values())
    tables = {m: core.LayeredSkin().compliance_table(pitch_m, m) for m, _ in grids}
    guess = {m: None for m, _ in grids}
    out = np.zeros((samples, eng.nrec))
    for k in range(samples):
        s = k * period_m / samples
        for m, off in grids:
            gap = skins[m] - z0 - grating_cells(m, pitch_m, s, period_m, edge_m)
            p, _ = core.elastic_pressure(
                np.where(np.isfinite(gap), gap, np.inf),
                pitch_m,
                FORCE_N,
                compliance_m_per_pa=tables[m],
                tolerance=1e-8,
                max_iterations=20000,
                initial_pa=guess[m],
            )
            guess[m] = p
            fine = np.zeros((nf, nf))
            fine[off : off + 2 * m, off : off + 2 * m] = np.kron(p, np.ones((2, 2)))
            out[k] -= eng.stress(fine, slip=SLIP)[:, 2] / len(grids)
    return out


def harmonic_power(stress: np.ndarray) -> np.ndarray:
    """Mean over sites of the power (Pa^2, mean square) of each harmonic."""
    f = np.fft.rfft(stress - stress.mean(0), axis=0) / len(stress)
    return (2 * np.abs(f) ** 2).mean(1)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--small",
        action="store_true",
        help="64 x 0.2 mm taxels, the texture scaled x2 (period 2 mm)",
    )
    ap.add_argument("--samples", type=int, default=40, help="shifts per grating period")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    n, pitch, period = (64, 2e-4, 2e-3) if a.small else (128, 1e-4, 1e-3)
    line = int(round(period / pitch))
    if a.samples <= 2 * (line + 1):
        ap.error(f"--samples must exceed {2 * (line + 1)} (the grid line is harmonic {line})")
    cases = (
        ("default", 0.05e-3 * period / 1e-3, False),
        ("edges resolved", 2 * pitch, False),
        ("grid shift average", 0.05e-3 * period / 1e-3, True),
    )
    rows = []
    for name, edge, shift in cases:
        pw = harmonic_power(run(n, pitch, period, edge, a.samples, shift))
        rows.append(
            {
                "case": name,
                "pitch_m": pitch,
                "edge_m": edge,
                "grid_harmonic": line,
                "power_pa2": {str(h): float(pw[h]) for h in range(1, line + 3)},
            }
        )
    if a.json:
        print(json.dumps(rows))
        return 0
    for r in rows:
        p = r["power_pa2"]
        print(
            f"{r['case']:20s} pitch {pitch * 1e6:.0f} um, edge {r['edge_m'] * 1e6:.0f} um: "
            f"harmonic 1 {p['1']:.3g} Pa^2; grid line (harmonic {line}) {p[str(line)]:.3g}; "
            f"neighbours {p[str(line - 1)]:.3g} / {p[str(line + 1)]:.3g}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
