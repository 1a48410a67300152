"""Movements the torque twin's motors can do: uniformly slowed, or re-timed locally.

The shipped CMU clips need more torque than the motors have at full speed
(:meth:`skinny_mj.plant.dynamics.Dynamics.feasibility`). Two ways to make one feasible:

- **Uniform slow-down** (:func:`fastest_uniform_speed`): the whole clip at one speed
  factor, the fastest on a grid (0.01, from 0.6 down to 0.05) at and below which no
  held step torque exceeds ``limit_ratio`` of a limit. Slow everywhere for the sake of
  a few bursts: at md_02's 0.18 in 2D most of the torque holds the arms up against
  gravity.
- **Local time scaling** (:func:`retime`): the clip along its own path
  (:func:`skinny_mj.trajectories.retime.path_spline`) with the time-optimal timing
  s(t) under the limits, by TOPP-RA (``toppra``): as fast as the shipped clip
  (path speed ṡ <= 1) wherever the limits allow, slower only where they do not. The
  constraints, at every path point of a grid of :data:`POINTS_PER_STEP` points per
  20 ms step, both ends of each interval (toppra's interpolation discretization):

  - joint torque within ``torque_margin`` (default :data:`TORQUE_MARGIN` = 0.9) of each
    limit, from the torque twin's inverse dynamics along the path
    (:func:`skinny_mj.plant.path_dynamics.path_torque_terms`, tau = a s̈ + b ṡ² + c + d ṡ).
    The joints' damping term d ṡ is linear in ṡ, which TOPP-RA's linear constraints in
    (s̈, ṡ²) cannot hold exactly; it is bounded from above by the tangent of the
    concave sqrt at ṡ0² (d ṡ <= |d| (ṡ² + ṡ0²) / (2 ṡ0)), exact at ṡ0 and conservative
    elsewhere, with ṡ0 = 1 first and then the previous pass's ṡ (:data:`PASSES` passes;
    each pass's timing is feasible, and the previous one is feasible for the next, so
    it is no slower up to toppra's numerical slack);
  - joint speed within :func:`skinny_mj.plant.path_dynamics.velocity_limits_rad_s`
    (30 rad/s; toppra's ``JointVelocityConstraint``), and ṡ <= 1.

  The timing is then sampled every control step (:func:`skinny_mj.trajectories.retime.
  resample`) and **checked with the project's own measure**: the held step torques of the
  sampled clip's clamped cubic spline (:func:`skinny_mj.plant.path_dynamics.
  step_torque_ratio`) and its spline speeds. The plan holds at its grid points only,
  and sampling at 50 Hz and the spline through the samples smooth its bang-bang path
  acceleration, which together can ask more than the plan where the path speed drops
  fast; if the check finds more than ``torque_margin`` of a limit (or a speed over its
  limit), the plan is redone with its limits scaled down by the excess (at most
  :data:`MAX_CHECKS` times; on the shipped clips the last plans use 0.80-0.84 of the
  limits), so a returned clip passes (else :class:`SkinnyInputError`).

A margin below 1 leaves a tracking controller headroom (the movement itself asks at
most 0.9 of a limit; feedback corrects with the rest). A movement name may ask for the
local re-timing: ``md_02.amc@feasible`` (margin 0.9) or ``md_02.amc@feasible=0.8``
(:func:`load_movement`, what the ``skinny`` commands load).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.body import Body, BodyLike, body_of
from skinny_mj.plant.path_dynamics import (
    gravity_share,
    path_torque_terms,
    step_torque_ratio,
    torque_dynamics,
    velocity_limits_rad_s,
)
from skinny_mj.trajectories import load_movement as _load_any
from skinny_mj.trajectories.retime import PathTiming, path_grid, path_spline, resample
from skinny_mj.trajectories.trajectory import Trajectory

#: Share of each torque limit the re-timed movement may ask (headroom for feedback).
TORQUE_MARGIN = 0.9
#: Path points per control step of the clip (the grid TOPP-RA plans on).
POINTS_PER_STEP = 8
#: Passes of the damping term's tangent bound (ṡ0 = 1, then the previous pass's ṡ).
PASSES = 3
#: Largest number of re-plans after the sampled clip's check.
MAX_CHECKS = 8
#: The uniform slow-down's grid: speeds from ``UNIFORM_STOP`` to ``UNIFORM_START`` every
#: ``UNIFORM_STEP`` (the study's: 0.01 from 0.6 down).
UNIFORM_STEP, UNIFORM_START, UNIFORM_STOP = 0.01, 0.6, 0.05
#: The movement-name suffix that asks for the local re-timing.
SUFFIX = "feasible"
_X_FLOOR = 1e-4  # smallest ṡ0² of the tangent bound (ṡ0 = 0.01)


# -- the measure ---------------------------------------------------------------------------
def peak_torque_ratio(traj: Trajectory, which: BodyLike) -> float:
    """Largest |held step torque| / limit of ``traj`` over its steps and DOFs (the
    ``peak_ratio`` of :meth:`Dynamics.feasibility`, its largest DOF)."""
    return float(step_torque_ratio(torque_dynamics(which), traj.angles, traj.dt).max())


def peak_speed_ratio(traj: Trajectory, which: BodyLike) -> float:
    """Largest |joint speed| / speed limit of ``traj``'s clamped cubic spline, at the
    4 Gauss nodes of each step (where :meth:`Dynamics.feasibility` reads its speeds)."""
    spline = path_spline(traj)
    t = traj.dt * np.arange(len(traj))
    nodes, _ = np.polynomial.legendre.leggauss(4)
    ts = (t[:-1, None] + 0.5 * traj.dt * (1.0 + nodes)).ravel()
    return float((np.abs(spline(ts, 1)) / velocity_limits_rad_s(which)).max())


def gravity_share_of(traj: Trajectory, which: BodyLike) -> float:
    """:func:`skinny_mj.plant.path_dynamics.gravity_share` of ``traj`` on the body's torque
    twin."""
    return gravity_share(torque_dynamics(which), traj.angles, traj.dt)


# -- uniform slow-down -------------------------------------------------------------------
def fastest_uniform_speed(traj: Trajectory, which: BodyLike, limit_ratio: float = 1.0,
                          step: float = UNIFORM_STEP, start: float = UNIFORM_START,
                          stop: float = UNIFORM_STOP) -> float:
    """The fastest speed factor on the grid ``stop``, ``stop + step``, ..., ``start`` at
    and below which (down to ``stop``) ``traj.resample(speed)`` asks at most
    ``limit_ratio`` of every torque limit (:func:`peak_torque_ratio`): scanned from
    ``stop`` up, the speed below the first that asks more (``start`` if none does).

    "At and below": near its edge a clip's need is not monotonic in the speed (the 3D
    md_02 passes at 0.48 but not at 0.46-0.47), and a speed with a slower failing one
    below it is not taken.
    """
    first, last = int(round(stop / step)), int(round(start / step))
    if not 1 <= first <= last:
        raise SkinnyInputError(f"the speed grid needs 0 < stop <= start, got {stop}, {start}")
    fastest = None
    for k in range(first, last + 1):
        speed = round(k * step, 10)
        if peak_torque_ratio(traj.resample(speed), which) > limit_ratio:
            break
        fastest = speed
    if fastest is None:
        raise SkinnyInputError(f"{traj.name!r} asks more than {limit_ratio:g} of a torque "
                               f"limit at speed {stop:g} already")
    return fastest


# -- local time scaling ------------------------------------------------------------------
@dataclass(frozen=True)
class Retimed:
    """A movement re-timed along its path: ``trajectory`` (sampled every control step),
    its ``timing`` (:class:`skinny_mj.trajectories.retime.PathTiming`), the share of the
    limits the last plan used (``planned_margin``: ``torque_margin`` unless the sampled
    clip's check scaled it down), and the check's ``peak_torque_ratio`` and
    ``peak_speed_ratio``."""

    trajectory: Trajectory
    timing: PathTiming
    torque_margin: float
    planned_margin: float
    peak_torque_ratio: float
    peak_speed_ratio: float

    def full_speed_share(self, tol: float = 1e-3) -> float:
        """Share of the re-timed clip's control steps played at the shipped speed
        (ṡ >= 1 - ``tol`` at the step's start)."""
        t = self.trajectory.dt * np.arange(len(self.trajectory) - 1)
        return float((self.timing.path_speed(t) >= 1.0 - tol).mean())


def _toppra_timing(path, grid, terms, limit_nm, vlim, x0):
    """One TOPP-RA solve: the time-optimal ṡ at ``grid`` (None if none exists)."""
    import toppra
    import toppra.algorithm
    import toppra.constraint as tc
    from toppra.constraint import DiscretizationType
    from toppra.constraint.linear_constraint import canlinear_colloc_to_interpolate

    a, b, c, d = terms
    n = a.shape[1]
    root = np.sqrt(x0)[:, None]
    bound_b, bound_c = np.abs(d) / (2.0 * root), np.abs(d) * root / 2.0
    rows = (np.hstack([a, a]), np.hstack([b + bound_b, b - bound_b]),
            np.hstack([c + bound_c, c - bound_c]))
    F = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), -np.eye(n)]])
    g = np.concatenate([limit_nm, limit_nm])

    class PathTorque(tc.LinearConstraint):
        """|a s̈ + b ṡ² + c + d ṡ| <= limit, d ṡ bounded by its tangent at x0."""

        def __init__(self):
            super().__init__()
            self.dof, self.identical = n, True
            self.set_discretization_type(DiscretizationType.Interpolation)
            self._format_string = "    path torque\n"

        def compute_constraint_params(self, path_, gridpoints):
            assert np.array_equal(gridpoints, grid)
            return canlinear_colloc_to_interpolate(*rows, F, g, None, None, grid,
                                                   identical=True)

    class PathSpeedCap(tc.LinearConstraint):
        """ṡ <= 1: never faster than the movement as shipped."""

        def __init__(self):
            super().__init__()
            self.dof = n
            self._format_string = "    path speed <= 1\n"

        def compute_constraint_params(self, path_, gridpoints):
            xbound = np.zeros((len(gridpoints), 2))
            xbound[:, 1] = 1.0
            return None, None, None, None, None, None, xbound

    solver = toppra.algorithm.TOPPRA(
        [tc.JointVelocityConstraint(vlim), PathSpeedCap(), PathTorque()], path,
        gridpoints=grid, solver_wrapper="seidel")
    _, sd, _ = solver.compute_parameterization(0.0, 0.0)
    if sd is None or not np.all(np.isfinite(sd)):
        return None
    return np.minimum(sd, 1.0)


