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
- ``arm-table``, ``arm-robust``: the arm's own dynamics (:mod:`skinny_mj.controllers.torque_arm`,
  poles placed in inertia-scaled coordinates): ``arm-ct`` computed torque (omega 15
  rad/s), ``arm-idpd`` inverse-dynamics feed-forward + PD (omega 5), ``arm-pdg`` PD +
  gravity compensation (omega 15), ``arm-pd`` the inertia-scaled PD alone (omega 5, the
  teacher's gains), all zeta = 1 and K = 1; ``fel-arm`` ESN + FEL with that PD's
  feedback torque as the error signal (beta = 1, 3 cycles x 15 epochs, K 1 -> 0; readout
  on the normal equations with forgetting 0.8 and ridge 1e-2; the 3D ESN has 500
  units), ``fel-arm-cycle`` / ``fel-arm-rls`` the same with the readout refitted on
  each cycle alone / by RLS; robustness rows as above with ``fel-arm`` and ``arm-ct``.
- ``kinematic``: ``2d-ymca-kinematic`` is the velocity-servo run of paper E's schedule,
  for the wall-time ratio.

Metrics per run: test position / joint-angle / motor NRMSE (motor: against the
normalized inverse-dynamics torques), mean |applied torque| (N m), positive motor work
(J), max |commanded| and |applied| torque / limit, MuJoCo warnings of the training and
test plants, the wall time per run (lockstep batch / R), and the learning curves
(position NRMSE and feedback share per epoch) in the run files. Goals, targets to
measure against (not numbers tuned to): computed torque <= 0.008 joint-angle NRMSE on
YMCA and the recorded-like YMCA with mean |tau| <= 1.5x the movement's need; the ESN
alone (K = 0) on YMCA <= 0.010 (2D) and <= 0.008 (3D) position NRMSE; earlier goals
(limit-scaled PD teacher) <= 0.03 (2D) and <= 0.06 (3D).
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

from skinny_mj.engine.experiment import Experiment, Row, RunFailed
from skinny_mj.engine.options import config_from_dict
from skinny_mj.engine.sweep import one_of_batch
from skinny_mj.training.config import TrainConfig, relative_cost

NAME = "dynamic"
#: controller id -> TrainConfig overrides
CONTROLLERS = {
    "pd": {"rule": "none", "test.gain": 1.0},
    "ct": {"rule": "none", "test.gain": 1.0, "actuation.feedback": "computed-torque"},
    "fel-orig": {"rule": "original"},
    "fel-new": {"rule": "new", "rule.beta": 0.1},
    "fel-new-gff": {"rule": "new", "rule.beta": 0.1, "actuation.gravity_feedforward": True},
    "tt": {"rule": "true-target", "rule.beta": 0.1},
}
#: The arm's own dynamics (skinny_mj.controllers.torque_arm): the textbook controllers alone
#: (K = 1) and FEL with the inertia-scaled PD teacher (beta = 1, 3 learning cycles per
#: epoch, 15 epochs of K 1 -> 0; readout on the normal equations with forgetting 0.8,
#: ridge 1e-2, or on each cycle alone, or by RLS)
ARM_FEL = {"rule": "new", "rule.beta": 1.0, "rule.cycles": 3, "rule.epochs": 15,
           "actuation.feedback": "inertia-pd", "rule.fit": "forgetting"}
ARM_CONTROLLERS = {
    "arm-ct": {"rule": "none", "test.gain": 1.0, "actuation.feedback": "ct"},
    "arm-idpd": {"rule": "none", "test.gain": 1.0, "actuation.feedback": "id-pd"},
    "arm-pdg": {"rule": "none", "test.gain": 1.0, "actuation.feedback": "pd-gravity"},
    "arm-pd": {"rule": "none", "test.gain": 1.0, "actuation.feedback": "inertia-pd"},
    "fel-arm": ARM_FEL,
    "fel-arm-cycle": {**ARM_FEL, "rule.fit": "cycle"},
    "fel-arm-rls": {**ARM_FEL, "rule.fit": "rls"},
}
#: reservoir size of the 3D arm's ESN in the arm-dynamics rows (2D: the default 200)
ARM_RESERVOIR_3D = 500
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
                 "motor_nrmse": "test motor NRMSE",
                 "mean_abs_torque_nm": "mean |τ| (N m)", "energy_j": "motor work (J)",
                 "max_torque_ratio": "max |τ|/limit", "warnings": "MuJoCo warnings",
                 "train_wall_s": "wall per run (s)"}


