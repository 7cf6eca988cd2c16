"""``mjtouch probe``: a pin, sphere or vibrating plate on the fingertip."""

from __future__ import annotations

import argparse
import time

import numpy as np

from mjtouch.cli.types import positive_float, run_and_print

EXAMPLE = """example:
  mjtouch probe --waveform ramp --probe pin --depth 0.5e-3
  mjtouch probe --waveform sine --probe plate --amplitude 5e-6 --freq 200 --json"""


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "probe",
        help="a stimulus on the fingertip (displacement-controlled pin, "
        "sphere, or a vibrating plate under a pressed finger); "
        "prints firing rates per class",
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--waveform",
        choices=["ramp", "sine", "sines", "noise", "trace"],
        default="ramp",
        help="ramp-and-hold (default), sine, sum of sines, "
        "band-limited noise, or a trace from --trace FILE",
    )
    p.add_argument(
        "--probe",
        choices=["pin", "sphere", "plate"],
        default="pin",
        help="flat pin (default), sphere, or a vibrating plate under the finger "
        "pressed with --press",
    )
    p.add_argument(
        "--radius",
        type=positive_float("--radius"),
        default=0.5e-3,
        help="pin / sphere radius (m), default 5e-4",
    )
    p.add_argument(
        "--depth",
        type=positive_float("--depth"),
        default=0.5e-3,
        help="ramp: indentation (m), default 5e-4",
    )
    p.add_argument(
        "--ramp",
        type=positive_float("--ramp"),
        default=0.05,
        help="ramp time (s) of ramp-and-hold and of the sine envelopes, default 0.05",
    )
    p.add_argument(
        "--hold",
        type=positive_float("--hold"),
        default=0.5,
        help="ramp: hold time (s), default 0.5",
    )
    p.add_argument(
        "--amplitude",
        type=positive_float("--amplitude"),
        nargs="+",
        default=[10e-6],
        help="sine(s): amplitude(s) (m), default 1e-5",
    )
    p.add_argument(
        "--freq",
        type=positive_float("--freq"),
        nargs="+",
        default=[40.0],
        help="sine(s): frequency(ies) (Hz), default 40",
    )
    p.add_argument(
        "--duration",
        type=positive_float("--duration"),
        default=1.0,
        help="sine / noise duration (s), default 1",
    )
    p.add_argument(
        "--rms",
        type=positive_float("--rms"),
        default=5e-6,
        help="noise: RMS displacement (m), default 5e-6",
    )
    p.add_argument(
        "--band",
        type=float,
        nargs=2,
        default=[10.0, 500.0],
        metavar=("LO", "HI"),
        help="noise: band (Hz), default 10 500",
    )
    p.add_argument("--seed", type=int, default=0, help="noise: seed, default 0")
    p.add_argument(
        "--trace",
        metavar="FILE",
        help="trace: displacement samples (m), a .npy or a text file of numbers",
    )
    p.add_argument(
        "--trace-dt",
        type=positive_float("--trace-dt"),
        default=1e-3,
        help="trace: sample spacing (s), default 1e-3",
    )
    p.add_argument(
        "--preindent",
        type=float,
        default=None,
        help="pin/sphere: static indentation (m) under the waveform; default 0 for "
        "ramp, 5e-4 otherwise (so the probe stays in contact)",
    )
    p.add_argument(
        "--press",
        type=positive_float("--press"),
        default=0.5,
        help="plate: the finger's press force (N), default 0.5",
    )
    p.add_argument(
        "--dt",
        type=positive_float("--dt"),
        default=1e-4,
        help="simulation timestep (s), default 1e-4",
    )
    p.add_argument(
        "--nx",
        type=int,
        default=49,
        help="taxels per side, default 49 (odd: a taxel centre on the probe's axis)",
    )
    p.add_argument(
        "--pitch",
        type=positive_float("--pitch"),
        default=1.5e-4,
        help="taxel pitch (m), default 1.5e-4",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    return p


def run(args: argparse.Namespace) -> dict:
    from mjtouch.experiments import stimuli
    from mjtouch.scene import scenes

    if args.waveform == "ramp":
        w = stimuli.ramp_and_hold(args.depth, ramp_s=args.ramp, hold_s=args.hold)
    elif args.waveform == "sine":
        w = stimuli.sine(args.amplitude[0], args.freq[0], args.duration, args.ramp)
    elif args.waveform == "sines":
        w = stimuli.sum_of_sines(args.amplitude, args.freq, args.duration, args.ramp)
    elif args.waveform == "noise":
        w = stimuli.noise(args.rms, tuple(args.band), args.duration, args.seed, args.ramp)
    else:
        if not args.trace:
            raise ValueError("--waveform trace needs --trace FILE")
        vals = (
            np.load(args.trace) if args.trace.endswith(".npy") else np.loadtxt(args.trace).ravel()
        )
        w = stimuli.trace(vals, args.trace_dt)
    tip = scenes.Fingertip(nx=args.nx, pitch_m=args.pitch, ridges=False)
    t0 = time.perf_counter()
    if args.probe == "plate":
        res = stimuli.PlateScene(args.press, tip, timestep_s=args.dt).run(w)
    else:
        pre = (
            args.preindent
            if args.preindent is not None
            else (0.0 if args.waveform == "ramp" else 0.5e-3)
        )
        shape = stimuli.Probe(args.probe, radius_m=args.radius)
        res = stimuli.ProbeScene(shape, tip, preindent_m=pre, timestep_s=args.dt).run(w)
    out = res.summary()
    out.update(probe=args.probe, wall_s=time.perf_counter() - t0)
    return out


def print_human(o: dict) -> None:
    w = o["waveform"]
    print(
        f"mjtouch probe: {o['probe']}, {w['kind']} "
        + " ".join(f"{k}={v}" for k, v in w.items() if k != "kind" and not isinstance(v, list))
        + f" (wall {o['wall_s']:.1f} s)"
    )
    print("rates in the steady part (Hz), mean / max / centred unit:")
    for c, r in o["rates_hz"].items():
        print(
            f"  {c:3s} {r['mean']:8.1f} {r['max']:8.1f} {r['centre']:8.1f}   "
            f"({o['receptors'][c]} receptors)"
        )
    print(
        f"force {o['force_steady_mean_n']:.4g} N; displacement achieved to "
        f"{o['max_displacement_error_m'] * 1e6:.3g} um of commanded; finger moved "
        f"{o['finger_motion_max_m'] * 1e6:.3g} um"
    )
    print(
        "centred units' distance from the probe's axis (um): "
        + ", ".join(f"{c} {d * 1e6:.3g}" for c, d in o["centred_offaxis_m"].items())
    )


def main(args: argparse.Namespace) -> int:
    return run_and_print(args, run, print_human)
