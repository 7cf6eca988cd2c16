"""Shao et al. 2010 (Tribology International 43: 2308), sliding over
gratings with and without fingerprint ridges, reproduced in 3D.

    python examples/shao2010.py            # both textures, ~2 min
    python examples/shao2010.py --quick    # D = 0.2 mm only, shorter (the test)
    python examples/shao2010.py --json

Shao's 2D finite-element fingertip slid at 25 mm/s over plateaux of spacing
D. Their findings: D = 0.6 mm gives the texture fundamental V/D = 42 Hz
without ridges and its doubling, 84 Hz, with ridges (4 ridges per 3
plateaux); D = 0.2 mm gives 125 Hz with harmonics at 250 and 375 Hz with
ridges, stronger at the Pacinian site than at the Meissner site, and no
clear peak without ridges.

Here: the default fingertip (ridge pitch 0.45 mm, Shao's layered skin over
bone) under 0.1 N (Shao's 0.6 mm displacement was ~0.1 N), the `elastic`
contact model, exact stress, Mises stress (Shao's measure) at the Meissner
(0.75 mm) and Pacinian (2 mm) depths. Textures: plateaux of width D/2
(Shao's Fig. 1: 0.2 mm tall with 0.2 mm corner radii for D = 0.6 mm; the
fine one 0.05 mm tall here, which the paper does not state). Prints, per
case and site, the strongest spectral peaks and the power at V/D, 2V/D and
3V/D. README "Reproducing the source studies" compares them with the paper.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from mjtouch import analysis
from mjtouch.experiments import rollout
from mjtouch.scene import scenes

SPEED_M_S = 0.025
SITES = {"Meissner": "RA", "Pacinian": "PC"}


def case(period_m: float, ridges: bool, duration_s: float) -> dict:
    coarse = period_m >= 0.6e-3
    texture = scenes.Texture(
        kind="grating",
        period_m=period_m,
        plateau_m=period_m / 2,
        height_m=0.2e-3 if coarse else 0.05e-3,
        edge_m=min(period_m / 8, 0.075e-3),
        resolution_m=period_m / 30,
        length_m=2 * SPEED_M_S * duration_s + 0.03,
    )
    # 4-6 taxels per period; the contact at 0.1 N (~4 mm) fits the grid
    nx, pitch, dt = (64, 1e-4, 5e-4) if coarse else (96, 5e-5, 2.5e-4)
    tip = scenes.Fingertip(
        nx=nx,
        pitch_m=pitch,
        ridges=ridges,
        skin={
            "pressure": "elastic",
            "quantity": "maxcomp vonmises vonmises",
            "outputs": "stress force",
        },
    )
    proto = scenes.Protocol(force_n=0.1, speed_m_s=SPEED_M_S, timestep_s=dt, press_s=0.1)
    res = rollout.run_slide(tip, texture, proto, duration_s=duration_s)
    w = res.window(0.05)
    fd = SPEED_M_S / period_m
    out = {"period_m": period_m, "ridges": ridges, "v_over_d_hz": fd, "sites": {}}
    for name, cls in SITES.items():
        f, p = analysis.stress_spectrum(res.stress[w][:, res.layout.mask(cls)], res.dt)
        out["sites"][name] = {
            "peaks_hz": [float(x) for x in analysis.spectral_peaks(f, p, n=6, fmin_hz=10.0)],
            "power_at_harmonics_pa2": [float(analysis.power_at(f, p, k * fd)) for k in (1, 2, 3)],
            "fft_bin_hz": float(f[1] - f[0]),
        }
    return out


def run(quick: bool = False) -> list[dict]:
    periods = [0.2e-3] if quick else [0.6e-3, 0.2e-3]
    duration = 0.25 if quick else 0.5
    return [case(d, r, duration) for d in periods for r in (True, False)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="D = 0.2 mm only, 0.25 s")
    ap.add_argument("--json", action="store_true", help="one JSON list of the cases")
    args = ap.parse_args()
    cases = run(args.quick)
    if args.json:
        print(json.dumps(cases))
        return
    for c in cases:
        print(
            f"D = {c['period_m'] * 1e3:.1f} mm, {'ridged' if c['ridges'] else 'smooth'} skin "
            f"(V/D = {c['v_over_d_hz']:.1f} Hz)"
        )
        for name, s in c["sites"].items():
            p = np.array(s["power_at_harmonics_pa2"])
            print(
                f"  {name:9s} peaks {np.round(s['peaks_hz'], 1)} Hz; power at V/D, 2V/D, 3V/D "
                f"{p[0]:.3g}, {p[1]:.3g}, {p[2]:.3g} Pa^2"
            )


if __name__ == "__main__":
    main()
