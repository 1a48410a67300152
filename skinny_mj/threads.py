"""One BLAS thread wherever a run computes, so a seed gives the same bits whatever the
machine's thread settings.

OpenBLAS splits some products and factorizations over its threads, and the split changes
the order of floating-point sums: the same training run gave metrics differing by ~1e-14
under ``OPENBLAS_NUM_THREADS=1`` and ``=2``. The engine's workers already start with one
thread; :func:`one_blas_thread` pins the calling process too (the parent of a sweep, the
commands, the Python API), through threadpoolctl, for the duration of a call.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import ParamSpec, TypeVar

from threadpoolctl import threadpool_limits

__all__ = ["one_blas_thread", "single_threaded"]

P = ParamSpec("P")
T = TypeVar("T")


def one_blas_thread() -> threadpool_limits:
    """A context in which BLAS and OpenMP libraries use one thread (restored on exit)."""
    return threadpool_limits(limits=1)


def single_threaded(fn: Callable[P, T]) -> Callable[P, T]:
    """``fn`` run inside :func:`one_blas_thread`."""

    @functools.wraps(fn)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> T:
        with one_blas_thread():
            return fn(*args, **kwargs)

    return wrapper
