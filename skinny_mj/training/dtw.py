"""Dynamic time warping distance through ``dtaidistance`` (a maintained C library).

``pip install "skinny-mj[metrics]"`` installs it; it is imported only when a DTW distance
is asked for, so the rest of Skinny-MJ runs without it.
"""

from __future__ import annotations

import numpy as np

from skinny_mj.errors import SkinnyInputError

__all__ = ["dtw_distance", "dtw_nrmse", "available"]


def available() -> bool:
    """True when dtaidistance can be imported."""
    try:
        import dtaidistance  # noqa: F401
    except ImportError:
        return False
    return True


def dtw_distance(actual: np.ndarray, target: np.ndarray, *, window: int | None = None
                 ) -> float:
    """Multivariate DTW distance: the square root of the smallest sum of squared
    Euclidean distances along any monotone alignment of the two series
    (``dtaidistance.dtw_ndim.distance_fast``).

    Parameters
    ----------
    actual, target : (T, n) and (T', n) signals (e.g. normalized joint angles).
    window : Sakoe-Chiba band, steps (None: unconstrained).
    """
    try:
        from dtaidistance import dtw_ndim
    except ImportError:
        raise SkinnyInputError("the DTW metric needs dtaidistance: pip install "
                               "'skinny-mj[metrics]'") from None
    a = np.ascontiguousarray(actual, dtype=np.double)
    b = np.ascontiguousarray(target, dtype=np.double)
    return float(dtw_ndim.distance_fast(a, b, window=window))


def dtw_nrmse(actual: np.ndarray, target: np.ndarray, *, window: int | None = 50,
              value_range: float = 2.0) -> float:
    """A time-warp-tolerant counterpart of the position NRMSE: DTW distance /
    sqrt(T n) / ``value_range`` for (T, n) series. On the identity alignment it equals
    the RMS over all signals / range, so it is at most that (the NRMSE with the error
    pooled over signals) and drops where the produced movement is right but late or
    early. ``window`` default: 50 steps = 1 s at 50 Hz."""
    a = np.asarray(actual, float)
    return dtw_distance(a, target, window=window) / np.sqrt(a.size) / value_range
