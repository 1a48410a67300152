"""The numeric flags of every ``skinny`` command that are not training settings, checked
once after parsing.

argparse has converted each flag to its type (``int`` or ``float``); :func:`check_args`
then refuses, with one line naming the flag, a value out of its range: a negative seed,
an image of no pixels, a speed of 0, a NaN or infinite number. The same rule holds
whichever command takes the flag (``--seed`` of train, test, track and demo alike). The
flags that set a training setting (``--reservoir``, ``--beta``, ...) are checked by the
config's own parts (:mod:`skinny_mj.cli.config_flags`).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import Any

from skinny_mj.errors import SkinnyInputError
from skinny_mj.trajectories.trajectory import MAX_SPEED, MIN_SPEED

__all__ = ["RULES", "check_args", "check_value"]


def _at_least(low: float) -> Callable[[float], bool]:
    return lambda v: v >= low


def _above(low: float) -> Callable[[float], bool]:
    return lambda v: v > low


def _within(low: float, high: float, *, open_low: bool = False) -> Callable[[float], bool]:
    return lambda v: (v > low if open_low else v >= low) and v <= high


#: dest -> (kind, test, the range in words). Every value must also be finite.
RULES: dict[str, tuple[type, Callable[[float], bool], str]] = {
    "seed": (int, _at_least(0), ">= 0"),
    "reps": (int, _at_least(1), ">= 1"),
    "runs": (int, _at_least(1), ">= 1"),
    "workers": (int, _at_least(1), ">= 1"),
    "frame": (int, _at_least(0), ">= 0"),
    "width": (int, _within(1, 640), "in [1, 640]"),
    "height": (int, _within(1, 480), "in [1, 480]"),
    "web_port": (int, _within(1, 65535), "in [1, 65535]"),
    "grpc_port": (int, _within(1, 65535), "in [1, 65535]"),
    "speed": (float, _within(MIN_SPEED, MAX_SPEED, open_low=True),
              f"in ({MIN_SPEED:g}, {MAX_SPEED:g}]"),
}


def check_value(dest: str, value: Any) -> None:
    """Refuse ``value`` for the flag ``dest`` (a key of :data:`RULES`) when it is not a
    finite number of the flag's kind in its range; None (not given) passes."""
    if value is None or dest not in RULES:
        return
    kind, ok, words = RULES[dest]
    flag = "--" + dest.replace("_", "-")
    is_number = isinstance(value, int | float) and not isinstance(value, bool)
    if not is_number or (kind is int and not isinstance(value, int)):
        raise SkinnyInputError(f"{flag} must be a {'whole number' if kind is int else 'number'}"
                               f" {words}, got {value!r}")
    if not math.isfinite(value) or not ok(value):
        raise SkinnyInputError(f"{flag} must be {words}, got {value:g}"
                               if kind is float else f"{flag} must be {words}, got {value}")


def check_args(args: argparse.Namespace) -> None:
    """Every numeric flag of a parsed ``skinny`` command line, in :data:`RULES`'s order."""
    values = vars(args)
    for dest in RULES:
        check_value(dest, values.get(dest))
