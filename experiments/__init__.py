"""One module per paper; each regenerates its table and figures through the shared engine
(:mod:`skinny_mj.experiment`). A module exposes ``NAME``, ``build(quick, movement, asf)
-> Experiment`` and ``report(results, out_dir) -> str`` (figures + the paper's claims).
"""

from __future__ import annotations

import importlib
from types import ModuleType

from skinny_mj.errors import SkinnyInputError

REGISTRY = {
    "paper-a": "experiments.paper_a",
    "paper-b": "experiments.paper_b",
    "paper-c": "experiments.paper_c",
    "paper-d": "experiments.paper_d",
    "paper-e": "experiments.paper_e",
}


def get(name: str) -> ModuleType:
    if name not in REGISTRY:
        raise SkinnyInputError(f"unknown experiment {name!r}; known: {', '.join(REGISTRY)}")
    return importlib.import_module(REGISTRY[name])


def describe(name: str) -> str:
    doc = get(name).__doc__ or ""
    return doc.strip().splitlines()[0] if doc.strip() else ""
