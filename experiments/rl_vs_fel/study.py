"""ESN + FEL against deep RL (PPO, SAC) on the same tracking task: test error against env
steps and wall time (needs the ``rl`` extra: ``pip install -e '.[rl]'``).

Rows ``<learner>-<body>-<movement>``: learner ``fel`` (ESN + FEL, paper E's experiment 5:
N = 200, new method β = 0.1 with 3 learning cycles per epoch, 10 epochs, K 1 -> 0),
``ppo`` or ``sac`` (stable-baselines3's defaults, CPU); body ``velocity`` (the velocity
servo) or ``torque`` (the torque twin); movement ``ymca`` or ``md02`` (CMU modern dance
md_02, seconds 3 to 9.26, as long as one YMCA). 2D with Cartesian signals by default
(``--dof 8``: 3D).

The task is the gymnasium env :class:`skinny_mj.gym.env.SkinnyEnv` of the same movement,
full scale and sensor noise (0.01) as the ESN's plant. Observation [sensed(t) |
desired(t) | desired(t+1)] (the ESN's inputs are desired(t+1) and sensed(t)); on the
torque body both learners also get [qd_d(t+1) / v_max; qd(t) / v_max], the torque ESN's
velocity inputs. Action: the normalized joint velocity or torque, in [-1, 1]. Reward
(RL only; FEL learns from the feedback controller's motor error): the env's, minus the
mean absolute tracking error of the noise-free signals after each step,
``-mean |desired(t) - true(t)|``; a diverged simulation ends the episode with the worst
reward (-2) for every step left. An episode is one pass of the movement (T - 1 = 312
steps for both movements).

Every run is tested before training and during it (FEL: after every epoch; RL: every
``budget / evals`` env steps, deterministic policy) on a fresh plant, K = 0, by the
position NRMSE :func:`skinny_mj.training.loop.evaluate` computes
(:mod:`skinny_mj.experiments.rl_vs_fel.runs`). Metrics per run: final and best test error, env
steps used, training wall and CPU time (tests excluded), and for 0.05 and 0.02 the env
steps, wall and CPU time of the first test at or below it. Budgets per run (the
study's parameters, :data:`PARAMS`): FEL 10 epochs = 15 600 env steps, PPO the same
15 600, SAC 1 560, chosen for two shared cores; each run's curve stays in its run file.
Groups: ``fel``, ``ppo``, ``sac``, ``velocity``, ``torque``, ``ymca``, ``md02``. Without
the ``rl`` extra the PPO and SAC rows are left out (named, refused in one line) and the
FEL rows run.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from skinny_mj.experiments.rl_vs_fel import runs as runs_mod

from skinny_mj.engine.experiment import RunFailed
from skinny_mj.engine.study import Quick, Row, Study
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.preflight import Estimate
from skinny_mj.training.config import TrainConfig

NAME = "rl-vs-fel"
LEARNERS = ("fel", "ppo", "sac")
BODIES = ("velocity", "torque")
MOVEMENTS = ("ymca", "md02")
#: The ``md02`` rows' movement: CMU modern dance, seconds 3 to 9.26 (as long as one YMCA).
CLIP = "md_02.amc@start=3,duration=6.26"
#: CPU seconds per env step of each learner, measured on the 2D body (the schedule only).
STEP_COST = {"fel": 1e-3, "ppo": 2e-3, "sac": 2.7e-2}
#: Budgets in env steps per run (FEL's: its epochs, ``rule.epochs``), the RL runs' tests
#: after the one before training, the thresholds of the reach columns, and ``quick``
#: (smaller PPO/SAC batches, a smoke test).
PARAMS = {"ppo_steps": 15_600,  # FEL's env steps: 10 epochs x (3 + 2) cycles x 312 steps
          "sac_steps": 1_560,  # a tenth of that (SAC costs ~15x PPO's CPU per env step)
          "evals": 10, "thresholds": (0.05, 0.02), "quick": False}


def _row(learner: str, body: str, movement: str) -> Row:
    """The row's plant and movement (ESN + FEL trains on them; PPO and SAC take them)."""
    clip = {"movement.trajectory": CLIP, "movement.asf": None} if movement == "md02" else {}
    return Row(f"{learner}-{body}-{movement}", {"actuation": body, **clip},
               params={"learner": learner, "movement": movement})


ROWS = tuple(_row(learner, body, mv) for mv in MOVEMENTS for body in BODIES
             for learner in LEARNERS)


def budget(p: Mapping[str, Any], learner: str) -> int:
    return {"ppo": p["ppo_steps"], "sac": p["sac_steps"]}[learner]


