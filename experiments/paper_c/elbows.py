"""What moves the Y-pure network's elbows on YM (paper C: "the elbows are not used").

Trains paper C's Y-pure network (its recipe: the row ``y-pure`` of
:data:`skinny_mj.experiments.paper_c.study.STUDY`),
tests it on YM and measures, per elbow, the network's input -> command Jacobian along the
test (one step from the previous reservoir state, tanh readout) and two closed-loop
counterfactual tests: YM with both elbow targets held at Y pure's angle, and with the left
one held; and the timing (cross-correlation lag, steps) of its YM and YMCA tests.
``--quiet`` sets sensor and reservoir noise to 0. Prints one JSON line::

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python -m skinny_mj.experiments.paper_c.elbows --seeds 0 1
"""

from __future__ import annotations

import argparse
import dataclasses
import json

import numpy as np
from skinny_mj.experiments.paper_c import study as paper_c
from skinny_mj.experiments.paper_c.study import lag_steps

from skinny_mj.plant import body
from skinny_mj.training.loop import build_run, evaluate, train_run


def jacobian(esn, r: int, states: np.ndarray, y_esn: np.ndarray, n_in: int) -> np.ndarray:
    """Mean over a rollout of d command / d input, (n_out, n_in), for run ``r``.

    states : (T, D) extended states [x; u; 1]; y_esn : (T, n_out) the outputs."""
    n = esn.cfg.n_reservoir
    x, u = states[:, :n], states[:, n:n + n_in]
    prev = np.vstack([np.zeros((1, n)), x[:-1]])
    pre = np.concatenate([u, np.ones((len(u), 1))], 1) @ esn.W_in[r].T + prev @ esn.W[r].T
    dx = 1.0 - np.tanh(pre) ** 2  # (T, N)
    w = esn.W_out[r]
    grad = np.einsum("tn,nj,on->toj", dx, esn.W_in[r][:, :n_in], w[:, :n]) + w[None, :, n:n + n_in]
    return np.mean((1.0 - y_esn**2)[:, :, None] * grad, axis=0)


def dead_beat_gain(run, joint: int, dof: int, dt: float) -> float:
    """The ideal inverse model's gain on a joint's desired (+) and sensed (−) angle:
    1 / (signal per rad x full-scale speed x dt), normalized units."""
    skinny = body.body_of(dof)
    per_rad = skinny.normalize_angles(np.eye(dof)) - skinny.normalize_angles(
        np.zeros((1, dof)))
    return float(1.0 / (per_rad[joint, joint] * run.max_speed_rad_s[joint] * dt))


def analyse(run, dof: int = 4) -> list[dict]:
    """Per run: YM elbow range ratio and correlation, the elbows' Jacobian rows, and the
    produced elbow ranges (deg) with YM's elbow targets held (both, left only)."""
    names, elbows = body.body_of(dof).dof_names, paper_c.elbow_dofs(dof)
    ym, pure = paper_c.load("ym", dof), paper_c.load("y-pure", dof)
    held, left_held = ym.angles.copy(), ym.angles.copy()
    held[:, elbows] = pure.angles[0, elbows]
    left_held[:, elbows[1]] = pure.angles[0, elbows[1]]
    counter = {name: evaluate(run, dataclasses.replace(ym, angles=a, name=name))
               for name, a in (("elbow targets held", held), ("left target held", left_held))}

    ymca = paper_c.load("ymca", dof)
    ymca_lags = [lag_steps(t.rollout.angles[0], ymca.angles) for t in evaluate(run, ymca)]
    out = []
    for r, test in enumerate(evaluate(run, ym)):
        ro, produced = test.rollout, test.rollout.angles[0]
        jac = jacobian(run.esn, r, ro.states[0], ro.y_esn[0], 2 * dof)
        inputs = [f"desired {n}" for n in names] + [f"sensed {n}" for n in names]
        out.append({
            "seed": run.seeds[r], "ym_position_nrmse": test.position_nrmse,
            "elbow_range_ratio": float(np.mean([np.ptp(produced[:, e]) / np.ptp(ym.angles[:, e])
                                                for e in elbows])),
            "elbow_corr": float(np.mean([np.corrcoef(produced[:, e], ym.angles[:, e])[0, 1]
                                         for e in elbows])),
            "jacobian": {names[e]: dict(zip(inputs, np.round(jac[e], 3).tolist(), strict=True))
                         for e in elbows},
            "dead_beat_gain": dead_beat_gain(run, elbows[0], dof, ym.dt),
            "lag_steps": {"ym": lag_steps(produced, ym.angles), "ymca": ymca_lags[r]},
            **{f"{k}: elbow range (deg)": np.round(np.degrees(np.ptp(
                v[r].rollout.angles[0][:, elbows], axis=0)), 1).tolist()
               for k, v in counter.items()},
        })
    return out


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    p.add_argument("--epochs", type=int, default=150)
    p.add_argument("--quiet", action="store_true", help="sensor and reservoir noise 0")
    a = p.parse_args(argv)
    tc = paper_c.STUDY.config("y-pure").override({"method.epochs": a.epochs})
    if a.quiet:
        tc = tc.override({"esn.noise_level": 0.0, "plant.sensor_noise": 0.0})
    run = build_run(tc, a.seeds)
    train_run(run)
    print(json.dumps(analyse(run)))


if __name__ == "__main__":
    main()
