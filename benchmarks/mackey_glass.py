"""Mackey-Glass (tau = 17) 84-step free-run prediction, after Jaeger & Haas (2004).

Each trial: a fresh series and a fresh reservoir; the ESN is teacher-forced through
``washout + train`` samples (output feedback, states after the washout collected),
the readout fitted, then the network runs free for 84 steps. The error is
Jaeger & Haas's NRMSE_84 = sqrt(mean over trials of (y(84) - d(84))^2 / var(d)),
reported as log10 (they reach about -4.2 with N = 1000). All trials step in lockstep
as the runs of one batched ESN.

    python benchmarks/mackey_glass.py                 # N = 400
    python benchmarks/mackey_glass.py --reservoir 1000
    python benchmarks/mackey_glass.py --reservoir 1000 --reservoirpy   # + reservoirpy 0.4
                                                                       # on the same series
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from skinny_mj.controllers.esn import ESN, ESNConfig, run_generators
from skinny_mj.controllers.mackey_glass import mackey_glass

HORIZON = 84


def run(args: argparse.Namespace) -> dict:
    """Run the benchmark; returns log10 NRMSE_84 and the per-step free-run curve."""
    gens = run_generators(args.seed, args.trials)
    length = args.washout + args.train + HORIZON
    series = np.stack([mackey_glass(length, g) for g in gens])[..., None]  # (R, L, 1)
    cfg = ESNConfig(
        n_inputs=1, n_outputs=1, n_reservoir=args.reservoir,
        spectral_radius=args.spectral_radius, bias=args.bias, input_scaling=1.0,
        leak_rate=args.leak, noise_level=args.noise, output_feedback=True,
        feedback_scaling=args.feedback_scaling, readout_activation="identity",
        readout="ridge" if args.ridge > 0 else "pinv", ridge_lambda=args.ridge,
    )
    esn = ESN(cfg, n_runs=args.trials, rngs=gens)
    n_fit = args.washout + args.train
    zeros = np.zeros((args.trials, n_fit, 1))
    t0 = time.perf_counter()
    _, states = esn.run(zeros, noise=True, teacher=series[:, :n_fit], washout=args.washout)
    esn.fit(states, series[:, args.washout + 0 : n_fit])
    # re-drive the fitted network noise-free to the end of the teacher before the free run
    esn.reset()
    esn.run(zeros, noise=False, teacher=series[:, :n_fit])
    esn.y = series[:, n_fit - 1].copy()
    free = np.stack([esn.step(np.zeros((args.trials, 1)), noise=False)
                     for _ in range(HORIZON)], axis=1)
    wall = time.perf_counter() - t0
    target = series[:, n_fit:]
    variance = series[:, args.washout:n_fit].var()
    nrmse_t = np.sqrt(np.mean((free - target) ** 2, axis=(0, 2)) / variance)
    return {"log10_nrmse84": float(np.log10(nrmse_t[-1])), "curve": nrmse_t,
            "diverged": int(esn.is_diverged().sum()), "wall_s": wall}


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--reservoir", type=int, default=400)
    p.add_argument("--trials", type=int, default=10)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--washout", type=int, default=1000)
    p.add_argument("--train", type=int, default=2000)
    p.add_argument("--spectral-radius", type=float, default=0.95)
    p.add_argument("--leak", type=float, default=0.6)
    p.add_argument("--noise", type=float, default=1e-8, help="uniform state noise level")
    p.add_argument("--ridge", type=float, default=0.0, help="0 = pseudoinverse")
    p.add_argument("--bias", type=float, default=0.2)
    p.add_argument("--feedback-scaling", type=float, default=0.56)
    p.add_argument("--reservoirpy", action="store_true",
                   help="compare with reservoirpy on the same series (skinny_mj.cli.bench)")
    args = p.parse_args(argv)
    if args.reservoirpy:
        from skinny_mj.cli.bench_mackey_glass import mackey_glass as compare

        print(compare(args.reservoir, args.trials, args.washout, args.train, args.seed))
        return
    out = run(args)
    print(f"N={args.reservoir} trials={args.trials}: log10 NRMSE_84 = "
          f"{out['log10_nrmse84']:.2f} (Jaeger & Haas 2004, N=1000: about -4.2); "
          f"log10 NRMSE at steps 1/17/84: "
          f"{np.log10(out['curve'][[0, 16, 83]]).round(2).tolist()}; "
          f"diverged runs: {out['diverged']}; {out['wall_s']:.1f} s")


if __name__ == "__main__":
    main()