def run_batch(config: TrainConfig, row: Row, seeds: list[int]) -> list:
    """One curve per seed (one after the other: each learner runs its seed alone)."""
    p = row.params
    out: list = []
    for seed in seeds:
        if p["learner"] == "fel":
            points, facts = runs_mod.fel_curve(config, seed)
        else:
            points, facts = runs_mod.rl_curve(p["learner"], config, seed,
                                              budget(p, p["learner"]), p["evals"],
                                              quick=p["quick"])
        if facts.pop("failed"):
            out.append(RunFailed("the ESN diverged in training"))
            continue
        out.append({**runs_mod.curve_metrics(points, p["thresholds"]), **facts,
                    "curve": points})
    return out


#: stable-baselines3's defaults: PPO's rollout steps (``quick``: 128), SAC's replay buffer,
#: the hidden layers of their MlpPolicy (PPO: policy and value net; SAC: the actor, two
#: critics and their target copies).
PPO_N_STEPS, SAC_BUFFER, PPO_HIDDEN, SAC_HIDDEN = 2048, 1_000_000, (64, 64), (256, 256)


def _mlp(n_in: int, n_out: int, hidden: tuple[int, ...]) -> int:
    """Parameters of a fully connected net."""
    sizes = (n_in, *hidden, n_out)
    return sum((a + 1) * b for a, b in zip(sizes[:-1], sizes[1:], strict=True))


def estimate_bytes(config: TrainConfig, row: Row, runs: int):
    """The memory a PPO or SAC run of ``row`` needs beyond the process's own (torch and
    stable-baselines3 are imported when the sweep is built): the rollout buffer (PPO) or
    the part of the replay buffer the budget fills (SAC: its zeros are not touched
    before), float64 observations, actions and five scalars per step; the networks'
    float32 weights, gradients and Adam's two moments (a target copy: weights only).
    ESN + FEL rows: None (their training configuration says)."""
    p, dof = row.params, config.plant.dof
    learner = p["learner"]
    if learner == "fel":
        return None
    n_obs = 3 * body.body_of(config.plant.body).n_signals(config.plant.signals) \
        + (2 * dof if config.actuation.kind == "torque" else 0)
    if learner == "ppo":
        steps = 128 if p["quick"] else PPO_N_STEPS
        trained, targets = _mlp(n_obs, dof, PPO_HIDDEN) + _mlp(n_obs, 1, PPO_HIDDEN), 0
    else:
        steps = min(budget(p, learner), SAC_BUFFER)
        critic = _mlp(n_obs + dof, 1, SAC_HIDDEN)
        trained, targets = _mlp(n_obs, 2 * dof, SAC_HIDDEN) + 2 * critic, 2 * critic
    return Estimate({"buffer": steps * (2 * n_obs + dof + 5) * 8,
                     "networks": (4 * trained + targets) * 4},
                    {"buffer": f"{learner} buffer of {steps} steps",
                     "networks": f"{learner}'s networks"})


def cost(config: TrainConfig, row: Row) -> float:
    """One run's CPU seconds, roughly (the schedule only)."""
    learner = row.params["learner"]
    steps = config.rule.epochs * 5 * 312 if learner == "fel" else budget(row.params, learner)
    return steps * STEP_COST[learner] * (2.0 if config.actuation.kind == "torque" else 1.0)


def unavailable_rows() -> dict[str, str]:
    """The PPO and SAC rows need the ``rl`` extra (stable-baselines3, torch)."""
    try:
        runs_mod.require_rl()
    except SkinnyInputError:
        return {r.id: "needs the rl extra: pip install -e '.[rl]'" for r in ROWS
                if r.params["learner"] != "fel"}
    return {}


def _columns(thresholds: tuple[float, ...]) -> dict[str, str]:
    cols = {"position_nrmse": "final test NRMSE", "train_cpu_s": "train CPU (s)"}
    for th in thresholds:
        cols.update({f"steps_to_{th:g}": f"env steps to {th:g}",
                     f"cpu_to_{th:g}": f"CPU (s) to {th:g}"})
    return cols


def _groups() -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for r in ROWS:
        for group in (r.params["learner"], r.overrides["actuation"], r.params["movement"]):
            out.setdefault(group, []).append(r.id)
    return out


STUDY = Study(
    name=NAME, description=__doc__, rows=ROWS, run_batch=run_batch, runs=3, params=PARAMS,
    # paper E's experiment 5 (TrainConfig's defaults): N = 200, new method, β = 0.1,
    # 3 learning cycles per epoch, 10 epochs, K 1 -> 0; 2D, Cartesian signals
    base=TrainConfig().override({"rule.epochs": 10}),
    groups=_groups(), columns=_columns(PARAMS["thresholds"]),
    # a smoke test: 1 run per row, FEL 2 epochs, PPO 256 and SAC 100 env steps
    quick=Quick({"rule.epochs": 2}, runs=1,
                params={"ppo_steps": 256, "sac_steps": 100, "evals": 2, "quick": True}),
    cost=cost, memory=estimate_bytes, unavailable=unavailable_rows,
    report="skinny_mj.experiments.rl_vs_fel.report:report",
)
