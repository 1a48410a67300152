"""Motor babbling: smooth random joint movements that cover the body's joint space.

Paper A's discussion suggests pre-training the inverse model on random movements before
it learns a dance. :func:`babble` draws them: every DOF independently runs a chain of
minimum-jerk segments (Flash & Hogan 1985, J. Neurosci. 5:1688, the velocity profile of
unconstrained human point-to-point arm movements) between targets drawn uniformly
inside its joint range (1e-3 rad inside the limits). Each segment's peak speed is drawn
uniformly in ``[v_min, v_max]`` rad/s; its duration follows from the minimum-jerk peak
speed 1.875 |Δq| / T, bounded to ``[min_segment_s, max_segment_s]``. Default speeds span
the human movements shipped here: YMCA peaks at 5-7 rad/s, the CMU modern-dance clips
at 8-12 rad/s (md_03) and 13-18 rad/s at their 99th percentile (md_02). A minimum-jerk
segment starts and ends at rest (zero speed and acceleration), so the chain is smooth
(C²) at every junction.

Real dance also rests and holds its arms straight: the elbows of the CMU modern-dance
clips are within 3° of their limit for 34-47 % of md_02's samples, where uniform targets
put a joint that close to a limit for 1-2 % of the time. ``limits`` and ``holds`` draw
such segments: with probability ``holds`` a segment is a rest of 0.2-1 s, with
probability ``limits`` its target is one of the joint's two limits (each equally
likely), else it is uniform as above. With both 0 (the default) the draws are the
ones above, bit for bit.

The name syntax (``get("babble:seed=3,duration=20,limits=0.5,holds=0.2")``) is parsed by
:func:`parse_babble_name`; :func:`bridge` is the minimum-jerk joining segment the
training sets of :mod:`skinny_mj.trajectories.library` put between their pieces.
Pure NumPy, every draw from a Generator seeded by ``seed``.
"""

from __future__ import annotations

import math

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.trajectories.trajectory import DEFAULT_DT_S, Trajectory, check_size

__all__ = ["babble", "bridge", "min_jerk", "parse_babble_name", "BABBLE_KEYS"]

#: Margin kept inside the joint limits, rad (the plant's range clip never bites).
LIMIT_MARGIN_RAD = 1e-3
#: Keys of the name syntax and their defaults: seed, duration (s), peak speeds (rad/s),
#: the probabilities of a segment to a joint limit and of a rest.
BABBLE_KEYS = {"seed": 0.0, "duration": 20.0, "vmin": 1.0, "vmax": 8.0, "limits": 0.0,
               "holds": 0.0}
#: Duration range of a rest (``holds``), s.
HOLD_S = (0.2, 1.0)


def min_jerk(q0: np.ndarray, q1: np.ndarray, n: int) -> np.ndarray:
    """(n, ...) the minimum-jerk path from q0 to q1 sampled at s = 1/n, ..., 1 (q0 excluded,
    q1 included): q0 + (q1 - q0)(10 s³ - 15 s⁴ + 6 s⁵)."""
    s = np.arange(1, n + 1, dtype=float) / n
    shape = s**3 * (10.0 - 15.0 * s + 6.0 * s**2)
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    return q0 + np.multiply.outer(shape, q1 - q0)


