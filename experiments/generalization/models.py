"""Train the general models that ship with the package (``skinny_mj/data/models``).

``python -m skinny_mj.experiments.generalization.models [--only NAME] [--work DIR]``
runs, for every shipped name of :data:`skinny_mj.training.presets.SHIPPED`,
``skinny train --preset general --dof D --signals S --seed 0`` (of
:data:`~skinny_mj.training.presets.SHIPPED_TORQUE`: ``skinny train --preset general
--actuation torque --dof D --seed 0``) and writes its
``model.npz`` (weights, config and training metadata, no pickle) compressed to
``skinny_mj/data/models/NAME.npz``: the arrays are the same, only smaller on disk. A
model is reproduced from its own metadata (``config`` and ``training.seed``), which
``tests/test_generalization_models.py`` checks bit for bit.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from skinny_mj.cli import parser as cli
from skinny_mj.io import atomic_path
from skinny_mj.training.presets import SHIPPED, SHIPPED_NAMES, SHIPPED_TORQUE

#: The package-data folder of the shipped models (in a source checkout).
MODELS_DIR = Path(__file__).resolve().parents[2] / "skinny_mj" / "data" / "models"


def compress(src: Path, dest: Path) -> Path:
    """``dest``: the arrays of the model ``src`` (an :meth:`ESN.save` file), compressed."""
    with np.load(src, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    with atomic_path(dest) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    return dest


def train_shipped(name: str, work: Path, seed: int = 0) -> dict:
    """Train shipped model ``name`` with ``skinny train`` into ``work/name``: the wall and
    CPU seconds of the command, its metrics.json's test NRMSE and wall time, and the
    compressed file's size."""
    if name in SHIPPED_TORQUE:
        body = ["--actuation", "torque", "--dof", str(SHIPPED_TORQUE[name])]
    else:
        dof, signals = SHIPPED[name]
        body = ["--dof", str(dof), "--signals", signals]
    out = work / name
    start, cpu = time.perf_counter(), time.process_time()
    code = cli.main(["train", "--preset", "general", *body, "--seed", str(seed),
                     "--out", str(out), "--quiet"])
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    if code != 0:
        raise SystemExit(f"training {name} failed (exit {code}); see {out}/metrics.json")
    dest = compress(out / "model.npz", MODELS_DIR / f"{name}.npz")
    metrics = json.loads((out / "metrics.json").read_text())
    return {"name": name, "wall_s": wall, "cpu_s": cpu, "train_wall_s": metrics.get("wall_s"),
            "test_position_nrmse": metrics["test"]["position_nrmse"],
            "bytes": dest.stat().st_size, "bytes_uncompressed": (out / "model.npz").stat().st_size}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", choices=SHIPPED_NAMES, action="append",
                        help="train only this model (repeatable; default: all)")
    parser.add_argument("--work", type=Path, default=Path("results/shipped_models"),
                        help="folder of the `skinny train` runs (default: %(default)s)")
    args = parser.parse_args(argv)
    for name in args.only or SHIPPED_NAMES:
        print(json.dumps(train_shipped(name, args.work / time.strftime("%Y%m%d-%H%M%S"))),
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
