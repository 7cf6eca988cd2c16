"""Argument types of the command line, on the checks of :mod:`mjtouch._validate`."""

from __future__ import annotations

import argparse
import math

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
