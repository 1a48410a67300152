"""The studies ``skinny experiment NAME`` can run.

This project's own are the modules of the ``experiments`` package that set a top-level
``NAME = "..."``: found by reading their source (so listing them imports none), loaded
by name. Another package adds its own through the entry-point group
``skinny_mj.experiments`` in its pyproject::

    [project.entry-points."skinny_mj.experiments"]
    my-sweep = "my_package.my_sweep:STUDY"    # a skinny_mj.engine.study.Study
    my-other = "my_package.my_other"          # a module (its STUDY, or the contract below)

An entry is a :class:`~skinny_mj.engine.study.Study` (a module's ``STUDY``), or a module of the
contract of :mod:`skinny_mj.engine.experiment` (``NAME``, ``build(*, quick, movement, asf, dof,
signals) -> Experiment``, ``report(results, out_dir) -> str``). Every registered study
passes ``tests/test_studies.py`` (it builds, plans its ``--quick`` rows, runs one tiny run
and writes its table). The project's own names win over an entry point of the same name.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
from importlib.metadata import entry_points
from pathlib import Path
from types import ModuleType
from typing import Any

from skinny_mj.errors import SkinnyInputError

GROUP = "skinny_mj.experiments"
PACKAGE = "skinny_mj.experiments"


def declared_name(path: Path) -> str | None:
    """The string a module's top-level ``NAME = "..."`` sets, None without one."""
    try:
        tree = ast.parse(path.read_text(encoding="utf-8"))
    except (OSError, SyntaxError, ValueError):
        return None
    for stmt in tree.body:
        if (isinstance(stmt, ast.Assign) and len(stmt.targets) == 1
                and isinstance(stmt.targets[0], ast.Name) and stmt.targets[0].id == "NAME"
                and isinstance(stmt.value, ast.Constant) and isinstance(stmt.value.value, str)):
            return stmt.value.value
    return None


def _package_studies() -> dict[str, str]:
    """name -> module of the package's studies (none imported): a module
    ``experiments/<name>.py``, or ``experiments/<folder>/study.py`` for a study kept in one
    folder with its report."""
    spec = importlib.util.find_spec(PACKAGE)
    if spec is None or not spec.submodule_search_locations:
        return {}
    found = {}
    for folder in spec.submodule_search_locations:
        for path in sorted([*Path(folder).glob("*.py"), *Path(folder).glob("*/study.py")]):
            if path.name.startswith("_") or not (name := declared_name(path)):
                continue
            rel = path.relative_to(folder).with_suffix("")
            found[name] = ".".join((PACKAGE, *rel.parts))
    return found


def _entries() -> dict[str, str]:
    """name -> entry-point value ("module" or "module:attr"), the package's last."""
    return {**{ep.name: ep.value for ep in entry_points(group=GROUP)}, **_package_studies()}


def names() -> list[str]:
    """Every registered study name, sorted."""
    return sorted(_entries())


def _load(value: str) -> Any:
    module_name, _, attr = value.partition(":")
    obj: Any = importlib.import_module(module_name.strip())
    for part in filter(None, attr.strip().split(".")):
        obj = getattr(obj, part)
    return getattr(obj, "STUDY", obj) if isinstance(obj, ModuleType) else obj


def get(name: str) -> Any:
    """The study registered as ``name``: a :class:`~skinny_mj.engine.study.Study`, or a module
    of the older contract; an unknown name is a :class:`SkinnyInputError` listing the
    known ones."""
    from skinny_mj.engine.study import Study

    found = _entries()
    if name not in found:
        known = ", ".join(sorted(found)) or f"none (is the package installed? group {GROUP})"
        raise SkinnyInputError(f"unknown experiment {name!r}; known: {known}")
    study = _load(found[name])
    if not isinstance(study, Study | ModuleType):
        raise SkinnyInputError(f"experiment {name!r} ({found[name]}) is neither a Study "
                               "nor a module")
    return study


def doc(name: str) -> str:
    """The study's whole description (a module's docstring)."""
    study = get(name)
    return (study.description if not isinstance(study, ModuleType) else study.__doc__) or ""


def describe(name: str) -> str:
    """The first paragraph of the study's description, whole, on one line ("" if none)."""
    return " ".join(doc(name).strip().split("\n\n")[0].split())
