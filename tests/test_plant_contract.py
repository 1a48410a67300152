"""One contract over every :class:`skinny_mj.controllers.plant.Plant` (as dm_control's suite_test
runs one over every task): the pure-NumPy ToyPlant, EnvPlant (dm_control), BatchPlant
(velocity servo and torque twin) and paper B's BimanualPlant, each at 4 and 8 DOF with
joint and Cartesian signals.

Every case is driven the same way: episodes of ``EPISODE`` steps (then ``reset``) under
piecewise-constant random commands. Plant-specific facts live in :class:`Case` only, so
a new plant (or a changed constructor) is one factory function.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pytest
from skinny_mj.controllers.plant import Plant, ToyPlant

from skinny_mj.plant import body
from skinny_mj.plant.ideal import max_speeds
from skinny_mj.trajectories import Trajectory

EPISODE = 60  # steps per episode; the stand-in movement has EPISODE + 1 samples
SEEDS = [11, 12, 13]
OTHER_SEEDS = [21, 22, 23]
# The velocity servo tracks a velocity step to < 1 % within one 20 ms step (the model
# card's and skinny_defaults.xml's kv claim; measured 0.17 % in 2D, 0.11 % in 3D).
SERVO_TRACKING = 0.01
# Statistical checks use 5 standard errors: a false alarm has probability < 1e-6 per
# check for Gaussian noise (and the seeds are fixed, so a pass is a pass for good).
Z = 5.0
# MuJoCo joint limits are soft constraints: the torque twin may pass a limit a little
# (a few degrees) while the constraint pushes back. The velocity servo never targets
# a joint past LIMIT_MARGIN_RAD inside its range, so there it is exact.
SOFT_LIMIT_RAD = 0.05


def stand_in(dof: int) -> Trajectory:
    """A smooth movement whose first pose is inside every range, off any symmetry."""
    t = np.linspace(0.0, 1.0, EPISODE + 1)[:, None]
    lo, hi = body.body_of(dof).joint_ranges().T
    return Trajectory(lo + (hi - lo) * (0.5 + 0.4 * np.sin(2 * np.pi * t + np.arange(dof))))


# -- the implementations -------------------------------------------------------------------
def _toy(dof: int, signals: str) -> Callable:
    traj = stand_in(dof)
    signal_map = {"joint": "joint", "cartesian": "planar_arm"}[signals]  # its x-z analogue

    def make(seeds: Sequence[int], noise: float) -> Plant:
        return ToyPlant(len(seeds), traj.angles[0], body.body_of(dof).joint_ranges(),
                        max_speeds(traj.angles, traj.dt), traj.dt, signal_map,
                        sensor_noise_std=noise, rngs=[np.random.default_rng(s) for s in seeds])
    return make


def _env(dof: int, signals: str, actuation: str) -> Callable:
    from skinny_mj.plant.adapters import EnvPlant
    from skinny_mj.plant.task import load

    def make(seeds: Sequence[int], noise: float) -> Plant:
        (seed,) = seeds
        return EnvPlant(load(body.body_of(dof).twin(actuation), signals, stand_in(dof), noise,
                             seed=seed))
    return make


def _batch(dof: int, signals: str, actuation: str) -> Callable:
    from skinny_mj.plant.adapters import BatchPlant

    def make(seeds: Sequence[int], noise: float) -> Plant:
        return BatchPlant(body.body_of(dof).twin(actuation), signals, stand_in(dof),
                          n_runs=len(seeds), seeds=list(seeds), sensor_noise=noise)
    return make


def _bimanual(dof: int, signals: str) -> Callable:
    from skinny_mj.plant.bimanual import BimanualPlant

    traj = stand_in(dof)

    def make(seeds: Sequence[int], noise: float) -> Plant:
        return BimanualPlant(dof, signals, traj, "right", max_speeds(traj.angles, traj.dt),
                             n_runs=len(seeds), seeds=list(seeds), sensor_noise=noise)
    return make


@dataclass(frozen=True)
class Case:
    """One plant configuration and what the contract may expect of it.

    make : (seeds, sensor noise std) -> plant with len(seeds) runs.
    dof : the body's DOF (``joint_angles()`` has one column per body joint).
    commanded : joint_angles columns the command drives (all but a forced leading arm).
    velocity : the command is a normalized velocity (the Jacobian predicts the step).
    amp : |command| of the random commands where a property other than robustness is
        checked: beyond full scale (clipping everywhere) for the kinematic plants; 0.3
        for the torque twin, which full random torques drive through its joint limits
        (see the xfails of the two robustness tests).
    mj_data : plant -> its ``mujoco.MjData`` (None without MuJoCo), for its warnings.
    """

    name: str
    make: Callable[[Sequence[int], float], Plant]
    dof: int
    signals: str
    n_runs: int
    n_dof: int
    n_signals: int
    commanded: tuple[int, ...]
    velocity: bool = True
    amp: float = 1.5
    mj_data: Callable[[Plant], object] | None = None


def _case(kind: str, make: Callable, dof: int, signals: str, n_runs: int, **kw) -> Case:
    kw.setdefault("n_dof", dof)
    kw.setdefault("n_signals", body.body_of(dof).n_signals(signals))
    kw.setdefault("commanded", tuple(range(dof)))
    return Case(f"{kind}-{dof}dof-{signals}", make, dof, signals, n_runs, **kw)


def _cases() -> list[Case]:
    torque = {"velocity": False, "amp": 0.3}
    env = {"mj_data": lambda p: p.physics.data.ptr}
    batch = {"mj_data": lambda p: p.data}
    cases = []
    for dof, sig in itertools.product((4, 8), ("joint", "cartesian")):
        cases += [
            _case("toy", _toy(dof, sig), dof, sig, 3,
                  n_signals=dof if sig == "joint" else 2 * dof),
            _case("env", _env(dof, sig, "velocity"), dof, sig, 1, **env),
            _case("env-torque", _env(dof, sig, "torque"), dof, sig, 1, **torque, **env),
            _case("batch", _batch(dof, sig, "velocity"), dof, sig, 3, **batch),
            _case("batch-torque", _batch(dof, sig, "torque"), dof, sig, 3, **torque, **batch),
            # the right arm leads (forced), the left arm is commanded
            _case("bimanual", _bimanual(dof, sig), dof, sig, 2, n_dof=dof // 2,
                  commanded=tuple(range(dof // 2, dof)), mj_data=lambda p: p.whole.data),
        ]
    return cases


CASES = _cases()
VELOCITY_CASES = [c for c in CASES if c.velocity]
_TORQUE_LIMITS = ("torque twin: its soft joint limits give way, full random torques push "
                  "joints 0.7-1 rad past their ranges")


def _params(cases: list[Case], xfail: Callable[[Case], str | None] = lambda c: None):
    """Cases as pytest params; ``xfail(case)`` names a known plant defect (strict)."""
    return [pytest.param(c, id=c.name, marks=[pytest.mark.xfail(reason=xfail(c), strict=True)]
                         if xfail(c) else []) for c in cases]


def _seeds(case: Case, seeds: list[int] = SEEDS) -> list[int]:
    return seeds[: case.n_runs]


# -- driving a plant ---------------------------------------------------------------------
def commands(case: Case, n_steps: int, amp: float | None = None, hold: int = 5,
             seed: int = 0) -> np.ndarray:
    """(n_steps, R, n_dof) random commands in [-amp, amp], each held for ``hold`` steps."""
    amp = case.amp if amp is None else amp
    rng = np.random.default_rng(seed)
    n_blocks = -(-n_steps // hold)
    blocks = rng.uniform(-amp, amp, (n_blocks, case.n_runs, case.n_dof))
    return np.repeat(blocks, hold, axis=0)[:n_steps]


@dataclass
class Record:
    """What a plant returned at each observed state (after a reset or a step)."""

    sensed: list[np.ndarray]
    true: list[np.ndarray]
    angles: list[np.ndarray]
    jacobian: list[np.ndarray]

    def stacked(self, name: str) -> np.ndarray:
        return np.stack(getattr(self, name))


def drive(plant: Plant, u: np.ndarray, on_return: Callable | None = None) -> Record:
    """Reset, then step through ``u`` (n_steps, R, n_dof), resetting every EPISODE steps.
    ``on_return(arrays, command)`` sees each state's returned arrays (and the command
    that led there, None after a reset) right after they are recorded."""
    rec = Record([], [], [], [])

    def observe(sensed: np.ndarray, command: np.ndarray | None) -> None:
        out = (sensed, plant.true_signals(), plant.joint_angles(), plant.command_jacobian())
        for store, arr in zip((rec.sensed, rec.true, rec.angles, rec.jacobian), out,
                              strict=True):
            store.append(arr)
        if on_return is not None:
            on_return(out, command)

    observe(plant.reset(), None)
    for k, command in enumerate(u):
        if k and k % EPISODE == 0:
            observe(plant.reset(), None)
        command = command.copy()
        observe(plant.step(command), command)
    return rec


def _same(a: Record, b: Record) -> None:
    for name in ("sensed", "true", "angles", "jacobian"):
        np.testing.assert_array_equal(a.stacked(name), b.stacked(name), err_msg=name)


# -- the contract ------------------------------------------------------------------------
@pytest.mark.parametrize("case", _params(CASES))
def test_protocol_attributes_and_shapes(case):
    plant = case.make(_seeds(case), 0.01)
    assert isinstance(plant, Plant)
    assert (plant.n_runs, plant.n_dof, plant.n_signals) == (case.n_runs, case.n_dof,
                                                            case.n_signals)
    assert isinstance(plant.dt, float) and plant.dt > 0
    speed = np.asarray(plant.max_speed_rad_s)
    assert speed.shape == (case.n_dof,) and np.all(np.isfinite(speed) & (speed > 0))
    rec = drive(plant, commands(case, 2 * EPISODE))
    r, n, k = case.n_runs, case.n_signals, case.n_dof
    for name, shape in (("sensed", (r, n)), ("true", (r, n)), ("angles", (r, case.dof)),
                        ("jacobian", (r, n, k))):
        for arr in getattr(rec, name):
            assert isinstance(arr, np.ndarray) and arr.shape == shape, name
            assert arr.dtype == np.float64, name
            assert np.all(np.isfinite(arr)), name


@pytest.mark.parametrize("case", _params(CASES))
def test_saturating_commands_keep_the_physics_valid(case):
    """Finite returns, and no MuJoCo warning: on a diverging state MuJoCo resets the
    whole MjData (every run of a batch) and only logs it, so finite is not enough. (The 3D
    torque twin diverged here until its shoulder hinges got armature.)"""
    plant = case.make(_seeds(case), 0.01)
    rec = drive(plant, commands(case, 4 * EPISODE, amp=1.5))
    for name in ("sensed", "true", "angles", "jacobian"):
        assert np.all(np.isfinite(rec.stacked(name))), name
    if case.mj_data is not None:
        warnings = {i: w.number for i, w in enumerate(case.mj_data(plant).warning) if w.number}
        assert not warnings, f"MuJoCo warnings fired (mjtWarning: count): {warnings}"


@pytest.mark.parametrize("case", _params(
    CASES, lambda c: None if c.velocity else _TORQUE_LIMITS))
def test_joints_stay_in_their_ranges(case):
    u = commands(case, 4 * EPISODE, amp=1.5)  # saturating: every joint meets its limits
    q = drive(case.make(_seeds(case), 0.01), u).stacked("angles")
    lo, hi = body.body_of(case.dof).joint_ranges().T
    tol = 0.0 if case.velocity else SOFT_LIMIT_RAD
    assert np.all(q.min(axis=(0, 1)) >= lo - tol - 1e-12)
    assert np.all(q.max(axis=(0, 1)) <= hi + tol + 1e-12)
    # and the commands did reach the limits (the check is not vacuous)
    reach = np.minimum(q.min(axis=(0, 1)) - lo, hi - q.max(axis=(0, 1)))
    assert np.all(reach[list(case.commanded)] < 0.05)


@pytest.mark.parametrize("case", _params(CASES))
def test_commands_outside_the_unit_box_act_as_clipped_ones(case):
    u = commands(case, 2 * EPISODE, amp=max(3.0, 3 * case.amp), seed=1)
    if not case.velocity:  # torque: full torque only now and then (see amp)
        u = np.where(np.random.default_rng(2).random(u.shape) < 0.1, u,
                     commands(case, 2 * EPISODE, seed=3))
    assert np.abs(u).max() > 1.5
    wild = drive(case.make(_seeds(case), 0.01), u)
    tame = drive(case.make(_seeds(case), 0.01), np.clip(u, -1.0, 1.0))
    _same(wild, tame)


@pytest.mark.parametrize("case", _params(VELOCITY_CASES))
def test_command_jacobian_predicts_a_small_step(case):
    """true(after c) - true(after 0) == J c up to a bound derived, not tuned.

    Each signal is a normalized joint angle (linear: no remainder) or a component of a
    segment's unit direction e (or, for the toy, sin / cos of a joint-angle sum). For
    the latter every second derivative is a_j x (a_i x e) (j upstream of i, unit hinge
    axes), so |d2 s / dq_i dq_j| <= 1 and Taylor's remainder is <= 1/2 |dq|_1^2. The
    servo misses each joint's commanded step by at most SERVO_TRACKING of the largest
    one (a fraction of the velocity change; the arm's joints are coupled through its
    mass matrix, so a still joint moves a little with a moving neighbour), so the
    linear term is off by at most that times sum_j |dS/dq_j|. The zero-command twin
    takes out what the command does not cause (a forced leading arm's motion).
    """
    seeds = _seeds(case)
    moved, still = case.make(seeds, 0.0), case.make(seeds, 0.0)
    moved.reset()
    still.reset()
    jac = moved.command_jacobian()
    speed = np.asarray(moved.max_speed_rad_s)
    step_rad = 0.002 * np.random.default_rng(4).uniform(-1, 1, (case.n_runs, case.n_dof))
    c = step_rad / (speed * moved.dt)
    moved.step(c)
    still.step(np.zeros_like(c))
    # the joints: the commanded step, within the servo's tracking
    dq = moved.joint_angles() - still.joint_angles()
    want = np.zeros((case.n_runs, case.dof))
    want[:, list(case.commanded)] = step_rad
    largest = np.abs(step_rad).max(axis=1, keepdims=True)
    assert np.all(np.abs(dq - want) <= SERVO_TRACKING * largest + 1e-15)
    # the signals: J c, within the bound
    change = moved.true_signals() - still.true_signals()
    predicted = np.einsum("rsk,rk->rs", jac, c)
    curvature = 0.0 if case.signals == "joint" else 1.0
    taylor = curvature * 0.5 * np.abs(step_rad).sum(axis=1, keepdims=True) ** 2
    per_rad = np.abs(jac / (speed * moved.dt)).sum(axis=2)  # sum_j |dS / dq_j|
    servo = SERVO_TRACKING * largest * per_rad
    bound = taylor + servo + 1e-12
    assert np.all(np.abs(change - predicted) <= bound)
    assert bound.max() < 0.2 * np.abs(predicted).max()  # a wrong Jacobian cannot pass


@pytest.mark.parametrize("case", _params(CASES))
def test_sensor_noise_has_the_configured_statistics(case):
    sigma = 0.05
    rec = drive(case.make(_seeds(case), sigma), commands(case, 5 * EPISODE))
    noise = rec.stacked("sensed") - rec.stacked("true")  # (states, R, n_signals)
    x = noise.reshape(-1)
    n = x.size
    assert abs(x.mean()) <= Z * sigma / np.sqrt(n)
    # the sample std of n Gaussian values has a standard error of sigma / sqrt(2 n)
    assert abs(x.std(ddof=1) / sigma - 1.0) <= Z / np.sqrt(2 * n)
    # runs with different seeds: independent streams
    per_run = noise.transpose(1, 0, 2).reshape(case.n_runs, -1)
    for a in range(case.n_runs):
        for b in range(a):
            rho = np.corrcoef(per_run[a], per_run[b])[0, 1]
            assert abs(rho) <= Z / np.sqrt(per_run.shape[1])


@pytest.mark.parametrize("case", _params(CASES))
def test_reset_returns_to_the_same_first_pose(case):
    plant = case.make(_seeds(case), 0.01)
    first = plant.reset()
    pose = (plant.joint_angles(), plant.true_signals(), plant.command_jacobian())
    for command in commands(case, EPISODE // 2):
        plant.step(command)
    assert not np.array_equal(plant.joint_angles(), pose[0])
    again = plant.reset()
    for got, want in zip((plant.joint_angles(), plant.true_signals(),
                          plant.command_jacobian()), pose, strict=True):
        np.testing.assert_array_equal(got, want)
    # the pose repeats; the noise stream goes on (it is not re-seeded on reset)
    assert not np.array_equal(again - pose[1], first - pose[1])


@pytest.mark.parametrize("case", _params(CASES))
def test_same_seeds_same_sequences(case):
    u = commands(case, 2 * EPISODE)
    a = drive(case.make(_seeds(case), 0.01), u)
    b = drive(case.make(_seeds(case), 0.01), u)
    _same(a, b)
    other = drive(case.make(_seeds(case, OTHER_SEEDS), 0.01), u)
    # open loop, the noise never reaches the physics: same motion, other noise
    np.testing.assert_array_equal(other.stacked("angles"), a.stacked("angles"))
    np.testing.assert_array_equal(other.stacked("true"), a.stacked("true"))
    assert np.all(np.abs(other.stacked("sensed") - a.stacked("sensed")).max(axis=-1) > 0)


@pytest.mark.parametrize("case", _params([c for c in CASES if c.n_runs > 1]))
def test_each_run_is_the_plant_alone_with_its_seed(case):
    """Lockstep runs share nothing: run r of R equals a one-run plant with seeds[r].
    Bitwise, except that MuJoCo solves the torque twin's joint-limit constraints of a
    batch island by island and one robot's in one piece: rounding (measured 1e-14)."""
    u = commands(case, 2 * EPISODE)
    together = drive(case.make(_seeds(case), 0.01), u)
    atol = 0.0 if case.velocity else 1e-12
    for r, seed in enumerate(_seeds(case)):
        alone = drive(case.make([seed], 0.01), u[:, r : r + 1])
        for name in ("sensed", "true", "angles", "jacobian"):
            np.testing.assert_allclose(together.stacked(name)[:, r], alone.stacked(name)[:, 0],
                                       rtol=0, atol=atol, err_msg=name)


@pytest.mark.parametrize("case", _params(CASES))
def test_returned_arrays_share_no_memory_with_the_plant(case):
    u = commands(case, 2 * EPISODE)

    def scribble(arrays, command):
        for arr in (*arrays, command):
            if arr is not None and arr.flags.writeable:
                arr[...] = np.nan

    reference = drive(case.make(_seeds(case), 0.01), u)
    kept = drive(case.make(_seeds(case), 0.01), u)  # its returns, untouched
    copies: list = []
    drive(case.make(_seeds(case), 0.01), u,
          on_return=lambda arrays, command: (copies.append([a.copy() for a in arrays]),
                                             scribble(arrays, command)))
    # mutating every returned array (and the command) changed nothing the plant did ...
    scribbled = Record(*[list(x) for x in zip(*copies, strict=True)])
    _same(scribbled, reference)
    # ... and no later call rewrote an array returned earlier
    _same(kept, reference)
