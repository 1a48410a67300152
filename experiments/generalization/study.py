"""Generalization (the thesis's RQ3): which training movement teaches an inverse
model that imitates movements it never saw?

A train-set x test-movement matrix for three bodies/representations: 2D joint angles
(``j2``, paper C's), 2D Cartesian (``c2``, paper E's) and 3D Cartesian (``c3``, paper D's).
Rows are training sets (:data:`TRAIN_SETS`): the thesis's (YMCA only, paper C) and ours —
YMCA with its mirrors, motor babbling (:mod:`skinny_mj.trajectories.babble`) of several
durations and speed ranges, the real CMU clips leave-one-clip-out (train on md_03, test
on md_02 and the other way round), the first seconds of a clip (its rest is the unseen
excerpt), and mixtures joined by minimum-jerk bridges (``set:A+B``). Two rows vary the
network instead of the movement: the reservoir size (N = 400) and the command scale
(full scale = 4x instead of 2x the training movement's fastest speed per DOF).

The rows of ``--rows general`` (:data:`GENERAL_ROWS`) measure the ``general`` preset of
each body and signal (2D and 3D, joint angles and Cartesian; ``j3`` is 3D joint angles)
against the best row before it, and its ingredients: babbling that also moves to the
joint limits and rests (``limits``, ``holds``), a longer babble, the feedback
controller's correction weighted 3x in the learning targets (``method.u_error_gain``).
The rows of ``--rows cartesian`` (:data:`CARTESIAN_ROWS`) change one thing in the
Cartesian preset rows of before, on their seeds: the feedback controller's Jacobian
damping (``method.u_error_damping``), a forward model's prediction as an input, each
elbow's angle as an extra signal (``cartesian-elbow``, the presets since) and, in 3D,
a longer babble before YMCA.

Every network is trained once (paper E's experiment 5 schedule: new method, β = 0.1,
3 learning cycles x 10 epochs, K 1 -> 0, N = 200, spectral radius 0.5) and tested on
every column (:data:`TESTS`: the YMCA family with mirrors and speeds, both clips whole and
their unseen tails, and an unseen babble) with :func:`skinny_mj.training.loop.evaluate`
after one unscored washout cycle, K = 0. Per cell (:mod:`skinny_mj.training.imitation`): position
NRMSE, DTW NRMSE (:mod:`skinny_mj.training.dtw`), the fraction of steps within 5° per joint,
per-joint RMS error, the timing lag, the produced angles scored on Cartesian signals,
the fraction of true-command samples beyond full scale (|c| > 1 before clipping, the
run's own scale) and what that alone costs: the position NRMSE of the exact inverse
model clipped at full scale (:func:`clipped_ideal_nrmse`, a kinematic bound).
Paper E's schedule instead of paper C's (N = 1000, 150 epochs) keeps the whole matrix
near 20 min on one worker (measured: 21.5 min for 240 runs on a shared
2-core machine): the thesis's own row at its size is paper C's sweep
(``skinny experiment paper-c``). Every seed of a row trains on the same babble draw
(``seed=0``; lockstep needs one movement): the babble's own variability is not sampled.

The bimanual patterns of paper B are left out as test movements: they are defined for
one forced arm and one driven arm, not for a network that drives both.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import TYPE_CHECKING

import numpy as np
from skinny_mj.controllers.metrics import position_nrmse

from skinny_mj.engine.results import train_failure
from skinny_mj.engine.study import Quick, Row, Study, Test
from skinny_mj.plant import body
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.imitation import imitation_metrics, saturation  # noqa: F401 (API)
from skinny_mj.training.presets import preset_fields
from skinny_mj.trajectories import load_movement

if TYPE_CHECKING:
    from skinny_mj.training.result import RunResult

NAME = "generalization"
#: Representation id -> (dof, signals); the matrix runs the first three.
REPRESENTATIONS = {"j2": (4, "joint"), "c2": (4, "cartesian"), "c3": (8, "cartesian"),
                   "j3": (8, "joint")}
MATRIX_REPS = ("j2", "c2", "c3")
#: Babbling that also dwells at the joint limits and rests (30 s).
LIMITS_BABBLE = "babble:seed=0,duration=30,limits=0.5,holds=0.2"
#: Training set id -> (movement, TrainConfig overrides).
TRAIN_SETS: dict[str, tuple[str, dict]] = {
    "ymca": ("ymca", {}),  # the thesis's (paper C)
    "ymca-mirrors": ("set:ymca+mirror-right+mirror-left", {}),
    "babble5": ("babble:seed=0,duration=5", {}),
    "babble15": ("babble:seed=0,duration=15", {}),
    "babble15-slow": ("babble:seed=0,duration=15,vmin=0.5,vmax=4", {}),
    "babble15+ymca": ("set:babble:seed=0,duration=15+ymca", {}),
    "md_03": ("md_03.amc", {}),  # leave-one-clip-out: md_02 is unseen
    "md_02": ("md_02.amc", {}),  # md_03 is unseen
    "md_02-head": ("md_02.amc@start=0,duration=5", {}),  # md_02's tail is unseen
    "babble15+md_03": ("set:babble:seed=0,duration=15+md_03.amc", {}),
    "babble15-N400": ("babble:seed=0,duration=15", {"esn.n_reservoir": 400}),
    "babble15-scale4": ("babble:seed=0,duration=15", {"movement.full_scale_factor": 4.0}),
}
#: Rows added after the first full sweep (the recorded-like YMCA), last in the
#: experiment so every earlier row keeps its place and seeds: (representation, set id).
EXTRA_ROWS = (("j2", "ymca-recorded"), ("c2", "ymca-recorded"))
TRAIN_SETS_EXTRA = {"ymca-recorded": ("ymca-recorded", {})}
#: The general model of each body and signal (``--rows general``, after EXTRA_ROWS):
#: ``general`` is the preset (:func:`skinny_mj.training.presets.preset_fields`), the
#: others isolate its ingredients. Babbling with ``limits``/``holds`` moves to the joint
#: limits and rests as real dance does (:mod:`skinny_mj.trajectories.babble`).
TRAIN_SETS_GENERAL: dict[str, tuple[str, dict]] = {
    "babble15-scale4": TRAIN_SETS["babble15-scale4"],
    "limits30-scale4": (LIMITS_BABBLE, {"movement.full_scale_factor": 4.0}),
    "general": ("", {}),  # the preset's own movement and keys (general_row)
}
GENERAL_ROWS = (("j2", "limits30-scale4"), ("j3", "babble15-scale4"), ("j3", "general"),
                ("c2", "babble15-scale4"),
                ("c2", "limits30-scale4"), ("c2", "general"), ("c3", "babble15-scale4"))
#: Per representation, the row of its ``general`` preset (the Cartesian ones: their
#: CARTESIAN_ROWS row with the elbow angles).
GENERAL_OF = {"j2": "j2-limits30-scale4", "j3": "j3-general", "c2": "c2-general+elbow",
              "c3": "c3-babble15+ymca+elbow-babble240"}
#: Candidates for the Cartesian presets (``--rows cartesian``, after GENERAL_ROWS): each
#: is the representation's ``general`` preset with one change, on the preset row's seeds
#: (a paired comparison): the feedback controller's damped-least-squares lambda, a
#: parallel forward model whose prediction is an input of the inverse model (paper A),
#: the elbow angles as extra signals (``cartesian-elbow``), and what the screen of those
#: pointed to.
CARTESIAN_VARIANTS: dict[str, dict] = {
    "damp0.1": {"method.u_error_damping": 0.1},
    "damp0.3": {"method.u_error_damping": 0.3},
    "damp1": {"method.u_error_damping": 1.0},
    "forward": {"forward": "parallel"},
    "elbow": {"plant.signals": "cartesian-elbow"},
    "elbow-babble30": {"plant.signals": "cartesian-elbow",
                       "movement.trajectory": "set:babble:seed=0,duration=30+ymca"},
    "elbow-babble60": {"plant.signals": "cartesian-elbow",
                       "movement.trajectory": "set:babble:seed=0,duration=60+ymca"},
    "elbow-babble120": {"plant.signals": "cartesian-elbow",
                        "movement.trajectory": "set:babble:seed=0,duration=120+ymca"},
    "elbow-babble240": {"plant.signals": "cartesian-elbow",
                        "movement.trajectory": "set:babble:seed=0,duration=240+ymca"},
}
#: The longer babbles before YMCA are c3's (its base row's movement).
CARTESIAN_ROWS = (*((rep, v) for rep in ("c2", "c3") for v in CARTESIAN_VARIANTS
                    if not v.startswith("elbow-babble")),
                  *(("c3", f"elbow-babble{d}") for d in (30, 60, 120, 240)))
#: Test column id -> movement.
TESTS = {
    "ymca": "ymca", "y": "y", "y-pure": "y-pure", "ym": "ym",
    "mirror-right": "mirror-right", "mirror-left": "mirror-left",
    "ymca@0.5": "ymca@0.5", "ymca@1.5": "ymca@1.5",
    "md_02": "md_02.amc", "md_03": "md_03.amc",
    "md_02-tail": "md_02.amc@start=5", "md_03-tail": "md_03.amc@start=2",
    "babble-new": "babble:seed=99,duration=10",
}
#: Test columns (part of) each training set contains: not "unseen" for that row.
SEEN = {
    "ymca": {"ymca", "ymca@0.5", "ymca@1.5"},
    "ymca-mirrors": {"ymca", "ymca@0.5", "ymca@1.5", "mirror-right", "mirror-left"},
    "babble15+ymca": {"ymca", "ymca@0.5", "ymca@1.5"},
    "md_03": {"md_03", "md_03-tail"}, "md_02": {"md_02", "md_02-tail"},
    "md_02-head": {"md_02"}, "babble15+md_03": {"md_03", "md_03-tail"},
}
#: Training sets of the Cartesian representations (the full list is j2's, paper C's own
#: representation): the ~20 min budget of one worker does not hold all twelve three times.
CORE_SETS = ("ymca", "babble5", "babble15", "babble15+ymca", "md_03", "md_02")
QUICK_SETS = ("ymca", "babble5", "md_03")
QUICK_TESTS = ("ymca", "md_02", "md_02-tail")


@functools.lru_cache(maxsize=64)
def load_test(movement: str, dof: int):
    """A test movement for ``dof`` (cached: every row of a worker reuses it)."""
    return load_movement(movement, dof)[0]


def clipped_ideal_nrmse(angles: np.ndarray, dt: float, max_speed_rad_s: np.ndarray,
                        signals: str) -> float:
    """Position NRMSE of the exact inverse model whose commands are clipped to [-1, 1]
    (kinematic: q(t+1) = q(t) + clip(c) v_max dt, no sensor noise): what the command
    scale alone costs on ``angles`` (T, n_dof) rad, a lower bound for any network."""
    step = np.asarray(max_speed_rad_s) * dt
    q = np.empty_like(angles)
    q[0] = angles[0]
    for t in range(1, len(angles)):  # sequential: each step starts where the last ended
        q[t] = q[t - 1] + np.clip((angles[t] - q[t - 1]) / step, -1.0, 1.0) * step
    dof = angles.shape[1]
    skinny = body.body_of(dof)
    return float(position_nrmse(skinny.position_signals(q, signals)[None],
                                skinny.position_signals(angles, signals))[0])


def test_movement(column: str, config: TrainConfig):
    """Test column ``column``'s movement on ``config``'s body (:func:`load_test`)."""
    return load_test(TESTS[column], config.plant.dof)


def tests(config: TrainConfig, row: Row) -> tuple[Test, ...]:
    """Train the row's networks once, then test them on every column of
    ``row.params["tests"]``."""
    return tuple(Test(col, functools.partial(test_movement, col)) for col in row.params["tests"])


def metrics(result: RunResult) -> dict:
    """One run's training figures and its imitation metrics on every test column (a
    diverged test counts in ``n_test_failed``)."""
    config, traj = result.config, result.trajectory
    dof, max_speed = config.plant.dof, result.max_speed_rad_s
    out = {
        "train_position_nrmse": result.train.last_position_nrmse,
        "train_steps": len(traj), "train_wall_s": result.train_wall_s, "n_test_failed": 0,
        "train_coverage": coverage(traj.angles, dof),
        "train_speed_p99_rad_s": float(np.percentile(np.abs(traj.velocities()), 99)),
        "max_speed_rad_s": [float(v) for v in max_speed],
    }
    for col, outcome in result.tests.items():
        test = outcome.trajectory
        out[f"{col}__saturated"] = saturation(test.angles, test.dt, max_speed)
        out[f"{col}__clipped_ideal_nrmse"] = clipped_ideal_nrmse(
            test.angles, test.dt, max_speed, config.plant.signals)
        if outcome.failed:
            out["n_test_failed"] += 1
            continue
        out.update({f"{col}__{k}": v for k, v in imitation_metrics(outcome, dof).items()})
    out["wall_s"] = result.wall_s
    return out


def coverage(angles: np.ndarray, dof: int, bins: int = 6) -> float:
    """Fraction of the joint space a movement visits: per arm, the occupied cells of a
    ``bins``-per-DOF grid over the arm's joint ranges, over all cells; mean of the arms."""
    q = body.body_of(dof).normalize_angles(np.asarray(angles))  # [-1, 1] per DOF
    cells = np.clip(((q + 1.0) / 2.0 * bins).astype(int), 0, bins - 1)
    n_arm = dof // 2
    return float(np.mean([len({tuple(c) for c in cells[:, a * n_arm:(a + 1) * n_arm]})
                          / bins**n_arm for a in range(2)]))


