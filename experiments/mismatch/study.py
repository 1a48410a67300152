"""Model mismatch: does a learned inverse model earn its place when the controllers'
model of the arm is wrong and they see only what a robot senses?

Every row runs on the torque body (2D unless ``3d-``), YMCA, with the realistic sensing
(``actuation.sensing=encoders``: encoder noise 5e-4 rad; joint velocities from the
model-based observer, ``actuation.sensing.velocity=observer``, the torque recipe's) and
controllers that know at most the nominal body (payload 0, masses x 1, no friction); the
rows ``*-fd2`` (group ``fd2``) sense velocities by the second-order backward difference
instead. Rows ``<body>-<movement>-<mismatch>-<controller>``; the mismatch is the plant as
it is, in training and test alike:

- ``none``; ``payload0.5`` / ``payload1``: 0.5 / 1 kg at the right hand's centre of mass;
  ``mass+20`` / ``mass-20``: every arm link's mass and inertia x 1.2 / x 0.8;
  ``friction``: 1 N m Coulomb friction and 0.5 N m s/rad more viscous damping on every
  arm joint; ``noisy-encoders``: encoder noise 5e-3 rad (x 10); ``delay``: one control
  step (20 ms) of sensing latency (the ESN's position inputs lag too).

Controllers (all on the same sensed state):

- ``pd-g``: PD + the nominal gravity torque, poles at 15 rad/s (inertia-scaled by the
  nominal M(q) at the sensed pose);
- ``teacher``: FEL's teacher alone, the inertia-scaled PD at 5 rad/s, nominal M(q);
- ``ct-nominal``: computed torque (15 rad/s) on the nominal model;
- ``ct-adaptive``: computed torque whose model adapts online (the nominal model plus an
  exact inertial regressor: link mass scales, hand payload, viscous and Coulomb friction
  per joint; the desired-compensation adaptation law, :mod:`skinny_mj.training.adaptive`),
  its estimate carried through ``ADAPT_CYCLES`` unscored cycles before the scored one;
- ``ct-oracle``: computed torque on the plant's true model (an oracle: no robot has it);
- ``esn``: ESN + FEL trained on the plant as it is with the nominal teacher (the dynamic
  study's recipe: beta 1, 3 learning cycles per epoch, readout on the normal equations
  with forgetting 0.8, K 1 -> 0 over ``EPOCHS`` epochs), tested at K = 0
  (``position_nrmse``) and with its teacher on at K = 1 (``*_k1``) after one training; the
  ``none`` row's ESN (trained on the nominal arm) is also tested on every changed plant
  (``*_on_<mismatch>``): the network trained on the nominal arm, tested on the changed one.

Groups: ``clips`` and ``clips-3d`` (the shipped clips re-timed to the torque limits),
``2d`` and ``3d`` (the 3D body: the dynamic study's 3D recipe for the ESN, 500
units, 6 learning cycles per epoch, the teacher at 20 rad/s, forgetting 0.9), and
``switch``: a 1 kg payload switched on mid-movement
(:mod:`skinny_mj.experiments.mismatch.switch`), ``long``: ESN rows trained 4x as long
(:data:`LONG`) beside the rows they lengthen, ``delay-esn``: the ESN under the delay.

Seeds come from the engine (each row's own). ``--quick``: a smoke test (one run, three
mismatches and two switch rows, two epochs, one adaptation cycle).
"""

from __future__ import annotations

import dataclasses

from skinny_mj.experiments.dynamic.study import ARM_GOALS, TABLE_COLUMNS
from skinny_mj.experiments.dynamic.study import metrics as dynamic_metrics
from skinny_mj.experiments.mismatch import switch

from skinny_mj import training
from skinny_mj.engine.study import Quick, Row, Shape, Study, Test
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.result import RunResult

NAME = "mismatch"
#: mismatch id -> the plant as it is (TrainConfig overrides)
MISMATCHES = {
    "none": {},
    "payload0.5": {"actuation.payload_kg": 0.5},
    "payload1": {"actuation.payload_kg": 1.0},
    "mass+20": {"actuation.mass_scale": 1.2},
    "mass-20": {"actuation.mass_scale": 0.8},
    "friction": {"actuation.friction_nm": 1.0, "actuation.damping_nm_s_rad": 0.5},
    "noisy-encoders": {"actuation.sensing.encoder_noise": 5e-3},
    "delay": {"actuation.sensing.delay": 1},
}
#: where the model's error matters (the goal: the ESN with feedback >= 2x better than
#: nominal computed torque there)
MODEL_ERROR = ("payload0.5", "payload1", "friction")
EPOCHS, QUICK_EPOCHS = 15, 2
ADAPT_CYCLES, QUICK_ADAPT_CYCLES = 5, 1
ESN = {"method": "new", "method.beta": 1.0, "method.cycles": 3, "method.epochs": EPOCHS,
       "actuation.feedback": "inertia-pd", "method.fit": "forgetting", "test.gain": 0.0}
