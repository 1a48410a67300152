"""The study's curves as small JSON data files, one per learning curve and seed, that the
report and the results page are made from without training again.

``<data>/<curve>-<seed>.json``: ``curve`` (``ppo-ymca``: the row id without its
segment), ``learner``, ``regime``, ``seed``, ``scores`` (name -> the test columns it
averages), ``points`` (the curve, :mod:`skinny_mj.experiments.rl_vs_fel.runs`; numbers
to 6 significant digits), ``rows`` (the run files it came from; an RL curve's last
finished segment holds the whole curve so far) and ``diverged_episodes`` (RL).

Export a sweep's finished runs (each curve's longest one)::

    python -m skinny_mj.experiments.rl_vs_fel.data results/rl-vs-fel/full \\
        --data docs/results/rl-vs-fel-data
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from skinny_mj.engine.stats import load_runs
from skinny_mj.io import atomic_write_text

DEFAULT_DATA = Path("docs/results/rl-vs-fel-data")


def _round(value: Any) -> Any:
    if isinstance(value, float):
        return float(f"{value:.6g}")
    if isinstance(value, dict):
        return {k: _round(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_round(v) for v in value]
    return value


def curves_of(sweeps: Iterable[Path]) -> dict[tuple[str, int], dict]:
    """(curve, seed) -> its data record, from the ok runs of the sweep folders (the run
    that reaches the most env steps, where segments overlap)."""
    found: dict[tuple[str, int], dict] = {}
    for sweep in sweeps:
        for run in load_runs(Path(sweep)):
            m = run["metrics"]
            if run["status"] != "ok" or not m.get("curve"):
                continue
            p = run["params"]
            key = (p["curve"], int(run["seed"]))
            record = {"curve": p["curve"], "learner": p["learner"], "regime": p["regime"],
                      "seed": int(run["seed"]), "scores": p["scores"],
                      "points": m["curve"],
                      "rows": [f"{run['row']}-{run['seed']}.json"],
                      "diverged_episodes": m.get("diverged_episodes")}
            old = found.get(key)
            if old is None or old["points"][-1]["steps"] < record["points"][-1]["steps"]:
                found[key] = record
    return found


def export(sweeps: Iterable[Path], data: Path = DEFAULT_DATA) -> list[Path]:
    """Write one data file per (curve, seed) of ``sweeps`` into ``data``; returns them."""
    data = Path(data)
    data.mkdir(parents=True, exist_ok=True)
    out = []
    for (curve, seed), record in sorted(curves_of(sweeps).items()):
        path = data / f"{curve}-{seed}.json"
        atomic_write_text(path, json.dumps(_round(record), indent=1) + "\n")
        out.append(path)
    return out


def load(data: Path = DEFAULT_DATA) -> list[dict]:
    """Every data file's record in ``data`` (sorted by name; none: [])."""
    return [json.loads(p.read_text()) for p in sorted(Path(data).glob("*.json"))]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m skinny_mj.experiments.rl_vs_fel.data",
        description="Export the finished curves of rl-vs-fel sweeps as one small JSON "
                    "file per curve and seed.")
    parser.add_argument("sweeps", nargs="+", type=Path, help="sweep folders (--out)")
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA,
                        help=f"the data folder (default {DEFAULT_DATA})")
    args = parser.parse_args(argv)
    for path in export(args.sweeps, args.data):
        print(path)


if __name__ == "__main__":
    main()