@dataclass(frozen=True)
class Config:
    """Shared parameters; rows vary the rest."""

    bodies: tuple[str, ...] = ("2d", "3d")
    ymca: str = "ymca"
    recorded: str = "ymca-recorded"  # the recorded-like YMCA: never still, marker noise
    clip: str = "md_02.amc@start=3,duration=6.26"
    signals: str = "cartesian"
    epochs: int = 10
    arm_epochs: int = 15  # FEL with the inertia-scaled teacher (ARM_FEL)
    runs: int = 10

    @classmethod
    def from_dict(cls, d: dict) -> Config:
        return config_from_dict(cls, d)


def all_rows(cfg: Config) -> tuple[Row, ...]:
    out = []
    for bd in cfg.bodies:
        for mv, traj in (("ymca", cfg.ymca), ("md02", cfg.clip)):
            for ctl, changes in CONTROLLERS.items():
                out.append(Row(f"{bd}-{mv}-{ctl}", {"plant.dof": 4 if bd == "2d" else 8,
                                                    "movement.trajectory": traj, **changes}))
    if "2d" in cfg.bodies:
        for pert, changes in PERTURBATIONS.items():
            for ctl, gain in (("fel-new-gff-k0", 0.0), ("fel-new-gff-k1", 1.0)):
                out.append(Row(f"2d-ymca-{pert}-{ctl}", {
                    "plant.dof": 4, "movement.trajectory": cfg.ymca,
                    **CONTROLLERS["fel-new-gff"], "test.gain": gain, **changes}))
            out.append(Row(f"2d-ymca-{pert}-pd", {"plant.dof": 4, "movement.trajectory": cfg.ymca,
                                                  **CONTROLLERS["pd"], **changes}))
        out.append(Row("2d-ymca-kinematic", {"plant.dof": 4, "movement.trajectory": cfg.ymca,
                                             "actuation": "velocity", "rule": "new"}))
    for bd in cfg.bodies:  # appended last, so the rows above keep their seeds
        for ctl in ("pd", "ct", "fel-new", "fel-new-gff"):
            out.append(Row(f"{bd}-rec-{ctl}", {"plant.dof": 4 if bd == "2d" else 8,
                                               "movement.trajectory": cfg.recorded,
                                               **CONTROLLERS[ctl]}))
    for bd in cfg.bodies:  # the arm's own dynamics, appended after every earlier row
        dof = 4 if bd == "2d" else 8
        size = {} if dof == 4 else {"esn.n_reservoir": ARM_RESERVOIR_3D}
        for mv, traj in (("ymca", cfg.ymca), ("rec", cfg.recorded)):
            for ctl, changes in ARM_CONTROLLERS.items():
                if mv == "rec" and ctl in ("fel-arm-cycle", "fel-arm-rls"):
                    continue
                out.append(Row(f"{bd}-{mv}-{ctl}", {"plant.dof": dof,
                                                    "movement.trajectory": traj,
                                                    **changes, **size}))
        for pert, changes in PERTURBATIONS.items() if bd == "2d" else ():
            for ctl, gain in (("fel-arm-k0", 0.0), ("fel-arm-k1", 1.0)):
                out.append(Row(f"{bd}-ymca-{pert}-{ctl}", {
                    "plant.dof": dof, "movement.trajectory": cfg.ymca, **ARM_FEL, **size,
                    "test.gain": gain, **changes}))
            out.append(Row(f"{bd}-ymca-{pert}-arm-ct", {
                "plant.dof": dof, "movement.trajectory": cfg.ymca, **ARM_CONTROLLERS["arm-ct"],
                **changes}))
    if "3d" in cfg.bodies:  # the 3D ESN still learning at its last epoch: twice as many
        for mv, traj in (("ymca", cfg.ymca), ("rec", cfg.recorded)):
            out.append(Row(f"3d-{mv}-fel-arm-long", {"plant.dof": 8, "movement.trajectory": traj,
                                                     **ARM_FEL,
                                                     "esn.n_reservoir": ARM_RESERVOIR_3D,
                                                     "epoch_factor": 2}))
    return tuple(out)


