"""Dynamic control: the torque-driven Skinny, with mass, gravity and torque limits,
tracked by textbook controllers and learned by an ESN inverse-dynamics model.

Rows (ids ``<body>-<movement>-<controller>``), every one a :class:`TrainConfig` with
``actuation=torque`` (:mod:`skinny_mj.training.torque`):

- ``table``: for 2D and 3D (``2d``, ``3d``) and YMCA and an excerpt of CMU clip md_02
  (``ymca``, ``md02``; md_02 needs more torque than the motors have, see the report):
  ``pd`` the limit-scaled PD alone (K = 1, nothing learned), ``ct`` that PD plus the
  inverse-dynamics torque of the desired motion, ``fel-orig`` ESN + FEL original
  method, ``fel-new`` ESN + FEL new β (0.1, 3 cycles), ``fel-new-gff`` the same with the
  gravity feed-forward ``qfrc_bias / limit``, ``tt`` the true-target architecture
  (torques of ``mj_inverse``, β = 0.1, 50 cycles). The learned rows train with K 1 -> 0
  over 10 epochs and are tested at K = 0 (the ESN alone, plus the feed-forward in
  ``fel-new-gff``). ``<body>-rec-<controller>``: the same on the recorded-like YMCA.
- ``robust`` (2D, YMCA): the test plant carries a 1 kg point mass at the right hand's
  centre of mass (``payload1``) or every arm link's mass and inertia x 1.2 / x 0.8
  (``mass+20``, ``mass-20``); tested at K = 0 (``-k0``) and with the teacher left on
  at K = 1 (``-k1``).
- ``arm-table``, ``arm-robust``: the arm's own dynamics
  (:mod:`skinny_mj.controllers.torque_arm`, poles placed in inertia-scaled coordinates):
  ``arm-ct`` computed torque (omega 15 rad/s), ``arm-idpd`` inverse-dynamics
  feed-forward + PD (omega 5), ``arm-pdg`` PD + gravity compensation (omega 15),
  ``arm-pd`` the inertia-scaled PD alone (omega 5, the teacher's gains), all zeta = 1
  and K = 1; ``fel-arm`` ESN + FEL with that PD's feedback torque as the error signal
  (beta = 1, 3 cycles x 15 epochs, K 1 -> 0; readout on the normal equations with
  forgetting 0.8 and ridge 1e-2; the 3D arm's ESN has 500 units and 6 learning cycles
  per epoch; ``3d-*-fel-arm-long``: 3 cycles x 30 epochs instead),
  ``fel-arm-cycle`` / ``fel-arm-rls`` the same with the readout refitted on each cycle
  alone / by RLS; robustness rows as above with ``fel-arm`` and ``arm-ct``.
- ``kinematic``: ``2d-ymca-kinematic`` is the velocity-servo run of paper E's schedule,
  for the wall-time ratio.
- ``omega20`` (3D, on the seeds of the row they change): ``3d-rec-fel-arm-omega20+forget0.9``
  and ``3d-ymca-fel-arm-omega20+forget0.9``, the 3D ``fel-arm`` rows with the stiffer
  teacher (poles at 20 rad/s, forgetting 0.9: :data:`STIFF`), and ``3d-rec-arm-pd-omega20``,
  that teacher alone.
- ``general``: the torque ``general`` preset's rows (:mod:`skinny_mj.experiments.dynamic.general`):
  computed torque, the torque-limited floor (``<body>-general-floor``: iLQR with the true
  model and the whole movement known), 15 s of slow babbling (``2d-general-first``) and the preset
  of each body (``2d-general``, ``3d-general``).

Groups ``2d`` and ``3d`` hold each body's rows (``--rows 3d``). ``--movement`` replaces
the md_02 excerpt of the ``md02`` rows; ``--signals`` the position signals of every row
(default Cartesian).

Metrics per run: test position / joint-angle / motor NRMSE (motor: against the
normalized inverse-dynamics torques), mean |applied torque| (N m), positive motor work
(J), max |commanded| and |applied| torque / limit, the largest joint angle past a limit
(rad, in the test; ``train_limit_overshoot_rad`` over every training cycle), MuJoCo
warnings of the training and test plants, the wall time per run (lockstep batch / R),
and the learning curves (position NRMSE and feedback share per epoch) in the run files.
Goals, targets to measure against (not numbers tuned to): computed torque <= 0.008
joint-angle NRMSE on YMCA and the recorded-like YMCA with mean |tau| <= 1.5x the
movement's need; the ESN alone (K = 0) on YMCA <= 0.010 (2D) and <= 0.008 (3D)
position NRMSE; earlier goals (limit-scaled PD teacher) <= 0.03 (2D) and <= 0.06 (3D).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

from skinny_mj.experiments.dynamic import general

from skinny_mj import training
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.presets import preset_fields

if TYPE_CHECKING:
    from skinny_mj.training.result import RunResult

NAME = "dynamic"
#: The movements: YMCA, the recorded-like YMCA (never still, marker noise) and the
#: md_02 excerpt of the ``md02`` rows (``--movement`` replaces it)
YMCA, RECORDED, CLIP = "ymca", "ymca-recorded", "md_02.amc@start=3,duration=6.26"
#: epochs of K 1 -> 0: the limit-scaled teacher's FEL rows, the inertia-scaled one's
EPOCHS, ARM_EPOCHS = 10, 15
#: controller id -> TrainConfig overrides
CONTROLLERS = {
    "pd": {"method": "none", "test.gain": 1.0},
    "ct": {"method": "none", "test.gain": 1.0, "actuation.feedback": "computed-torque"},
    "fel-orig": {"method": "original"},
    "fel-new": {"method": "new", "method.beta": 0.1},
    "fel-new-gff": {"method": "new", "method.beta": 0.1, "actuation.gravity_feedforward": True},
    "tt": {"method": "true-target", "method.beta": 0.1},
}
#: The arm's own dynamics (skinny_mj.controllers.torque_arm): the textbook controllers
#: alone (K = 1) and FEL with the inertia-scaled PD teacher (beta = 1, 3 learning cycles
#: per epoch, 15 epochs of K 1 -> 0; readout on the normal equations with forgetting
#: 0.8, ridge 1e-2, or on each cycle alone, or by RLS)
ARM_FEL = {"method": "new", "method.beta": 1.0, "method.cycles": 3, "method.epochs": ARM_EPOCHS,
           "actuation.feedback": "inertia-pd", "method.fit": "forgetting"}
ARM_CONTROLLERS = {
    "arm-ct": {"method": "none", "test.gain": 1.0, "actuation.feedback": "ct"},
    "arm-idpd": {"method": "none", "test.gain": 1.0, "actuation.feedback": "id-pd"},
    "arm-pdg": {"method": "none", "test.gain": 1.0, "actuation.feedback": "pd-gravity"},
    "arm-pd": {"method": "none", "test.gain": 1.0, "actuation.feedback": "inertia-pd"},
    "fel-arm": ARM_FEL,
    "fel-arm-cycle": {**ARM_FEL, "method.fit": "cycle"},
    "fel-arm-rls": {**ARM_FEL, "method.fit": "rls"},
}
#: The 3D arm's ESN in the arm-dynamics rows (2D: the default 200 units), and its FEL's
#: learning cycles per epoch (2D: 3)
ARM_3D = {"esn.n_reservoir": 500}
ARM_3D_CYCLES = 6
#: The 3D arm's stiffer teacher (group ``omega20``): the inertia-scaled PD's poles at 20 rad/s
#: (omega dt = 0.4 at 50 Hz; the arm rows': 5) and the readout's statistics kept with
#: forgetting 0.9 per learning cycle (the arm rows': 0.8)
STIFF = {"actuation.omega": 20.0, "method.fit.forgetting": 0.9}
#: The general rows' babbling speeds (rad/s), and 15 s of it: ``2d-general-first``'s movement
SLOW = "vmin=0.5,vmax=4"
BABBLE15 = f"babble:seed=0,duration=15,{SLOW}"
#: perturbation id -> test-plant changes
PERTURBATIONS = {"payload1": {"actuation.test_payload_kg": 1.0},
                 "mass+20": {"actuation.test_mass_scale": 1.2},
                 "mass-20": {"actuation.test_mass_scale": 0.8}}
#: goals for the ESN alone on YMCA (position NRMSE), by body: the limit-scaled PD
#: teacher's (GOALS) and the inertia-scaled teacher's (ARM_GOALS); computed torque's
#: joint-angle NRMSE goal and its torque budget (x the movement's mean |tau| need)
GOALS = {"2d": 0.03, "3d": 0.06}
ARM_GOALS = {"2d": 0.010, "3d": 0.008}
CT_JOINT_GOAL, TORQUE_BUDGET = 0.008, 1.5
TABLE_COLUMNS = {"position_nrmse": "test position NRMSE", "joint_nrmse": "joint-angle NRMSE",
                 "rms_error_deg": "RMS joint error (°)", "peak_error_deg": "peak joint error (°)",
                 "hand_error_cm": "RMS hand error (cm)", "motor_nrmse": "test motor NRMSE",
                 "mean_abs_torque_nm": "mean |τ| (N m)", "energy_j": "motor work (J)",
                 "max_torque_ratio": "max |τ|/limit",
                 "limit_overshoot_rad": "past a joint limit (rad)", "warnings": "MuJoCo warnings",
                 "train_wall_s": "wall per run (s)"}
BODIES = {"2d": 4, "3d": 8}
#: ``--quick`` (a smoke test): 2 epochs of every FEL row (the long rows 2 x 2)
QUICK_EPOCHS = 2


def _row(row_id: str, overrides: dict, epochs: int | None = None, factor: int = 1) -> Row:
    """A row; ``epochs``: a FEL row's epochs of K 1 -> 0 (x ``factor``; --quick: 2 x
    ``factor``), None for a row that learns nothing by FEL."""
    if epochs is None:
        return Row(row_id, overrides)
    return Row(row_id, {**overrides, "method.epochs": epochs * factor},
               quick={"method.epochs": QUICK_EPOCHS * factor})


def _learns(changes: dict) -> bool:
    return changes.get("method") in ("original", "new")


def _rows() -> tuple[Row, ...]:
    out = []
    for bd, dof in BODIES.items():
        for mv, traj in (("ymca", YMCA), ("md02", None)):
            where = {"plant.dof": dof, **({} if traj is None else {"movement.trajectory": traj})}
            for ctl, changes in CONTROLLERS.items():
                out.append(_row(f"{bd}-{mv}-{ctl}", {**where, **changes},
                                EPOCHS if _learns(changes) else None))
    ymca2 = {"plant.dof": 4, "movement.trajectory": YMCA}
    for pert, changes in PERTURBATIONS.items():
        for ctl, gain in (("fel-new-gff-k0", 0.0), ("fel-new-gff-k1", 1.0)):
            out.append(_row(f"2d-ymca-{pert}-{ctl}", {**ymca2, **CONTROLLERS["fel-new-gff"],
                                                      "test.gain": gain, **changes}, EPOCHS))
        out.append(_row(f"2d-ymca-{pert}-pd", {**ymca2, **CONTROLLERS["pd"], **changes}))
    out.append(_row("2d-ymca-kinematic", {**ymca2, "actuation": "velocity", "method": "new"},
                    EPOCHS))
    for bd, dof in BODIES.items():
        for ctl in ("pd", "ct", "fel-new", "fel-new-gff"):
            changes = CONTROLLERS[ctl]
            out.append(_row(f"{bd}-rec-{ctl}", {"plant.dof": dof, "movement.trajectory":
                                                RECORDED, **changes},
                            EPOCHS if _learns(changes) else None))
    for bd, dof in BODIES.items():  # the arm's own dynamics
        size = {} if dof == 4 else ARM_3D
        cycles = {} if dof == 4 else {"method.cycles": ARM_3D_CYCLES}
        for mv, traj in (("ymca", YMCA), ("rec", RECORDED)):
            for ctl, changes in ARM_CONTROLLERS.items():
                if mv == "rec" and ctl in ("fel-arm-cycle", "fel-arm-rls"):
                    continue
                learns = _learns(changes)
                out.append(_row(f"{bd}-{mv}-{ctl}", {"plant.dof": dof, "movement.trajectory":
                                                     traj, **changes, **size,
                                                     **(cycles if learns else {})},
                                ARM_EPOCHS if learns else None))
        for pert, changes in PERTURBATIONS.items() if bd == "2d" else ():
            for ctl, gain in (("fel-arm-k0", 0.0), ("fel-arm-k1", 1.0)):
                out.append(_row(f"{bd}-ymca-{pert}-{ctl}", {
                    "plant.dof": dof, "movement.trajectory": YMCA, **ARM_FEL, **size,
                    **cycles, "test.gain": gain, **changes}, ARM_EPOCHS))
            out.append(_row(f"{bd}-ymca-{pert}-arm-ct", {
                "plant.dof": dof, "movement.trajectory": YMCA, **ARM_CONTROLLERS["arm-ct"],
                **changes}))
    for mv, traj in (("ymca", YMCA), ("rec", RECORDED)):  # 3 cycles x 30 epochs instead
        out.append(_row(f"3d-{mv}-fel-arm-long", {"plant.dof": 8, "movement.trajectory": traj,
                                                  **ARM_FEL, **ARM_3D},
                        ARM_EPOCHS, 2))
    return (*out, *_general_rows(), *_stiff_rows())


def _general_row(row_id: str, overrides: dict, seeds_of: str | None = None) -> Row:
    """A row tested on the unseen clips (:data:`general.SHAPE`), joint-angle signals."""
    learns = _learns(overrides) or "method" not in overrides
    row = _row(row_id, {"plant.signals": "joint", **overrides},
               overrides.get("method.epochs", ARM_EPOCHS) if learns else None)
    return Row(row.id, row.overrides, seeds_of=seeds_of, params={"tests": tuple(general.TESTS)},
               quick={**row.quick, "tests": ("md_02-feasible", "ymca")},
               shape=general.SHAPE)


def _oracle_preset(dof: int) -> dict:
    """The torque general preset's keys without its sensing (this study senses as an
    oracle)."""
    return {k: v for k, v in preset_fields("general", "torque", dof=dof).items()
            if not k.startswith("actuation.sensing")}


def _general_rows() -> tuple[Row, ...]:
    """Computed torque and the torque-limited floor (iLQR, one deterministic run) on the
    test columns, 15 s of slow babbling
    (``2d-general-first``, on whose seeds the 2D preset runs) and the preset of each body
    (``skinny train --preset general --actuation torque [--dof 8]``)."""
    out = [_general_row(f"{bd}-general-arm-ct", {"plant.dof": dof, **ARM_CONTROLLERS["arm-ct"]})
           for bd, dof in BODIES.items()]
    out += [Row(f"{bd}-general-floor", {"plant.dof": dof, "plant.signals": "joint",
                                        "method": "none", "test.gain": 1.0},
                runs=1, params={"tests": general.FLOOR_TESTS, "iterations": 150},
                quick={"tests": ("ymca",), "iterations": 1},
                run_batch=general.floor_batch)
            for bd, dof in BODIES.items()]
    out.append(_general_row("2d-general-first", {"plant.dof": 4, "movement.trajectory":
                                                 BABBLE15, **ARM_FEL}))
    out.append(_general_row("2d-general", _oracle_preset(4), seeds_of="2d-general-first"))
    out.append(_general_row("3d-general", _oracle_preset(8)))
    return (*out, *_held_out_rows())


def _held_out_rows() -> tuple[Row, ...]:
    """Group ``held-out``: the candidates of :data:`general.HELD_OUT` per body, the preset
    as it ships (its sensing too) with the candidate's changes, on the first candidate's
    seeds, tested on :data:`general.HELD_OUT_TESTS`."""
    out = []
    for bd, dof in BODIES.items():
        first = None
        for name, changes in general.HELD_OUT[dof].items():
            keys = {**preset_fields("general", "torque", dof=dof), **changes}
            row = _general_row(f"{bd}-heldout-{name}", {"actuation.sensing": "encoders", **keys})
            out.append(dataclasses.replace(
                row, seeds_of=first, group="held-out", runs=general.HELD_OUT_RUNS,
                params={"tests": general.HELD_OUT_TESTS}))
            first = first or row.id
    return tuple(out)


def _stiff_rows() -> tuple[Row, ...]:
    """Group ``omega20``: the 3D ``fel-arm`` rows with :data:`STIFF`, on the seeds of the row
    each changes, and the inertia-scaled PD alone with those poles on the recorded-like
    YMCA (the learner against its teacher alone)."""
    base = {"plant.dof": 8, **ARM_FEL, **ARM_3D, "method.cycles": ARM_3D_CYCLES}
    out = []
    for mv, traj in (("rec", RECORDED), ("ymca", YMCA)):
        row = _row(f"3d-{mv}-fel-arm-omega20+forget0.9",
                   {**base, "movement.trajectory": traj, **STIFF}, ARM_EPOCHS)
        out.append(Row(row.id, row.overrides, seeds_of=f"3d-{mv}-fel-arm", group="omega20",
                       quick=row.quick))
    pd = {"plant.dof": 8, "movement.trajectory": RECORDED, **ARM_CONTROLLERS["arm-pd"], **ARM_3D,
          "actuation.omega": STIFF["actuation.omega"]}
    out.append(Row("3d-rec-arm-pd-omega20", pd, seeds_of="3d-rec-fel-arm", group="omega20"))
    return tuple(out)


def _groups(rows: tuple[Row, ...]) -> dict[str, tuple[str, ...]]:
    """``table``, ``robust``, ``kinematic``, each per body (``table-2d``, ...), the
    arm-dynamics rows' (``arm-table``, ``arm-robust``, ...), the torque general preset's
    (``general``, ``general-2d``, ...), and each body's rows."""
    out: dict[str, tuple[str, ...]] = {}
    for row in rows:
        if row.group is not None:  # its own group and its body's
            out[row.id[:2]] = (*out.get(row.id[:2], ()), row.id)
            continue
        kind = "kinematic" if row.id.endswith("kinematic") else \
            "robust" if any(p in row.id for p in PERTURBATIONS) else "table"
        is_general = row.id[3:].startswith("general")
        arm = "arm" in row.id.split("-") and not is_general
        for g in (kind, f"{kind}-{row.id[:2]}", row.id[:2],
                  *((f"arm-{kind}", f"arm-{kind}-{row.id[:2]}") if arm else ()),
                  *(("general", f"general-{row.id[:2]}") if is_general else ())):
            out[g] = (*out.get(g, ()), row.id)
    return out


