"""One module per paper, and per question beyond the thesis; each regenerates its table
and figures through the shared engine (:mod:`skinny_mj.experiment`, whose docstring is the
contract). A module exposes ``NAME``, ``build(*, quick, movement, asf, dof, signals) ->
Experiment`` and ``report(results, out_dir) -> str`` (figures + claims).
"""

from __future__ import annotations

from types import ModuleType

from skinny_mj import registry

#: This package's experiments, name -> module: the entry points it declares in pyproject
#: (group ``skinny_mj.experiments``), through which :mod:`skinny_mj.registry` finds them.
REGISTRY = {
    "paper-a": "experiments.paper_a",
    "paper-b": "experiments.paper_b",
    "paper-c": "experiments.paper_c",
    "paper-d": "experiments.paper_d",
    "paper-e": "experiments.paper_e",
    "paper-e-explain": "experiments.paper_e_explain",
    "generalization": "experiments.generalization",
    "ridge-vs-new": "experiments.ridge_vs_new",
    "figure-eight": "experiments.figure_eight",
    "mackey-glass": "experiments.mackey_glass",
    "adaptation": "experiments.adaptation",
    "fidelity-e": "experiments.fidelity_e",
    "fidelity-a": "experiments.fidelity_a",
    "bimanual-delay": "experiments.bimanual_delay",
    "fidelity-d": "experiments.fidelity_d",
    "dynamic": "experiments.dynamic",
    "three-d": "experiments.three_d",
    "rl-vs-fel": "experiments.rl_vs_fel",
}


def get(name: str) -> ModuleType:
    """The experiment registered as ``name`` (:func:`skinny_mj.registry.get`)."""
    return registry.get(name)


def describe(name: str) -> str:
    """First docstring line of an experiment (:func:`skinny_mj.registry.describe`)."""
    return registry.describe(name)