def groups(every: tuple[Row, ...]) -> dict[str, tuple[str, ...]]:
    """``table``, ``robust``, ``kinematic`` and one group per body (``2d``, ``3d``)."""
    out: dict[str, tuple[str, ...]] = {}
    for row in every:
        kind = "kinematic" if row.row_id.endswith("kinematic") else \
            "robust" if any(p in row.row_id for p in PERTURBATIONS) else "table"
        arm = "arm" in row.row_id.split("-")
        for g in (kind, f"{kind}-{row.row_id[:2]}",
                  *((f"arm-{kind}", f"arm-{kind}-{row.row_id[:2]}") if arm else ())):
            out[g] = (*out.get(g, ()), row.row_id)
    return out


def train_config(cfg: Config, row: Row) -> TrainConfig:
    p = dict(row.params)
    factor = p.pop("epoch_factor", 1)
    tc = TrainConfig().override({"actuation": "torque", "plant.signals": cfg.signals, **p})
    if not tc.learns_by_fel:  # the feedback controller alone, or the true target
        return tc
    arm = tc.torque is not None and tc.torque.feedback == "inertia-pd"
    return tc.override({"rule.epochs": cfg.arm_epochs * factor if arm else cfg.epochs})


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    """Several seeds of one row in lockstep; seed by seed what each gets alone."""
    from skinny_mj.training.loop import train_batch

    out = []
    for o in train_batch(train_config(cfg, row), seeds):
        m = o.metrics
        if m["failed"]:
            out.append(RunFailed(m.get("fail_reason") or "diverged"))
            continue
        metrics = {"position_nrmse": m["test"]["position_nrmse"],
                   "motor_nrmse": m["test"]["motor_nrmse"], "train_wall_s": m["wall_s"],
                   "joint_nrmse": joint_nrmse(o)}
        train = m.get("train", {})
        for key in ("position_nrmse", "feedback_share", "error_signal_share"):
            if key in train:  # learning curves, per epoch (kept in the run file)
                metrics[f"curve_{key}"] = train[key]
        tq = m["test"].get("torque")
        if tq is not None:
            metrics.update({k: tq[k] for k in ("mean_abs_torque_nm", "energy_j",
                                               "max_commanded_ratio", "max_applied_ratio")})
            metrics["max_torque_ratio"] = max(tq["max_commanded_ratio"],
                                              tq["max_applied_ratio"])
            metrics["warnings"] = tq["warnings"] + (m.get("train_warnings") or 0)
        out.append(metrics)
    return out


def joint_nrmse(outcome) -> float:
    """Test joint-angle NRMSE (each angle normalized to [-1, 1] over its range) of a
    :class:`skinny_mj.training.loop.TrainOutcome` against its movement's angles."""
    from skinny_mj.controllers.metrics import position_nrmse

    from skinny_mj.plant.body import normalize_angles

    dof = outcome.config.plant.dof
    angles = outcome.test.rollout.angles[:, :, :dof]
    return float(position_nrmse(normalize_angles(angles, dof),
                                normalize_angles(outcome.test.trajectory.angles, dof))[0])


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    return dict(one_of_batch(functools.partial(run_batch, cfg), row, seed))


def cost(cfg: Config, row: Row) -> float:
    """Relative cost: the training's cycles (a torque cycle costs ~2 velocity cycles)."""
    tc = train_config(cfg, row)
    return relative_cost(tc) * (2.0 if tc.torque is not None else 1.0)