ALONE = {"method": "none", "test.gain": 1.0}
CONTROLLERS = {
    "pd-g": {**ALONE, "actuation.feedback": "pd-gravity"},
    "teacher": {**ALONE, "actuation.feedback": "inertia-pd"},
    "ct-nominal": {**ALONE, "actuation.feedback": "ct"},
    "ct-adaptive": {**ALONE, "actuation.feedback": "adaptive-ct",
                    "test.washout_cycles": ADAPT_CYCLES},
    "ct-oracle": {**ALONE, "actuation.feedback": "ct", "actuation.model": "true"},
    "esn": ESN,
}
#: the 3D body: the dynamic study's 3D recipe (500 units, 6 cycles, teacher at 20 rad/s,
#: forgetting 0.9)
BODIES = {"2d": {"plant.dof": 4},
          "3d": {"plant.dof": 8, "esn.n_reservoir": 500, "method.cycles": 6,
                 "actuation.omega": 20.0, "method.fit.forgetting": 0.9}}
GOAL_K0 = ARM_GOALS  # the dynamic study's goals for the ESN alone on YMCA, now without the oracle
GOAL_RATIO, GOAL_VS_CT = 1.3, 2.0
COLUMNS = {**{k: TABLE_COLUMNS[k] for k in ("position_nrmse", "joint_nrmse", "rms_error_deg",
                                            "peak_error_deg", "hand_error_cm")},
           "position_nrmse_k1": "ESN, K = 1", "rms_error_deg_k1": "ESN, K = 1 (°)",
           **{k: TABLE_COLUMNS[k] for k in ("max_torque_ratio", "train_wall_s")}}


#: The movements trained and tested on: YMCA, and the shipped CMU clips re-timed locally
#: to the nominal arm's torque limits (``NAME@feasible``: TOPP-RA, slower only where a
#: torque would pass 0.9 of its limit), groups ``clips`` (2D) and ``clips-3d``.
MOVEMENTS = {"ymca": "ymca", "md02": "md_02.amc@feasible", "md03": "md_03.amc@feasible"}
CLIP_BODIES = ("2d", "3d")


def row_id(bd: str, mismatch: str, controller: str, movement: str = "ymca") -> str:
    return f"{bd}-{movement}-{mismatch}-{controller}"


def _rows(movement: str = "ymca") -> tuple[Row, ...]:
    out = []
    for bd, body_keys in BODIES.items():
        if movement != "ymca" and bd not in CLIP_BODIES:
            continue
        for m, changes in MISMATCHES.items():
            for ctl, keys in CONTROLLERS.items():
                over = {"movement.trajectory": MOVEMENTS[movement], **keys, **changes}
                over.update({k: v for k, v in body_keys.items()
                             if ctl == "esn" or k == "plant.dof"})
                if bd == "3d" and ctl != "esn" and "actuation.omega" in body_keys \
                        and keys["actuation.feedback"] == "inertia-pd":
                    over["actuation.omega"] = body_keys["actuation.omega"]
                quick = {"method.epochs": QUICK_EPOCHS} if ctl == "esn" else \
                    {"test.washout_cycles": QUICK_ADAPT_CYCLES} if ctl == "ct-adaptive" else {}
                params = {"also": tuple(k for k in MISMATCHES if k != "none")} \
                    if ctl == "esn" and m == "none" else {}
                group = bd if movement == "ymca" else "clips" if bd == "2d" else f"clips-{bd}"
                out.append(Row(row_id(bd, m, ctl, movement), over, group=group, quick=quick,
                               params=params, shape=ESN_SHAPE if ctl == "esn" else None))
    return tuple(out)


def _figures(result: RunResult, label: str) -> dict:
    """Test ``label``'s metrics, each key + ``label``."""
    test = result.tests[label]
    if test.failed:
        return {f"position_nrmse{label}": None}
    plant = result.config.plant
    tq = test.torque["metrics"]
    out = {"position_nrmse": test.position_nrmse,
           "joint_nrmse": training.torque.joint_nrmse(result, label),
           **test.robot_metrics(plant.body),
           "max_torque_ratio": max(tq["max_commanded_ratio"], tq["max_applied_ratio"]),
           "warnings": tq["warnings"]}
    return {f"{k}{label}": v for k, v in out.items()}


def esn_tests(config: TrainConfig, row: Row) -> tuple[Test, ...]:
    """An ESN row's tests: at K = 0 (the standard test), at K = 1 (``_k1``) and (the
    ``none`` row) on each changed plant of ``row.params["also"]`` (``_on_<mismatch>``)."""
    return (Test(), Test("_k1", overrides={"test.gain": 1.0}),
            *(Test(f"_on_{m}", overrides=MISMATCHES[m]) for m in row.params.get("also", ())))


