"""How ``skinny bench`` times a figure: both sides in one process, interleaved.

A module of its own so that ``skinny bench`` and the benchmarks under ``benchmarks/`` time
the same way.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np


def interleaved(fns: dict[str, Callable[[], Any]], repeats: int) -> dict[str, float]:
    """Best wall time (s) of each callable over ``repeats`` interleaved rounds."""
    best = {k: np.inf for k in fns}
    for _ in range(repeats):
        for key, fn in fns.items():
            start = time.perf_counter()
            fn()
            best[key] = min(best[key], time.perf_counter() - start)
    return best
