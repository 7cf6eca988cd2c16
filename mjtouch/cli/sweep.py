"""``mjtouch sweep``: slide over the product of several values of its
parameters (the fields of :class:`mjtouch.experiments.slide.SlideParams`)."""

from __future__ import annotations

import argparse
import json
import sys

from mjtouch import progress
from mjtouch.experiments import slide, sweep

EXAMPLE = """example:
  mjtouch sweep --out runs/ --period 0.6e-3 1.2e-3 --speed 0.02:0.04:0.01 --serial
  mjtouch sweep --config examples/sweep.toml --out runs/ --num-cpus 2"""


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "sweep",
        help="slide over the product of several values of its options, "
        "on Ray (or --serial); one Parquet row per run",
        description=sweep.__doc__.split("\n\n")[1],
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_arguments(p)
    return p


def add_arguments(p: argparse.ArgumentParser) -> None:
    """sweep's options: every SlideParams field as its slide option taking
    several values, then where and how to run."""
    for f in slide.fields():
        kind, choices = f.metadata["kind"], f.metadata["choices"]
        metavar = {"bool": "BOOL", "str": "CHOICE" if choices else "TEXT", "int": "N"}.get(
            kind, "X"
        )
        help_ = slide.describe(f)
        if choices:
            help_ += f"; choices {', '.join(choices)}"
        if kind == "bool":
            help_ += "; true, false or both"
        if kind in ("int", "float"):
            help_ += "; values or START:STOP:STEP"
        p.add_argument(
            slide.flag(f), dest=f.name, nargs="+", metavar=metavar, default=None, help=help_
        )
    p.add_argument(
        "--config",
        metavar="TOML",
        help="a TOML file of parameters (command-line options override its keys)",
    )
    p.add_argument(
        "--out",
        required=True,
        metavar="DIR",
        help="output directory: DIR/sweep.parquet and DIR/runs/ (runs already there are skipped)",
    )
    p.add_argument("--serial", action="store_true", help="run in this process, without Ray")
    p.add_argument(
        "--address",
        default=None,
        help="join the Ray cluster at this address (e.g. HEAD_IP:6379, as printed by "
        "`ray start --head`; or auto); default: start a local one",
    )
    p.add_argument(
        "--num-cpus",
        type=int,
        default=None,
        help="CPUs of the local Ray cluster (default: all of this machine's)",
    )
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    progress.add_argument(p)


def main(args: argparse.Namespace) -> int:
    given = {
        f.name: getattr(args, f.name) for f in slide.fields() if getattr(args, f.name) is not None
    }
    problem = None
    if args.num_cpus is not None and args.num_cpus < 1:
        problem = f"--num-cpus {args.num_cpus} must be >= 1"
    elif args.num_cpus is not None and (args.address or args.serial):
        problem = "--num-cpus sizes the local Ray cluster; not with --address or --serial"
    elif args.address and args.serial:
        problem = "--address joins a Ray cluster; not with --serial"
    if problem:
        print(f"mjtouch sweep: error: {problem}", file=sys.stderr)
        return 2
    try:
        result = sweep.run(
            given,
            args.out,
            config=args.config,
            serial=args.serial,
            address=args.address,
            num_cpus=args.num_cpus,
            progress=progress.wanted(args.progress, args.json),
        )
    except (ValueError, ImportError, ConnectionError) as e:
        print(f"mjtouch sweep: error: {e}", file=sys.stderr)
        return 2
    s = result.summary()
    if args.json:
        print(json.dumps(s))
    else:
        n, w = s["runs"], s["workers"]
        print(
            f"mjtouch sweep: {n} run{'s' * (n != 1)} ({s['ran']} ran, {s['skipped']} already "
            f"in {args.out}, {len(s['failed'])} failed) on {s['backend']} ({w} worker "
            f"process{'es' * (w != 1)}), wall {s['wall_s']:.1f} s ({s['startup_s']:.1f} s "
            f"starting) -> {s['table']}"
        )
    for f in s["failed"]:
        print(f"mjtouch sweep: run failed: {f['error']}  ({f['params']})", file=sys.stderr)
    return 1 if s["failed"] else 0
