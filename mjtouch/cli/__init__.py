"""Command line: ``python -m mjtouch slide | view | bench | sweep | probe | tuning`` (also the
``mjtouch`` script). One module per subcommand, each a thin argparse layer over
:mod:`mjtouch.experiments` (``add_parser`` and ``main``)."""

from __future__ import annotations

import argparse

from mjtouch.cli import probe, slide, sweep, tuning, view

BENCH_EXAMPLE = """example:
  mjtouch bench --quick
  mjtouch bench --knobs pitch,pressure --plot bench.png --save-json bench.json"""


def _bench_parser(sub) -> argparse.ArgumentParser:
    from mjtouch import bench

    p = sub.add_parser(
        "bench",
        help="what accuracy costs in time: sweeps each knob of the "
        "default sliding scene against a converged reference",
        description=bench.__doc__.split("\n\n")[0],
        epilog=BENCH_EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    bench.add_arguments(p)
    return p


def _bench_main(args: argparse.Namespace) -> int:
    from mjtouch import bench

    return bench.main(args)


COMMANDS = {
    "slide": (slide.add_parser, slide.main),
    "view": (view.add_parser, view.main),
    "bench": (_bench_parser, _bench_main),
    "sweep": (sweep.add_parser, sweep.main),
    "probe": (probe.add_parser, probe.main),
    "tuning": (tuning.add_parser, tuning.main),
}


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="mjtouch", description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    for add, _ in COMMANDS.values():
        add(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    return COMMANDS[args.command][1](args)
