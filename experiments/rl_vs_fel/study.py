"""ESN + FEL against deep RL (PPO, SAC) on the torque body, each at its best, with the
same information: learning curves of the test error against env steps and CPU seconds
(PPO and SAC need the ``rl`` extra: ``pip install -e '.[rl]'``).

Learners, each seeing the ESN's input at every step, [d(t+1); s(t); qd_d(t+1) / v_max;
qd(t) / v_max] (desired next and sensed position signals, desired next and sensed joint
velocities):

- ``fel``: ESN + FEL with the project's best torque recipe, the dynamic study's
  ``fel-arm`` rows (:data:`skinny_mj.experiments.dynamic.study.ARM_FEL`): the teacher is
  the inertia-scaled PD (``actuation.feedback=inertia-pd``, poles at 5 rad/s, zeta 1),
  beta = 1, 3 learning cycles per epoch, the readout on the normal equations with
  forgetting 0.8 (``method.fit=forgetting``), K 1 -> 0 over 15 epochs; on the unseen
  clips the torque ``general`` preset (the same teacher and readout, 30 epochs, joint
  signals; :data:`skinny_mj.training.presets.TORQUE_GENERAL`). Tested at K = 0 (the ESN
  alone); its points also hold the test at K = 1 (with the teacher, ``fel-k1`` in the
  report), the controller a residual policy is tested as.
- ``ppo`` / ``sac``: plain RL, the policy's action is the normalized torque, learned
  from the reward ``-mean |d(t+1) - true(t+1)|`` alone.
- ``ppo-res`` / ``sac-res``: residual RL, the action is added to the same feedback
  teacher FEL learns from (the hook the row's config names, so it follows
  ``actuation.feedback`` and its settings), tested with it.

The env is :class:`skinny_mj.experiments.rl_vs_fel.tracking.TrackingEnv`: the training
path's plant and rollout hook, stepped as FEL's rollout steps them. PPO and SAC run with
rl-baselines3-zoo's MuJoCo hyper-parameters and VecNormalize
(:data:`skinny_mj.experiments.rl_vs_fel.agents.HYPERPARAMS`: PPO the zoo's tuned Reacher
entry, the zoo's MuJoCo arm tracking a target by joint torques and the nearest in size;
SAC the zoo's MuJoCo setting), one CPU thread.

Regimes (row ids ``<learner>-<regime>[-<env steps>]``):

- ``ymca``: train and test on YMCA (2D, Cartesian signals), as the dynamic study's
  ``2d-ymca-fel-arm`` row;
- ``general``: train on the torque ``general`` preset's movement (240 s of slow motor
  babbling, then YMCA; joint-angle signals), test on the shipped CMU clips md_02 and
  md_03, never trained on, at one speed every clip is feasible at (0.18, the slower of
  their fastest feasible speeds on the 2D body,
  :data:`skinny_mj.experiments.dynamic.general.FEASIBLE_SPEED`) and at full speed.
  Scores ``clips@0.18`` and ``clips@1`` are the means over the two clips.

Each RL curve is trained in segments of :data:`SEGMENT` env steps, a row each
(``ppo-ymca-500000`` continues the checkpoint ``ppo-ymca-250000`` saved, on its seeds),
so that every run ends within an hour on one core; checkpoints go to the study's
``checkpoints`` folder under ``results/`` (:mod:`skinny_mj.experiments.rl_vs_fel.agents`).
Group ``budget`` (``budget-ymca``, ``budget-general``: one regime's) holds every row up
to the declared budgets (:data:`BUDGET`: PPO 10^6, SAC 10^5 env steps), ``extend`` the
segments past them (PPO to 2 x 10^6, SAC to 2 x 10^5), ``search`` a short
hyper-parameter search on YMCA only (:data:`SEARCH`, each one seed of a one-segment
curve of :data:`SEARCH_STEPS`; a choice made there is a fit on YMCA, the training clip, never on
the unseen clips). Tests: RL at :func:`runs.test_steps`
(log-spaced), FEL after every epoch. Per run: per score the final and best NRMSE, the
final RMS joint error (deg) and for each threshold of :data:`THRESHOLDS` the env steps,
CPU and wall time of the first test at or below it; the whole curve stays in the run
file (``python -m skinny_mj.experiments.rl_vs_fel.data`` exports it to a small JSON
file per curve; the report and page are made from those files).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skinny_mj.experiments.dynamic.general import FEASIBLE_SPEED
from skinny_mj.experiments.dynamic.study import ARM_FEL
from skinny_mj.experiments.rl_vs_fel import runs as runs_mod

from skinny_mj.engine.experiment import RunFailed
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.preflight import Estimate
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.presets import preset_fields
from skinny_mj.trajectories import load_movement

NAME = "rl-vs-fel"
THRESHOLDS = (0.05, 0.02, 0.01)
#: The unseen clips' one feasible speed (the slower clip's fastest, 2D body) and full speed
FIXED_SPEED = min(FEASIBLE_SPEED[4, clip] for clip in ("md_02.amc", "md_03.amc"))
CLIPS = ("md_02", "md_03")
#: regime -> (config overrides, test columns: id -> (movement, speed); None: the
#: training movement's one repetition), scores: name -> the columns it averages)
REGIMES: dict[str, tuple[dict, dict, dict]] = {
    "ymca": ({"actuation": "torque", "plant.signals": "cartesian",
              "movement.trajectory": "ymca", **ARM_FEL},
             {"ymca": None}, {"ymca": ("ymca",)}),
    "general": (preset_fields("general", "torque", dof=4),
                {f"{c}@{s:g}": (f"{c}.amc", s) for s in (FIXED_SPEED, 1.0) for c in CLIPS},
                {f"clips@{s:g}": tuple(f"{c}@{s:g}" for c in CLIPS)
                 for s in (FIXED_SPEED, 1.0)}),
}
#: RL learner -> (stable-baselines3 algorithm, the teacher's gain in the command)
RL = {"ppo": ("ppo", 0.0), "ppo-res": ("ppo", 1.0), "sac": ("sac", 0.0),
      "sac-res": ("sac", 1.0)}
#: The learners of each regime (SAC on YMCA only: an env step of SAC costs 7-10 of PPO's)
LEARNERS = {"ymca": ("fel", *RL), "general": ("fel", "ppo", "ppo-res")}
#: env steps per segment row, the declared budget, the extended one (group ``extend``)
SEGMENT = {"ppo": 250_000, "sac": 25_000}
BUDGET = {"ppo": 1_000_000, "sac": 100_000}
EXTENDED = {"ppo": 2_000_000, "sac": 200_000}
#: The short search on YMCA (group ``search``): name -> (learner, changes to HYPERPARAMS)
SEARCH: dict[str, tuple[str, dict[str, Any]]] = {
    "ppo-std-2": ("ppo", {"log_std_init": -2.0}),
    "ppo-res-std-2": ("ppo-res", {"log_std_init": -2.0}),
    "ppo-lr3e-4": ("ppo", {"learning_rate": 3e-4}),
    "ppo-gamma0.99": ("ppo", {"gamma": 0.99}),
    "sac-gamma0.9": ("sac", {"gamma": 0.9}),
    "sac-res-gamma0.9": ("sac-res", {"gamma": 0.9}),
    "sac-start1000": ("sac", {"learning_starts": 1000}),
}
SEARCH_STEPS = {"ppo": 250_000, "sac": 25_000}
#: CPU seconds per env step on the torque body, one core, training only (measured on YMCA
#: on a shared 2-core machine, docs/results/rl-vs-fel.md): the schedule only
STEP_COST = {"fel": 2.9e-4, "ppo": 2.5e-3, "sac": 2.4e-2}
#: env steps of one pass of each regime's training movement, roughly (the schedule only)
CYCLE_STEPS = {"ymca": 312, "general": 12_400}
#: --quick: env steps of an RL row, FEL's epochs, the general regime's movement and test
QUICK_STEPS = {"ppo": 256, "sac": 100}
QUICK_GENERAL = {"movement.trajectory": "babble:seed=0,duration=4,vmin=0.5,vmax=4"}
QUICK_TESTS = {"md_02@1": ("md_02.amc@start=3,duration=2", 1.0)}


def _label(steps: int) -> str:
    return str(steps)


def _rl_rows(learner: str, regime: str) -> list[Row]:
    algo, _ = RL[learner]
    over, tests, scores = REGIMES[regime]
    step, rows, first = SEGMENT[algo], [], f"{learner}-{regime}-{SEGMENT[algo]}"
    quick: dict[str, Any] = {"span": (0, QUICK_STEPS[algo])}
    if regime == "general":
        quick.update(QUICK_GENERAL, tests=QUICK_TESTS, scores={"quick": tuple(QUICK_TESTS)})
    for k, end in enumerate(range(step, EXTENDED[algo] + 1, step)):
        rows.append(Row(
            f"{learner}-{regime}-{_label(end)}", over, seeds_of=None if k == 0 else first,
            group="budget" if end <= BUDGET[algo] else "extend",
            params={"learner": learner, "regime": regime, "span": (end - step, end),
                    "curve": f"{learner}-{regime}", "segment": k, "changes": {},
                    "tests": tests, "scores": scores}, quick=quick))
    return rows


def _fel_row(regime: str) -> Row:
    over, tests, scores = REGIMES[regime]
    quick: dict[str, Any] = {"method.epochs": 2}
    if regime == "general":
        quick.update(QUICK_GENERAL, tests=QUICK_TESTS, scores={"quick": tuple(QUICK_TESTS)})
    return Row(f"fel-{regime}", over, group="budget",
               params={"learner": "fel", "regime": regime, "curve": f"fel-{regime}",
                       "tests": tests, "scores": scores}, quick=quick)


def _search_rows() -> list[Row]:
    over, tests, scores = REGIMES["ymca"]
    out = []
    for name, (learner, changes) in SEARCH.items():
        algo = RL[learner][0]
        out.append(Row(f"search-{name}", over, group="search", runs=1, params={
            "learner": learner, "regime": "ymca", "span": (0, SEARCH_STEPS[algo]),
            "curve": f"search-{name}", "segment": 0, "changes": changes, "tests": tests,
            "scores": scores}, quick={"span": (0, QUICK_STEPS[algo])}))
    return out


ROWS = (*(r for regime, learners in LEARNERS.items() for learner in learners
          for r in ([_fel_row(regime)] if learner == "fel" else _rl_rows(learner, regime))),
        *_search_rows())
#: the rows --quick sweeps: FEL's and the first segment of each RL curve (no search)
QUICK_ROWS = tuple(r.id for r in ROWS if r.group == "budget"
                   and r.params.get("segment", 0) == 0)
#: Study parameters: the checkpoints folder (relative to where the sweep runs), the
#: thresholds, and ``quick`` (small batches, no checkpoints: a smoke test)
PARAMS = {"checkpoints": "results/rl-vs-fel/checkpoints", "thresholds": THRESHOLDS,
          "quick": False}


def _columns_of(tc: TrainConfig, tests: Mapping[str, Any]) -> dict[str, Any]:
    return {col: None if spec is None else load_movement(spec[0], tc.plant.dof,
                                                         speed=spec[1])[0]
            for col, spec in tests.items()}


def run_batch(config: TrainConfig, row: Row, seeds: list[int]) -> list:
    """One curve (or one segment of one) per seed, one seed after the other."""
    p = row.params
    columns = _columns_of(config, p["tests"])
    out: list = []
    for seed in seeds:
        if p["learner"] == "fel":
            points, facts = runs_mod.fel_curve(config, seed, columns)
            if facts.pop("failed"):
                out.append(RunFailed("the ESN diverged in training"))
                continue
            extra = {f"k1_{k}": v for k, v in runs_mod.curve_metrics(
                points, p["scores"], p["thresholds"], "tests_k1").items() if "__" in k}
        else:
            algo, gain = RL[p["learner"]]
            folder = None if p["quick"] else \
                Path(p["checkpoints"]) / f"{p['curve']}-{seed}"
            points, facts = runs_mod.rl_segment(algo, gain, config, seed, columns,
                                                tuple(p["span"]), folder, p["changes"],
                                                quick=p["quick"])
            facts.pop("failed")
            extra = {}
        out.append({**runs_mod.curve_metrics(points, p["scores"], p["thresholds"]),
                    **extra, **facts, "curve": points})
    return out


def cost(config: TrainConfig, row: Row) -> float:
    """One run's CPU seconds, roughly (the schedule only). A curve's later segments cost
    a hair less, so that the schedule (costliest first, stable) runs them in order."""
    p = row.params
    if p["learner"] == "fel":
        steps = config.method.epochs * (config.learning_cycles + 2) * CYCLE_STEPS[p["regime"]]
        return steps * STEP_COST["fel"]
    algo = RL[p["learner"]][0]
    start, end = p["span"]
    return (end - start) * STEP_COST[algo] * (1.0 - 1e-6 * p["segment"])


def estimate_bytes(config: TrainConfig, row: Row, runs: int):
    """The memory a PPO or SAC run needs beyond the process's own: PPO's rollout buffer
    or the part of SAC's replay buffer the curve fills (float64 observations, actions
    and a few scalars per step). ESN + FEL rows: None (their training configuration
    says)."""
    p = row.params
    if p["learner"] == "fel":
        return None
    from skinny_mj.experiments.rl_vs_fel.agents import HYPERPARAMS

    dof = config.plant.dof
    n_obs = 2 * body.body_of(dof).n_signals(config.plant.signals) + 2 * dof
    algo = RL[p["learner"]][0]
    steps = HYPERPARAMS["ppo"][1]["n_steps"] if algo == "ppo" else p["span"][1]
    return Estimate({"buffer": steps * (2 * n_obs + dof + 5) * 8},
                    {"buffer": f"{algo} buffer of {steps} steps"})


def unavailable_rows() -> dict[str, str]:
    """The PPO and SAC rows need the ``rl`` extra (stable-baselines3, torch)."""
    try:
        runs_mod.require_rl()
    except SkinnyInputError:
        return {r.id: "needs the rl extra: pip install -e '.[rl]'" for r in ROWS
                if r.params["learner"] != "fel"}
    return {}


def _groups() -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for r in ROWS:
        for group in (r.params["learner"], r.params["regime"], r.params["curve"],
                      f"{r.group}-{r.params['regime']}"):
            if group != r.id:
                out.setdefault(group, []).append(r.id)
    return out


COLUMNS = {"env_steps": "env steps", "train_cpu_s": "train CPU (s)",
           "ymca__nrmse": "YMCA NRMSE", f"clips@{FIXED_SPEED:g}__nrmse":
           f"clips @ {FIXED_SPEED:g} NRMSE", "clips@1__nrmse": "clips @ 1 NRMSE"}

STUDY = Study(
    name=NAME, description=__doc__, rows=ROWS, run_batch=run_batch, runs=3, params=PARAMS,
    base=TrainConfig(), groups=_groups(), columns=COLUMNS, takes=(),
    # a smoke test: 1 run of FEL's rows (2 epochs) and of each RL curve's first segment
    # (a few hundred env steps, small batches, no checkpoints); the general regime on 4 s
    # of babbling, tested on 2 s of md_02
    quick=Quick(runs=1, rows=QUICK_ROWS, params={"quick": True}),
    cost=cost, memory=estimate_bytes, unavailable=unavailable_rows,
    report="skinny_mj.experiments.rl_vs_fel.report:report",
)
