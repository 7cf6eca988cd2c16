"""``python -m mjtouch bench``: arguments and main."""

from __future__ import annotations

import json
import sys

from mjtouch import progress
from mjtouch.bench.configs import BenchConfig
from mjtouch.bench.report import plot, print_markdown, print_report
from mjtouch.bench.runner import Bench, Progress


def add_arguments(p) -> None:
    p.add_argument(
        "--quick",
        action="store_true",
        help="a tiny sweep on small grids (well under a minute; for CI)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--markdown",
        action="store_true",
        help="print the accuracy table and the baselines as Markdown (docs/performance.md)",
    )
    p.add_argument("--plot", metavar="FILE", help="write a PNG: error vs cost, baselines, effects")
    p.add_argument("--save-json", metavar="FILE", help="also write the JSON object to FILE")
    p.add_argument(
        "--from-json",
        metavar="FILE",
        help="run nothing: print the table (and --plot) of a saved --save-json FILE",
    )
    p.add_argument(
        "--duration",
        type=float,
        default=None,
        help="sliding seconds per knob row (default 0.25; --quick 0.12)",
    )
    p.add_argument(
        "--time-steps",
        type=int,
        default=None,
        help="steps per timed repeat (default 200; --quick 60)",
    )
    p.add_argument(
        "--repeats",
        type=int,
        default=None,
        help="timing rounds over every configuration; the minimum is reported "
        "(default 8; --quick 3)",
    )
    p.add_argument(
        "--elastic-steps",
        type=int,
        default=None,
        help="sliding steps of the pressure knob, whose reference is the slow elastic "
        "model (default 300; --quick 120)",
    )
    p.add_argument(
        "--knob-steps",
        action="append",
        default=[],
        metavar="KNOB=N",
        help="sliding steps of one knob's rows (repeatable)",
    )
    p.add_argument(
        "--knobs",
        default=None,
        help="comma-separated knobs to sweep (default all: pitch, pressure, skin, "
        "stress_method, receptors, timestep, presets)",
    )
    p.add_argument(
        "--hand",
        action="store_true",
        help="run only the hand row: five skins on Gymnasium-Robotics' Shadow hand at 2 ms, "
        "bare / idle / pressed, rl preset and default (mjtouch.bench.hand; --quick: a smoke run)",
    )
    p.add_argument("--no-effects", action="store_true", help="skip the effects table")
    p.add_argument("--no-threads", action="store_true", help="skip the threads measurement")
    p.add_argument("--no-progress", action="store_true", help="no progress bar (--progress off)")
    progress.add_argument(p)


def config_from_args(args) -> BenchConfig:
    kw = {}
    for name, attr in (
        ("duration", "duration_s"),
        ("time_steps", "time_steps"),
        ("repeats", "repeats"),
        ("elastic_steps", "elastic_steps"),
    ):
        v = getattr(args, name)
        if v is not None:
            kw[attr] = v
    steps = {}
    for item in args.knob_steps:
        name, sep, n = item.partition("=")
        try:
            steps[name.strip()] = int(n)
        except ValueError:
            raise ValueError(f"--knob-steps {item!r} is not KNOB=N with N an integer") from None
        if not sep:
            raise ValueError(f"--knob-steps {item!r} is not KNOB=N")
    kw["knob_steps"] = steps
    if args.knobs:
        kw["knobs"] = tuple(s.strip() for s in args.knobs.split(",") if s.strip())
    kw["effects"] = not args.no_effects
    kw["threads"] = not args.no_threads
    cfg = BenchConfig.quick_config(**kw) if args.quick else BenchConfig(**kw)
    cfg.validate()
    return cfg


def main(args) -> int:
    if args.hand:
        from mjtouch.bench import hand

        hand_args = ["--quick"] if args.quick else []
        if args.time_steps is not None:
            hand_args += ["--steps", str(args.time_steps)]
        if args.repeats is not None:
            hand_args += ["--repeats", str(args.repeats)]
        return hand.main(hand_args)
    try:
        cfg = config_from_args(args)
    except ValueError as e:
        print(f"mjtouch bench: error: {e}", file=sys.stderr)
        return 2
    if args.plot:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            print(
                "mjtouch bench: error: --plot needs matplotlib: pip install 'mjtouch[plot]'",
                file=sys.stderr,
            )
            return 2
    if args.from_json:
        try:
            with open(args.from_json) as f:
                out = json.load(f)
            out["rows"], out["baselines"]  # noqa: B018  (a bench JSON object)
        except (OSError, ValueError, KeyError, TypeError) as e:
            print(
                f"mjtouch bench: error: --from-json {args.from_json}: not a saved bench "
                f"result ({e})",
                file=sys.stderr,
            )
            return 2
    else:
        bench = Bench(cfg)
        mode = "off" if args.no_progress else args.progress
        bench.progress = Progress(
            bench.count_tasks(), desc="bench", enabled=progress.wanted(mode, args.json)
        )
        out = bench.run()
        bench.progress.close()
    if args.plot:
        plot(out, args.plot)
        out["plot"] = args.plot
    text = json.dumps(out, allow_nan=False)
    if args.save_json:
        with open(args.save_json, "w") as f:
            f.write(text + "\n")
    if args.json:
        print(text)
    elif args.markdown:
        print_markdown(out)
    else:
        print_report(out)
    return 0
