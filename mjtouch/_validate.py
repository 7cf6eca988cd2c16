"""The checks every public entry point uses on its arguments.

Each raises ``ValueError`` naming the argument, its value and the valid range
(with units), never returns a silent default.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from typing import Any

import numpy as np


def _plain(value: Any) -> Any:
    """A numpy scalar as the Python number it holds (so messages read 0.5,
    not np.float64(0.5)); anything else unchanged."""
    return value.item() if isinstance(value, np.generic) else value


def _interval(lo: float, hi: float, lo_open: bool, hi_open: bool) -> str:
    return f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"


def positive(name: str, *values: Any) -> None:
    """Each value is a finite number > 0."""
    for v in map(_plain, values):
        if not (isinstance(v, numbers.Real) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name} = {v!r} must be a positive finite number")


def positive_number(name: str, value: Any, units: str = "") -> float:
    """A finite number > 0, as float; units name what it counts ("seconds")."""
    value = _plain(value)
    if not (isinstance(value, numbers.Real) and math.isfinite(value) and value > 0):
        of = f" of {units}" if units else ""
        raise ValueError(f"{name} = {value!r} must be a positive finite number{of}")
    return float(value)


def in_range(
    name: str,
    value: Any,
    lo: float,
    hi: float,
    units: str = "",
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> float:
    """value as float when lo <= value <= hi (either end open on request)."""
    interval = _interval(lo, hi, lo_open, hi_open)
    value = _plain(value)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} = {value!r} must be a number in {interval} {units}".rstrip())
    v = float(value)
    above = v > lo if lo_open else v >= lo
    below = v < hi if hi_open else v <= hi
    if not (math.isfinite(v) and above and below):
        raise ValueError(
            f"{name} = {value!r} is out of range; valid range {interval} {units}".rstrip()
        )
    return v


def integer_in_range(name: str, value: Any, lo: int, hi: int) -> int:
    """An integer lo <= value <= hi."""
    value = _plain(value)
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} = {value!r} must be an integer in [{lo}, {hi}]")
    if not lo <= value <= hi:
        raise ValueError(f"{name} = {value} is out of range; valid range [{lo}, {hi}]")
    return int(value)


def choice(name: str, value: Any, choices: Iterable[Any]) -> Any:
    """value when it is one of choices."""
    choices = tuple(choices)
    if value not in choices:
        raise ValueError(f"{name} = {value!r} is not one of {', '.join(map(repr, choices))}")
    return value
