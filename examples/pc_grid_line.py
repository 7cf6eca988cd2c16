"""The `elastic` contact's grid line in the PC stress (README, "What accuracy
costs"): the contact set moves cell by cell, which adds a line at V / pitch to
the receptor stress. At the default 0.1 mm pitch and 25 mm/s that is 250 Hz,
PC's best frequency (and the grating's 10th harmonic); Winkler's pressure
grows continuously with the overlap and has no such line.

    python examples/pc_grid_line.py [--duration 0.4] [--json]

Prints, per (pressure, pitch), the PC receptors' stress power at V / pitch and
at the grating harmonics around 250 Hz, and the PC rate (noise off). The
elastic rows solve on the taxel grid alone (grid_cycle=1); the last row is
the elastic skin with grid_cycle=4, which averages four sub-cell offset grids
solved in turn, which cancels the line."""

import argparse
import json
import sys

import numpy as np

from mjtouch import analysis
from mjtouch.experiments import rollout
from mjtouch.scene import scenes

SPEED_M_S = 0.025
CASES = (
    ("elastic", 1e-4, 128, "1"),
    ("elastic", 5e-5, 256, "1"),
    ("winkler", 1e-4, 128, "1"),
    ("elastic", 1e-4, 128, "4"),
)


def band_max(f, p, fc, half_width_hz):
    k = np.abs(f - fc) <= half_width_hz
    return float(p[k].max()) if k.any() else float("nan")


def run(pressure: str, pitch_m: float, nx: int, cycle: str, duration_s: float) -> dict:
    skin = {"pressure": pressure, "noise": "0 0 0", "grid_cycle": cycle}
    tip = scenes.Fingertip(nx=nx, pitch_m=pitch_m, skin=skin)
    r = rollout.run_slide(
        tip,
        scenes.Texture(),
        scenes.Protocol(speed_m_s=SPEED_M_S, force_n=0.5),
        duration_s=duration_s,
    )
    w = r.window()
    f, p = analysis.stress_spectrum(r.stress[w][:, r.layout.mask("PC")], r.dt)
    hw = max(3.0, 1.5 * (f[1] - f[0]))
    return {
        "pressure": pressure,
        "grid_cycle": int(cycle),
        "pitch_m": pitch_m,
        "v_over_pitch_hz": SPEED_M_S / pitch_m,
        "power_at_v_over_pitch_pa2": band_max(f, p, SPEED_M_S / pitch_m, hw),
        "power_at_harmonics_pa2": {str(h): band_max(f, p, h, hw) for h in (225, 250, 275)},
        "pc_rate_hz": analysis.rates_hz(r.spikes[w], r.dt, r.layout.classes)["PC"],
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=0.4, help="sliding time (s)")
    ap.add_argument("--small", action="store_true", help="coarse grids (a smoke run)")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    cases = ((p, 2 * h, n // 2, c) for p, h, n, c in CASES) if a.small else CASES
    rows = [run(p, h, n, c, a.duration) for p, h, n, c in cases]
    if a.json:
        print(json.dumps(rows))
        return 0
    for r in rows:
        hm = r["power_at_harmonics_pa2"]
        print(
            f"{r['pressure']:8s} grid_cycle {r['grid_cycle']} pitch {r['pitch_m'] * 1e6:5.1f} um: "
            "power at V/pitch "
            f"({r['v_over_pitch_hz']:.0f} Hz) {r['power_at_v_over_pitch_pa2']:.3g} Pa^2; "
            f"at 225/250/275 Hz {hm['225']:.3g} / {hm['250']:.3g} / {hm['275']:.3g}; "
            f"PC {r['pc_rate_hz']:.0f} Hz"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