def retime_movement(traj: Trajectory, which: BodyLike, torque_margin: float = TORQUE_MARGIN,
                    points_per_step: int = POINTS_PER_STEP) -> Retimed:
    """``traj`` re-timed along its path as fast as the body's torque twin allows with
    ``torque_margin`` of each torque limit and the joints' speed limits, never faster
    than shipped (see the module docstring)."""
    import logging

    import toppra

    if not (math.isfinite(torque_margin) and 0 < torque_margin <= 1):
        raise SkinnyInputError(f"torque margin must be in (0, 1], got {torque_margin}")
    skinny = body_of(which)
    if traj.dof != skinny.dof:
        raise SkinnyInputError(f"trajectory {traj.name!r} has {traj.dof} DOFs, the "
                               f"{skinny.name} body {skinny.dof}")
    logging.getLogger("toppra").setLevel(logging.ERROR)  # its retries are not our errors
    dyn = torque_dynamics(skinny)
    s_points = traj.dt * np.arange(len(traj))
    path = toppra.SplineInterpolator(s_points, traj.angles, bc_type="clamped")
    grid = path_grid(traj, points_per_step)
    terms = path_torque_terms(dyn, path(grid), path(grid, 1), path(grid, 2))
    limit, vlim = dyn.torque_limits_nm(), velocity_limits_rad_s(skinny)
    plan_margin, speed_scale = torque_margin, 1.0
    for _check in range(MAX_CHECKS + 1):
        x0 = np.ones(len(grid))
        sd = None
        for _pass in range(PASSES):
            found = _toppra_timing(path, grid, terms, plan_margin * limit,
                                   speed_scale * vlim, x0)
            if found is None:
                break
            sd, x0 = found, np.maximum(found ** 2, _X_FLOOR)
        if sd is None:
            raise SkinnyInputError(
                f"{traj.name!r} cannot be played within {plan_margin:.3g} of the torque "
                f"limits at any speed on the {skinny.name} body (holding a pose takes more)")
        timing = PathTiming(grid, sd)
        out = resample(traj, timing, name=f"{traj.name}@{SUFFIX}"
                       + (f"={torque_margin:g}" if torque_margin != TORQUE_MARGIN else ""))
        peak, speed = peak_torque_ratio(out, skinny), peak_speed_ratio(out, skinny)
        if peak <= torque_margin and speed <= 1.0:
            return Retimed(out, timing, torque_margin, plan_margin, peak, speed)
        plan_margin *= min(1.0, torque_margin / peak) * (1 - 1e-3)
        speed_scale *= min(1.0, 1.0 / speed) * (1 - 1e-3)
    raise SkinnyInputError(f"re-timing {traj.name!r} did not pass its check after "
                           f"{MAX_CHECKS} re-plans (peak {peak:.3f} of a limit)")


