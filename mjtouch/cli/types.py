"""Argument types of the command line, on the checks of :mod:`mjtouch._validate`,
and the run-then-print shape the subcommands share."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable

from mjtouch import _validate


def positive_float(name: str):
    """An argparse type: a positive finite number, the error naming option ``name``."""

    def parse(token: str) -> float:
        try:
            value = float(token)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{token!r} is not a number") from None
        try:
            return _validate.in_range(name, value, 0.0, math.inf, lo_open=True, hi_open=True)
        except ValueError as e:  # argparse names the option before the message
            raise argparse.ArgumentTypeError(str(e).removeprefix(f"{name} = ")) from None

    return parse


def run_and_print(
    args: argparse.Namespace,
    run: Callable[[argparse.Namespace], dict],
    print_human: Callable[[dict], None],
) -> int:
    """Run a subcommand; print its result as JSON (``--json``) or as text.
    A ValueError is the user's input: printed as an error, exit status 2."""
    try:
        out = run(args)
    except ValueError as e:
        print(f"mjtouch: error: {e}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(out))
    else:
        print_human(out)
    return 0
