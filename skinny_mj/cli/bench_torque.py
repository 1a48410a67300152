"""``skinny bench``'s torque figure: a torque run's wall time over the kinematic run's."""

from __future__ import annotations

import functools
from typing import Any


def torque_over_kinematic(n_runs: int, repeats: int, epochs: int | None = None) -> dict:
    """Wall time of a torque FEL run over a kinematic one, both the dynamic study's own
    rows: ``2d-ymca-fel-arm`` (the torque twin, inertia-scaled PD teacher, 15 epochs of 5
    cycles) over ``2d-ymca-kinematic`` (the velocity servo, paper E's 10 epochs of 5
    cycles), ``n_runs`` seeds in lockstep each, timed interleaved (best of ``repeats``);
    ``epochs`` shortens both to that many (a smoke test of this figure)."""
    from skinny_mj.cli.bench_timing import interleaved
    from skinny_mj.engine import registry
    from skinny_mj.training.loop import train_batch

    study = registry.get("dynamic")
    configs = {"torque": study.config("2d-ymca-fel-arm"),
               "kinematic": study.config("2d-ymca-kinematic")}
    if epochs is not None:
        configs = {k: c.override({"rule.epochs": epochs}) for k, c in configs.items()}
    seeds = list(range(n_runs))
    best = interleaved({k: functools.partial(train_batch, c, seeds)
                        for k, c in configs.items()}, repeats)
    out: dict[str, Any] = {"R": n_runs, **{f"{k}_epochs": c.rule.epochs
                                           for k, c in configs.items()}}
    return {**out, "torque_s": best["torque"], "kinematic_s": best["kinematic"],
            "ratio": best["torque"] / best["kinematic"]}
