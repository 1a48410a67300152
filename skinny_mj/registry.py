"""The experiments ``skinny experiment NAME`` can run, found through the entry-point group
``skinny_mj.experiments`` (NAME = "a.module"), so the package never imports them.

This project's own (``paper-a`` ... ``paper-e``) are declared in its pyproject; another
package adds one the same way in its own pyproject::

    [project.entry-points."skinny_mj.experiments"]
    my-sweep = "my_package.my_sweep"

The module follows the paper-module contract of :mod:`skinny_mj.experiment`: ``NAME``,
``build(*, quick, movement, asf, dof, signals) -> Experiment`` and ``report(results,
out_dir) -> str``.
"""

from __future__ import annotations

from importlib.metadata import EntryPoint, entry_points
from types import ModuleType

from skinny_mj.errors import SkinnyInputError

GROUP = "skinny_mj.experiments"


def _entry_points() -> dict[str, EntryPoint]:
    return {ep.name: ep for ep in entry_points(group=GROUP)}


def names() -> list[str]:
    """Every registered experiment name, sorted."""
    return sorted(_entry_points())


def get(name: str) -> ModuleType:
    """The module registered as ``name``; an unknown name is a :class:`SkinnyInputError`
    listing the known ones."""
    found = _entry_points()
    if name not in found:
        known = ", ".join(sorted(found)) or f"none (is the package installed? group {GROUP})"
        raise SkinnyInputError(f"unknown experiment {name!r}; known: {known}")
    module = found[name].load()
    if not isinstance(module, ModuleType):
        raise SkinnyInputError(f"experiment {name!r} ({found[name].value}) is not a module")
    return module


def describe(name: str) -> str:
    """The first paragraph of the experiment module's docstring, whole, on one line (""
    if it has none)."""
    doc = (get(name).__doc__ or "").strip()
    return " ".join(doc.split("\n\n")[0].split())
