"""``mjtouch tuning``: threshold-frequency and rate-intensity curves per class."""

from __future__ import annotations

import argparse
import json
import time

from mjtouch.cli.types import positive_float, run_and_print

EXAMPLE = """example:
  mjtouch tuning --quick --json
  mjtouch tuning --freqs 20 50 200 --plot tuning.png"""


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "tuning",
        help="threshold-frequency (absolute, entrainment) and "
        "rate-intensity curves per afferent class, with "
        "published ranges",
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="a few seconds: 2 frequencies, coarse grid, small skin (for tests)",
    )
    p.add_argument(
        "--freqs",
        type=positive_float("--freqs"),
        nargs="+",
        default=None,
        help="vibration frequencies (Hz); default 5-600 Hz in 9 steps",
    )
    p.add_argument(
        "--min-cycles",
        type=int,
        default=None,
        help="cycles counted at least per sine (default 20; --quick 5)",
    )
    p.add_argument("--threads", type=int, default=2, help="rollout threads, default 2")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--out", metavar="FILE", help="also write the JSON to FILE")
    p.add_argument("--plot", metavar="FILE", help="write a PNG of both curves (matplotlib)")
    return p


def run(args: argparse.Namespace) -> dict:
    from mjtouch.experiments import tuning

    cfg = tuning.TuningConfig.quick() if args.quick else tuning.TuningConfig()
    if args.freqs:
        cfg.freqs_hz = tuple(args.freqs)
    if args.min_cycles is not None:
        cfg.min_cycles = args.min_cycles
    cfg.threads = args.threads
    t0 = time.perf_counter()
    out = tuning.run(cfg)
    out["wall_s"] = time.perf_counter() - t0
    if args.out:
        with open(args.out, "w") as f:
            json.dump(out, f, indent=1)
    if args.plot:
        tuning.plot(out, args.plot)
    return out


def print_human(o: dict) -> None:
    th = o["thresholds"]
    print(
        f"mjtouch tuning: thresholds (um) of the unit under the probe, absolute / 1:1, "
        f"[most sensitive unit's absolute] (wall {o['wall_s']:.1f} s)"
    )
    print("  f (Hz) " + "".join(f"{c:>26s}" for c in th["thresholds_m"]))
    for i, f in enumerate(th["freqs_hz"]):
        cells = []
        for v in th["thresholds_m"].values():
            a, e, b = (
                v["centred"]["absolute"][i],
                v["centred"]["entrainment"][i],
                v["best"]["absolute"][i],
            )
            cells.append(f"{a * 1e6:8.3g} /{e * 1e6:8.3g} [{b * 1e6:6.3g}]")
        print(f"  {f:6.1f} " + "".join(f"{x:>26s}" for x in cells))
    print(
        "  centred units' distance from the probe's axis (um): "
        + ", ".join(f"{c} {d * 1e6:.3g}" for c, d in th["centred_offaxis_m"].items())
    )
    ri = o["rate_intensity"]
    print(
        "rate-intensity (centred unit, Hz): depth (mm) "
        + " ".join(f"{d * 1e3:.2f}" for d in ri["depths_m"])
    )
    for c, r in ri["rates"].items():
        print(
            f"  {c:3s} hold  "
            + " ".join(f"{x:.0f}" for x in r["hold_hz"])
            + "   ramps "
            + " ".join(f"{x:.0f}" for x in r["ramp_hz"])
        )


def main(args: argparse.Namespace) -> int:
    return run_and_print(args, run, print_human)