def retime(traj: Trajectory, which: BodyLike, torque_margin: float = TORQUE_MARGIN
           ) -> Trajectory:
    """:func:`retime_movement`'s trajectory: ``traj`` as fast as the limits allow, sampled
    every control step."""
    return retime_movement(traj, which, torque_margin).trajectory


# -- movement names ------------------------------------------------------------------------
def split_feasible(name: str) -> tuple[str, float | None]:
    """``"md_02.amc@feasible"`` -> ``("md_02.amc", 0.9)``, ``"X@feasible=0.8"`` ->
    ``("X", 0.8)``; a name without the suffix comes back with None."""
    base, at, tail = str(name).rpartition("@")
    key, eq, value = tail.strip().lower().partition("=")
    if not at or key != SUFFIX:
        return str(name), None
    if not eq:
        return base, TORQUE_MARGIN
    try:
        margin = float(value)
    except ValueError:
        margin = math.nan
    if not (math.isfinite(margin) and 0 < margin <= 1):
        raise SkinnyInputError(f"bad torque margin in {name!r}: use NAME@feasible or "
                               "NAME@feasible=MARGIN with 0 < MARGIN <= 1")
    return base, margin


@functools.lru_cache(maxsize=16)
def _retimed(base: str, skinny: Body, margin: float, kw: tuple):
    traj, report = _load_any(base, skinny, **dict(kw))
    return retime(traj, skinny, margin), report


def load_movement(name_or_path, body: BodyLike = "2d", *, speed: float = 1.0, reps: int = 1,
                  **kw):
    """:func:`skinny_mj.trajectories.load_movement`, and ``NAME@feasible[=MARGIN]``:
    the movement ``NAME`` (any name or file it accepts, excerpts too), at ``speed``,
    re-timed by :func:`retime` for the body's torque twin with that torque margin
    (default 0.9), then repeated ``reps`` times. Returns ``(trajectory, retarget
    report)``."""
    base, margin = split_feasible(str(name_or_path))
    if margin is None:
        return _load_any(name_or_path, body, speed=speed, reps=reps, **kw)
    extra = tuple(sorted((k, v if not hasattr(v, "__fspath__") else str(v))
                         for k, v in kw.items()))
    traj, report = _retimed(base, body_of(body), float(margin), (("speed", speed), *extra))
    return traj.repeat(reps), report