def metrics(result: RunResult) -> dict[str, Any]:
    """One run's metrics: the test's NRMSEs, joint-angle NRMSE and robot figures, the
    learning curves, the torque figures."""
    test, train = result.test, result.train
    metrics = {"position_nrmse": test.position_nrmse, "motor_nrmse": test.motor_nrmse,
               "train_wall_s": result.wall_s, "joint_nrmse": training.torque.joint_nrmse(result)}
    if train.kind != "none":  # learning curves, per epoch (kept in the run file)
        metrics["curve_position_nrmse"] = train.position_nrmse
    for key in ("feedback_share", "error_signal_share"):
        if key in train.extra:
            metrics[f"curve_{key}"] = train.extra[key]
    if "limit_overshoot_rad" in train.extra:  # over every training cycle
        metrics["train_limit_overshoot_rad"] = train.extra["limit_overshoot_rad"]
    tq = test.torque_figures
    if tq is not None:
        metrics.update({k: tq[k] for k in ("mean_abs_torque_nm", "energy_j",
                                           "max_commanded_ratio", "max_applied_ratio",
                                           "limit_overshoot_rad")})
        metrics["max_torque_ratio"] = max(tq["max_commanded_ratio"], tq["max_applied_ratio"])
        metrics["warnings"] = tq["warnings"] + (result.train_warnings or 0)
    # joint error (deg), hand error (cm), lag (s); torque body: RMS torque, |work|
    metrics.update(result.robot_figures())
    return metrics


ROWS = _rows()
#: ``--quick`` sweeps every row but the group ``omega20`` (the 3D ``fel-arm`` rows with other
#: poles) and the 3D preset (240 s of babbling: the longest run)
QUICK_ROWS = tuple(r.id for r in ROWS if r.group is None and r.id != "3d-general")
STUDY = Study(
    name=NAME, description=__doc__, rows=ROWS, runs=10, groups=_groups(ROWS),
    # every row on the torque twin with Cartesian signals; the md02 rows' movement is
    # the base's (--movement replaces it)
    # the oracle's sensing (noise-free joint velocities): this study measures what the
    # controllers can do at best, their model the nominal arm (the robustness rows' test
    # plants differ from it); the mismatch study takes realistic sensing
    base=TrainConfig().override({"actuation": "torque", "plant.signals": "cartesian",
                                 "movement.trajectory": CLIP, "actuation.sensing": "oracle"}),
    metrics=metrics, columns=TABLE_COLUMNS,
    # a smoke test, not a reproduction: 2 runs, 2 epochs of each FEL row
    quick=Quick(runs=2, rows=QUICK_ROWS), takes=("movement", "signals"),
    report="skinny_mj.experiments.dynamic.report:report",
)
