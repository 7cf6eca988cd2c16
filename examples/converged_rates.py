"""Population rates of the default slide against a converged reference, on
textures, periods and speeds the tests do not use.

    python examples/converged_rates.py                 # ~15-30 min on 2 cores
    python examples/converged_rates.py --cases grating --duration 0.5
    python examples/converged_rates.py --json

Per case, the slide (`python -m mjtouch slide --json` with the case's
options) runs with the default skin (128 x 0.1 mm, `elastic` on the taxel
grid alone, `grid_cycle` 1), with `grid_cycle` 4, and with the reference
`--nx 256 --pitch 5e-5 --grid-shift`; `--finer` adds `--nx 341 --pitch
3.75e-5 --grid-shift` to show that the reference itself has converged (the
goal: the two references within 5%). Printed: SA1 / RA / PC population rates
and each one's relative error against the reference (goal: 10% SA1 and RA,
15% PC)."""

import argparse
import json
import sys

from mjtouch.experiments import slide

CASES = {
    "grating": {"texture": "grating", "period_m": 0.7e-3, "speed_m_s": 0.035},
    "random": {
        "texture": "random",
        "rms_m": 2.5e-5,
        "corr_length_m": 8e-5,
        "seed": 5,
        "speed_m_s": 0.04,
    },
    "dots": {
        "texture": "dots",
        "dot_spacing_m": 1.8e-3,
        "dot_radius_m": 0.45e-3,
        "speed_m_s": 0.03,
    },
}
SETTINGS = {
    "default": {},
    "cycle 4": {"grid_cycle": 4},
    "ref 50 um": {"nx": 256, "pitch_m": 5e-5, "grid_shift": True},
    "ref 37.5 um": {"nx": 341, "pitch_m": 3.75e-5, "grid_shift": True},
}
CLASSES = ("SA1", "RA", "PC")
BOUND = {"SA1": 0.10, "RA": 0.10, "PC": 0.15}


def rates(case: str, setting: str, duration_s: float) -> dict:
    p = slide.from_mapping({**CASES[case], **SETTINGS[setting], "duration_s": duration_s})
    out = slide.run(p)
    return {"rates_hz": out.summary["rates_hz"], "wall_s": out.summary["wall_s"]}


def rel(a: float, b: float) -> float:
    return abs(a - b) / b if b > 0 else float("inf")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default=",".join(CASES), help="comma-separated: " + " ".join(CASES))
    ap.add_argument("--duration", type=float, default=0.5, help="sliding time per run (s)")
    ap.add_argument("--finer", action="store_true", help="also the 37.5 um reference")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    settings = ["default", "cycle 4", "ref 50 um"] + (["ref 37.5 um"] if a.finer else [])
    rows = {}
    for case in a.cases.split(","):
        if case not in CASES:
            ap.error(f"unknown case {case!r}; valid: {' '.join(CASES)}")
        rows[case] = {s: rates(case, s, a.duration) for s in settings}
    if a.json:
        print(json.dumps(rows))
        return 0
    for case, runs in rows.items():
        ref = runs["ref 50 um"]["rates_hz"]
        print(f"{case}: {CASES[case]}")
        for s, r in runs.items():
            cells = "  ".join(
                f"{c} {r['rates_hz'][c]:6.1f} ({100 * rel(r['rates_hz'][c], ref[c]):4.1f}%)"
                for c in CLASSES
            )
            ok = all(rel(r["rates_hz"][c], ref[c]) <= BOUND[c] for c in CLASSES)
            print(f"  {s:12s} {cells}  {'within' if ok else 'OUTSIDE'}  [{r['wall_s']:.0f} s]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