def _row(rep: str, ts: str, movement: str, changes: dict) -> Row:
    dof, signals = REPRESENTATIONS[rep]
    return Row(f"{rep}-{ts}", {"plant.dof": dof, "plant.signals": signals,
                               "movement.trajectory": movement, **changes},
               group=rep, params={"rep": rep, "train": ts, "tests": tuple(TESTS)},
               quick={"tests": QUICK_TESTS})


def cartesian_row(base: Row, variant: str) -> Row:
    """A row of CARTESIAN_ROWS: the ``base`` row (the representation's preset row,
    :data:`CARTESIAN_BASE`) with the variant's keys, on the base row's seeds."""
    return dataclasses.replace(
        base, id=f"{base.id}+{variant}", overrides={**base.overrides,
                                                    **CARTESIAN_VARIANTS[variant]},
        params={**base.params, "train": f"{base.params['train']}+{variant}"},
        seeds_of=base.id)


def general_row(rep: str, ts: str) -> Row:
    """A row of GENERAL_ROWS: ``general`` is ``skinny train --preset general`` for the
    representation's body and signals, on those signals (a preset on refined signals,
    ``cartesian-elbow``, is a row of CARTESIAN_ROWS)."""
    if ts != "general":
        return _row(rep, ts, *TRAIN_SETS_GENERAL[ts])
    dof, signals = REPRESENTATIONS[rep]
    fields = preset_fields("general", dof=dof, signals=signals)
    fields.pop("plant.signals")  # on the representation's own signals (the c2 row: the
    # preset before the elbow signals, CARTESIAN_BASE)
    return _row(rep, ts, fields.pop("movement.trajectory"), fields)