def esn_metrics(result: RunResult) -> dict:
    """Every test's figures (:func:`_figures`), the training curve and wall time."""
    out: dict = {}
    for label in result.tests:
        out.update(_figures(result, label))
    out["curve_position_nrmse"] = [float("nan") if v is None else float(v)
                                   for v in result.train.position_nrmse]
    out["train_wall_s"] = result.wall_s
    return out


def esn_failure(result: RunResult) -> str | None:
    """A diverged training or K = 0 test fails the run (the other tests' are data)."""
    if result.train.failed or result.test.failed:
        return result.train.fail_reason or "test diverged"
    return None


#: ESN + FEL trained once per seed on the plant as it is, then tested on each of
#: :func:`esn_tests`.
ESN_SHAPE = Shape(esn_metrics, tests=esn_tests, failure=esn_failure)


def _switch_rows() -> tuple[Row, ...]:
    """The payload switched on mid-movement (:mod:`skinny_mj.experiments.mismatch.switch`)."""
    out = []
    for learner in switch.LEARNERS:
        keys = ESN if learner.startswith("esn") else CONTROLLERS[learner]
        keys = {k: v for k, v in keys.items() if k != "test.washout_cycles"}
        out.append(Row(f"2d-ymca-switch-{learner}", {"movement.trajectory": "ymca",
                                                      "plant.dof": 4, **keys},
                       group="switch", params={"learner": learner}, shape=switch.shape(learner),
                       quick={"method.epochs": QUICK_EPOCHS} if learner.startswith("esn")
                       else {}))
    return tuple(out)


def _fd2_rows(rows: tuple[Row, ...]) -> tuple[Row, ...]:
    """Group ``fd2``: velocities by the second-order backward difference of the encoder
    angles instead of the observer, for every controller alone of ``rows`` (the payload
    switch's too) and the ESN on the nominal arm: each controller's better estimate of the
    two."""
    fd2 = {"actuation.sensing.velocity": "finite-difference-2"}
    return tuple(dataclasses.replace(row, id=f"{row.id}-fd2", group="fd2",
                                     overrides={**row.overrides, **fd2})
                 for row in rows
                 if not row.id.endswith("-esn") or row.id.endswith("-ymca-none-esn")
                 if "-switch-esn" not in row.id)


#: Group ``x4``: the ESN rows on YMCA with LONG_FACTOR x the epochs (K 1 -> 0 over 60), on
#: the seeds of the row each lengthens, per body: the mismatches and the runs per row
#: (does the error within 1.3x of the nominal arm's need only longer training?); group
#: ``long``: those and the rows they lengthen
LONG_FACTOR = 4
LONG = {"2d": (("none", "payload0.5", "payload1", "mass-20", "friction", "delay"), 10),
        "3d": (("none", "payload1", "friction", "delay"), 5)}


def _long_rows(rows: tuple[Row, ...]) -> tuple[Row, ...]:
    by_id = {r.id: r for r in rows}
    out = []
    for bd, (mismatches, runs) in LONG.items():
        for m in mismatches:
            row = by_id[row_id(bd, m, "esn")]
            out.append(dataclasses.replace(
                row, id=f"{row.id}-x{LONG_FACTOR}", group=f"x{LONG_FACTOR}", runs=runs,
                seeds_of=row.id,
                params={}, overrides={**row.overrides,
                                      "method.epochs": EPOCHS * LONG_FACTOR}))
    return tuple(out)


_YMCA, _SWITCH = _rows(), _switch_rows()
_CLIPS = tuple(r for mv in MOVEMENTS if mv != "ymca" for r in _rows(mv))
_LONG = _long_rows(_YMCA)
ROWS = (*_YMCA, *_fd2_rows((*_YMCA, *_SWITCH, *_CLIPS)), *_SWITCH, *_CLIPS, *_LONG)
#: ``long``: group ``x4`` and the rows it lengthens; ``delay-esn``: the ESN on every body
#: and movement under the sensing delay
GROUPS = {"long": (f"x{LONG_FACTOR}", *(r.seeds_of for r in _LONG)),
          "delay-esn": tuple(r.id for r in ROWS if r.id.endswith("-delay-esn"))}
QUICK_ROWS = (*(row_id("2d", m, c) for m in ("none", "payload1", "delay")
                for c in CONTROLLERS), "2d-ymca-switch-esn-rls", "2d-ymca-switch-ct-adaptive")
STUDY = Study(
    name=NAME, description=__doc__, rows=ROWS, runs=10, takes=(), groups=GROUPS,
    base=TrainConfig().override({"actuation": "torque", "plant.signals": "cartesian",
                                 "actuation.sensing.velocity": "observer"}),
    metrics=dynamic_metrics, columns=COLUMNS,  # a controller alone: the dynamic study's
    quick=Quick(runs=1, rows=QUICK_ROWS),
    report="skinny_mj.experiments.mismatch.report:report",
)
