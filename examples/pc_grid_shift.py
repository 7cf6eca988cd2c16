"""Grid-shift averaging against the `elastic` contact's V / pitch line, on the
sliding scene (issue 13; the quasi-static analysis: pc_grid_line_static.py).

    python examples/pc_grid_shift.py                    # 129 / 128 x 0.1 mm, ~1 min
    python examples/pc_grid_shift.py --reference 257    # and a 50 um run (~3 min more)
    python examples/pc_grid_shift.py --small --json     # 65 / 64 x 0.2 mm, ~15 s

The default slide (0.5 N, 25 mm/s over the 1 mm grating, noise off, each grid
alone: `grid_cycle=1`) runs on
an odd grid (nx, a taxel centred on the pole) and on the even grid nx - 1 of
the same pitch, whose cell centres sit half a cell away in x and y. Both carry
the same PC receptors: a 0.6 mm lattice (the bench's `sites`) on the odd
grid, each site moved by (+pitch/2, +pitch/2) onto the even grid's centres.
The two PC stress traces of each receptor are averaged and driven through the
PC afferent (core.receptor_run, as the plugin does) at the midpoint.

The line at V / pitch is the first Fourier component of a discretization
error periodic in the grid's offset against the texture (the grating's edge
pressure peaks are narrower than a cell and their sub-cell position is lost);
half a cell flips its sign, so the average cancels it, at twice the cost of
stages 1-3. Printed per case: PC population rate (Hz) and the PC stress power
(Pa^2) at V / pitch and at the grating harmonics beside it."""

import argparse
import json
import sys

import numpy as np

from mjtouch import analysis, core
from mjtouch.bench.configs import lattice_sites
from mjtouch.experiments import rollout
from mjtouch.scene import scenes

SPEED_M_S = 0.025


def shifted_sites(sites: str, dx_m: float) -> str:
    """The `sites` string with every x and y moved by dx_m."""
    out = []
    for entry in sites.split(";"):
        cls, x, y, depth = entry.split()
        out.append(f"{cls} {float(x) + dx_m:.9g} {float(y) + dx_m:.9g} {depth}")
    return "; ".join(out)


def pc_trace(nx: int, pitch_m: float, sites: str, duration_s: float):
    tip = scenes.Fingertip(
        nx=nx, pitch_m=pitch_m, skin={"noise": "0 0 0", "sites": sites, "grid_cycle": "1"}
    )
    r = rollout.run_slide(
        tip,
        scenes.Texture(),
        scenes.Protocol(speed_m_s=SPEED_M_S, force_n=0.5),
        duration_s=duration_s,
    )
    m = r.layout.mask("PC")
    return r.stress[:, m], r.layout.positions_m[m, :2], r.window(), r.dt


def summarize(name: str, stress: np.ndarray, window: slice, dt: float, pitch_m: float) -> dict:
    spikes = np.array(
        [
            core.receptor_run("PC", stress[:, k], dt, config={"noise": "0 0 0"}, stream=k)[0]
            for k in range(stress.shape[1])
        ]
    ).T
    steps = window.stop - window.start
    f, p = analysis.stress_spectrum(stress[window], dt)
    hw = max(3.0, 1.5 * (f[1] - f[0]))
    band = lambda fc: float(p[np.abs(f - fc) <= hw].max())  # noqa: E731
    line = SPEED_M_S / pitch_m
    return {
        "case": name,
        "pitch_m": pitch_m,
        "v_over_pitch_hz": line,
        "pc_rate_hz": float(spikes[window].sum() / (spikes.shape[1] * steps * dt)),
        "power_at_v_over_pitch_pa2": band(line),
        "power_beside_pa2": [band(line - 25.0), band(line + 25.0)],
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--nx", type=int, default=129, help="the odd grid (the even one is nx - 1)")
    ap.add_argument("--pitch", type=float, default=1e-4, help="taxel pitch (m)")
    ap.add_argument("--duration", type=float, default=0.3, help="sliding time (s)")
    ap.add_argument(
        "--reference",
        type=int,
        default=0,
        help="also run this odd nx at the pitch that keeps the skin's extent",
    )
    ap.add_argument("--small", action="store_true", help="65 / 64 x 0.2 mm, 0.25 s")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    if a.small:
        a.nx, a.pitch, a.duration = 65, 2e-4, 0.25
    if a.nx % 2 == 0 or a.nx < 5:
        ap.error(f"--nx = {a.nx} must be odd and >= 5")
    sites = lattice_sites([(a.nx, a.pitch)])
    s_odd, pos_odd, w, dt = pc_trace(a.nx, a.pitch, sites, a.duration)
    s_even, pos_even, _, _ = pc_trace(
        a.nx - 1, a.pitch, shifted_sites(sites, a.pitch / 2), a.duration
    )
    if not np.allclose(pos_even - pos_odd, a.pitch / 2, rtol=0, atol=1e-9):
        raise RuntimeError("the even grid's PC sites are not the odd grid's moved by pitch / 2")
    rows = [
        summarize(f"odd grid nx {a.nx}", s_odd, w, dt, a.pitch),
        summarize(f"even grid nx {a.nx - 1}", s_even, w, dt, a.pitch),
        summarize("grid shift average", 0.5 * (s_odd + s_even), w, dt, a.pitch),
    ]
    if a.reference:
        ref_pitch = a.nx * a.pitch / a.reference
        s_ref, _, wr, dtr = pc_trace(a.reference, ref_pitch, sites, a.duration)
        rows.append(summarize(f"reference nx {a.reference}", s_ref, wr, dtr, ref_pitch))
    if a.json:
        print(json.dumps(rows))
        return 0
    for r in rows:
        b = r["power_beside_pa2"]
        print(
            f"{r['case']:22s} pitch {r['pitch_m'] * 1e6:5.1f} um: PC {r['pc_rate_hz']:6.1f} Hz; "
            f"stress power at V/pitch ({r['v_over_pitch_hz']:.0f} Hz) "
            f"{r['power_at_v_over_pitch_pa2']:.3g} Pa^2, beside {b[0]:.3g} / {b[1]:.3g}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