def babble(which: body.BodyLike, *, seed: int = 0, duration_s: float = 20.0, v_min: float = 1.0,
           v_max: float = 8.0, limits: float = 0.0, holds: float = 0.0,
           dt: float = DEFAULT_DT_S, min_segment_s: float = 0.3,
           max_segment_s: float = 3.0) -> Trajectory:
    """A babbling movement of ``duration_s`` seconds for the body ``which``.

    Parameters
    ----------
    seed : seeds the Generator of every draw (targets, speeds, start pose).
    duration_s : length, s (``round(duration_s / dt)`` steps, at least 2).
    v_min, v_max : range of the segments' peak joint speeds, rad/s.
    limits : probability that a segment's target is one of the joint's limits.
    holds : probability that a segment is a rest of :data:`HOLD_S` seconds.
    dt : sample interval, s.
    min_segment_s, max_segment_s : bounds on one segment's duration, s (the lower bound
        caps the peak acceleration of long segments, 5.77 |Δq| / T² rad/s²).

    Returns
    -------
    Trajectory (T, n_dof), rad, every angle at least 1e-3 rad inside the joint ranges.
    """
    skinny = body.body_of(which)
    dof = skinny.dof
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise SkinnyInputError(f"babble duration must be > 0 s, got {duration_s}")
    if not (math.isfinite(v_min) and math.isfinite(v_max) and 0 < v_min <= v_max):
        raise SkinnyInputError(f"babble needs 0 < vmin <= vmax rad/s, got {v_min}, {v_max}")
    if not (0 <= limits and 0 <= holds and limits + holds <= 1):
        raise SkinnyInputError(f"babble needs limits, holds >= 0 with limits + holds <= 1, "
                               f"got {limits}, {holds}")
    rng = np.random.default_rng(int(seed))
    lo, hi = (skinny.joint_ranges() + [LIMIT_MARGIN_RAD, -LIMIT_MARGIN_RAD]).T
    steps = max(2, int(round(duration_s / dt)))
    check_size(steps, dof, f"babble duration {duration_s:g} s: {steps} steps")
    out = np.empty((steps, dof))
    for j in range(dof):  # each DOF its own chain: the joint space is covered as a product
        q = rng.uniform(lo[j], hi[j])
        pieces = [np.array([q])]
        n_done = 1
        while n_done < steps:
            # the segment's kind is drawn only when asked for: the default keeps its draws
            kind = rng.uniform() if limits or holds else 1.0
            if kind < holds:
                n = max(1, int(round(rng.uniform(*HOLD_S) / dt)))
                pieces.append(np.full(n, q))
                n_done += n
                continue
            if kind < holds + limits:
                target = lo[j] if rng.uniform() < 0.5 else hi[j]
            else:
                target = rng.uniform(lo[j], hi[j])
            peak = rng.uniform(v_min, v_max)
            seg_s = np.clip(1.875 * abs(target - q) / peak, min_segment_s, max_segment_s)
            n = max(1, int(round(seg_s / dt)))
            pieces.append(min_jerk(q, target, n))
            n_done += n
            q = target
        out[:, j] = np.concatenate(pieces)[:steps]
    extra = "".join(f",{k}={v:g}" for k, v in (("limits", limits), ("holds", holds)) if v)
    return Trajectory(out, dt, f"babble:seed={int(seed)},duration={duration_s:g}{extra}",
                      body=skinny.name)


def bridge(q0: np.ndarray, q1: np.ndarray, dt: float = DEFAULT_DT_S, *, peak_rad_s: float = 2.0,
           min_s: float = 0.5) -> np.ndarray:
    """(n, n_dof) a minimum-jerk joining segment from pose q0 to q1 (q0 excluded, q1
    included) whose fastest joint peaks at ``peak_rad_s``, at least ``min_s`` long: the
    washout between the pieces of a training set (slow, so it asks no new commands)."""
    dist = float(np.max(np.abs(np.asarray(q1, float) - np.asarray(q0, float))))
    n = max(int(round(min_s / dt)), int(math.ceil(1.875 * dist / peak_rad_s / dt)), 1)
    return min_jerk(q0, q1, n)


def parse_babble_name(name: str) -> dict[str, float] | None:
    """``"babble"`` / ``"babble:seed=3,duration=20,vmin=1,vmax=8"`` -> the parameters
    (:data:`BABBLE_KEYS`' defaults filled in); None for a name that is not babbling."""
    text = str(name).strip().lower()
    head, colon, spec = text.partition(":")
    if head != "babble" or (colon and not spec):
        return None if head != "babble" else _bad(name)
    values = dict(BABBLE_KEYS)
    seen: set[str] = set()
    for item in filter(None, spec.split(",")):
        key, eq, value = (p.strip() for p in item.partition("="))
        if not eq or key not in BABBLE_KEYS or key in seen:
            _bad(name)
        seen.add(key)
        try:
            values[key] = float(value)
        except ValueError:
            _bad(name)
    if values["seed"] != int(values["seed"]) or values["seed"] < 0:
        raise SkinnyInputError(f"babble seed must be a whole number >= 0 in {name!r}")
    return values


def _bad(name: str):
    keys = ",".join(f"{k}=" for k in BABBLE_KEYS)
    raise SkinnyInputError(f"bad babble name {name!r}: use babble or babble:{keys} "
                           "(seed, seconds, rad/s)")