#: j2: every training set; c2, c3: CORE_SETS; then EXTRA_ROWS, then GENERAL_ROWS.
_ROWS = (*(_row(rep, ts, *TRAIN_SETS[ts]) for rep in MATRIX_REPS for ts in TRAIN_SETS
           if rep == "j2" or ts in CORE_SETS),
         *(_row(rep, ts, *TRAIN_SETS_EXTRA[ts]) for rep, ts in EXTRA_ROWS),
         *(general_row(rep, ts) for rep, ts in GENERAL_ROWS))
#: The Cartesian candidates' base per representation: its preset row before them.
CARTESIAN_BASE = {"c2": "c2-general", "c3": "c3-babble15+ymca"}
_BY_ID = {r.id: r for r in _ROWS}
#: ... then CARTESIAN_ROWS.
ROWS = (*_ROWS, *(cartesian_row(_BY_ID[CARTESIAN_BASE[rep]], v) for rep, v in CARTESIAN_ROWS))


STUDY = Study(
    name=NAME, description=__doc__, rows=ROWS, runs=10,
    tests=tests, metrics=metrics, failure=train_failure,  # train once, test on each
    # paper E exp. 5's schedule (TrainConfig's defaults), 10 epochs, N = 200, one
    # unscored washout cycle before each test
    base=TrainConfig().override({"method.epochs": 10, "test.washout_cycles": 1,
                                 "esn.n_reservoir": 200}),
    columns={"train_position_nrmse": "train pos", "ymca__position_nrmse": "YMCA pos",
             "md_02__position_nrmse": "md_02 pos", "md_03__position_nrmse": "md_03 pos",
             "train_wall_s": "train s/run"},
    groups={"extra": [f"{rep}-{ts}" for rep, ts in EXTRA_ROWS],
            "general": [f"{rep}-{ts}" for rep, ts in GENERAL_ROWS],
            "cartesian": [f"{CARTESIAN_BASE[rep]}+{v}" for rep, v in CARTESIAN_ROWS]},
    # a smoke test: N = 50, 2 epochs, 2 runs, 3 sets x 3 tests on j2
    quick=Quick({"esn.n_reservoir": 50, "method.epochs": 2}, runs=2,
                rows=tuple(f"j2-{ts}" for ts in QUICK_SETS)),
    # the rows are the training sets and their bodies (select one with --rows j2|c2|c3|j3,
    # or --rows general)
    takes=(), report="skinny_mj.experiments.generalization.report:report",
)