def build(*, quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The sweep. ``quick``: 2 runs of 2 epochs (a smoke test). ``movement`` replaces the
    clip (``asf`` is not needed for the shipped CMU clips); ``dof`` 4 or 8 keeps one body;
    ``signals`` the position signals (default Cartesian)."""
    changes: dict = {}
    if movement is not None:
        changes["clip"] = str(movement)
    if dof is not None:
        changes["bodies"] = ("2d",) if int(dof) == 4 else ("3d",)
    if signals is not None:
        changes["signals"] = signals
    if quick:
        changes.update(epochs=2, arm_epochs=2, runs=2)
    cfg = Config(**changes)
    every = all_rows(cfg)
    return Experiment(name=NAME, rows=every, groups=groups(every),
                      run_one=functools.partial(run_one, cfg), config=cfg, runs=cfg.runs,
                      table_columns=TABLE_COLUMNS, run_batch=functools.partial(run_batch, cfg),
                      cost=functools.partial(cost, cfg))


def feasibility_table(movements: tuple[str, ...], bodies: tuple[str, ...]) -> list[str]:
    """Markdown rows: what each movement asks of each body's motors (inverse dynamics of
    the desired motion, :meth:`skinny_mj.plant.dynamics.Dynamics.feasibility`), the DOF with the
    largest peak named."""
    from skinny_mj.plant import body
    from skinny_mj.training.torque import feasibility

    lines = ["| movement | body | peak \\|τ\\|/limit (DOF) | p99 | steps over a limit | "
             "mean \\|τ\\| (N m) | peak speed (rad/s) | peak accel (rad/s²) | motor work (J) "
             "| feasible |", "|---|---|---|---|---|---|---|---|---|---|"]
    for mv in movements:
        for bd in bodies:
            dof = 4 if bd == "2d" else 8
            f = feasibility(dof, torque_movement(dof, mv))
            worst = int(f["peak_ratio"].argmax())
            lines.append(
                f"| {mv} | {bd} | {f['peak_ratio'][worst]:.2f} "
                f"({body.dof_names(dof)[worst]}) | {f['p99_ratio'].max():.2f} | "
                f"{100 * f['over_limit_share'].max():.1f} % | {f['mean_abs_nm'].mean():.2f} | "
                f"{f['peak_speed_rad_s'].max():.1f} | {f['peak_accel_rad_s2'].max():.0f} | "
                f"{f['work_j'].sum():.0f} | {'yes' if f['feasible'] else '**no**'} |")
    return lines


def report(results: dict, out_dir: Path) -> str:
    """The movements' feasibility, the goals, the torque limits and warnings, and the
    wall-time ratio, from the run files on disk."""
    from skinny_mj.experiments.claims import values

    out_dir = Path(out_dir)
    cfg = Config.from_dict(json.loads((out_dir / "config.json").read_text())["config"])
    lines = ["what the movements ask of the motors (inverse dynamics of the desired motion):",
             *feasibility_table((cfg.ymca, cfg.recorded, cfg.clip), cfg.bodies)]
    lines += [f"NOT FEASIBLE on this body: {ln.split('|')[1].strip()} "
              f"({ln.split('|')[2].strip()}): no controller within the limits can track it"
              for ln in lines[3:] if ln.endswith("**no** |")]
    for bd in cfg.bodies:
        for ctl in ("fel-orig", "fel-new", "fel-new-gff", "tt"):
            v = values(out_dir, f"{bd}-ymca-{ctl}", "position_nrmse")
            if v:
                hits = sum(x <= GOALS[bd] for x in v)
                lines.append(f"goal {bd} YMCA {ctl} (K = 0) position NRMSE <= {GOALS[bd]}: "
                             f"{hits} / {len(v)} runs, best {min(v):.4f}")
    lines += arm_report(out_dir, cfg)
    ratios = [x for row in results.get("rows", [])
              for x in values(out_dir, row["row"], "max_torque_ratio")]
    warns = [x for row in results.get("rows", []) for x in values(out_dir, row["row"], "warnings")]
    if ratios:
        lines.append(f"max |torque| / limit over {len(ratios)} runs: {max(ratios):.6f}")
    if warns:
        lines.append(f"MuJoCo warnings over {len(warns)} runs: {int(sum(warns))}")
    kin = values(out_dir, "2d-ymca-kinematic", "train_wall_s")
    dyn = values(out_dir, "2d-ymca-fel-new", "train_wall_s")
    if kin and dyn:
        ratio = (sum(dyn) / len(dyn)) / (sum(kin) / len(kin))
        lines.append(f"wall per run, torque FEL new / kinematic (2D YMCA): {ratio:.2f}x "
                     "(goal <= 3x)")
    arm = values(out_dir, "2d-ymca-fel-arm", "train_wall_s")
    if kin and arm:
        ratio = (sum(arm) / len(arm)) / (sum(kin) / len(kin))
        lines.append(f"wall per run, torque FEL inertia-scaled teacher (15 epochs) / kinematic "
                     f"(10 epochs), 2D YMCA: {ratio:.2f}x (goal <= 2x); per cycle "
                     f"{ratio * 10 / cfg.arm_epochs:.2f}x")
    return "\n".join(lines)


def floor(dof: int, name: str) -> float:
    """The position NRMSE of the best reachable pose of a movement (no controller beats it)."""
    from skinny_mj.training.imitation import movement_stats

    return movement_stats(torque_movement(dof, name))["reachable_floor_position_nrmse"]


def torque_movement(dof: int, name: str):
    """The movement ``name`` as the torque body of ``dof`` DOFs loads it."""
    from skinny_mj.training.parts import load_trajectory

    return load_trajectory(TrainConfig().override({
        "plant.dof": dof, "movement.trajectory": name, "actuation": "torque"}))[0]


def arm_report(out_dir: Path, cfg: Config) -> list[str]:
    """The goals of the arm-dynamics rows, from the run files."""
    import statistics

    from skinny_mj.experiments.claims import values

    from skinny_mj.training.torque import feasibility

    def mean(row: str, metric: str) -> float | None:
        v = values(out_dir, row, metric)
        return statistics.fmean(v) if v else None

    lines = []
    for bd in cfg.bodies:
        dof = 4 if bd == "2d" else 8
        for mv, name in (("ymca", cfg.ymca), ("rec", cfg.recorded)):
            ct, tau = mean(f"{bd}-{mv}-arm-ct", "joint_nrmse"), \
                mean(f"{bd}-{mv}-arm-ct", "mean_abs_torque_nm")
            if ct is not None:
                need = float(feasibility(dof, torque_movement(dof, name))["mean_abs_nm"].mean())
                peak = max(values(out_dir, f"{bd}-{mv}-arm-ct", "max_torque_ratio"))
                lines.append(f"goal {bd} {mv} computed torque joint NRMSE <= {CT_JOINT_GOAL}: "
                             f"{ct:.4f}; mean |τ| {tau:.2f} N m = {tau / need:.2f}x the "
                             f"movement's need {need:.2f} (goal <= {TORQUE_BUDGET}x); max "
                             f"|τ|/limit {peak:.3f}")
            fel, pd = mean(f"{bd}-{mv}-fel-arm", "position_nrmse"), \
                mean(f"{bd}-{mv}-arm-pd", "position_nrmse")
            if fel is not None:
                goal = f" (goal <= {ARM_GOALS[bd]})" if mv == "ymca" else \
                    f" (goal <= the reachable floor {floor(dof, name):.4f} + 0.01)"
                lines.append(f"goal {bd} {mv} ESN + FEL inertia-scaled teacher (K = 0) "
                             f"position NRMSE{goal}: {fel:.4f} over "
                             f"{len(values(out_dir, f'{bd}-{mv}-fel-arm', 'position_nrmse'))} "
                             "runs" + (f"; PD alone with the same gains {pd:.4f} "
                                       f"({pd / fel:.1f}x, goal >= 3x)" if pd else ""))
    return lines
