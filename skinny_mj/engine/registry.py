"""The studies ``skinny experiment NAME`` can run.

This project's own are the modules of the ``experiments`` package that set a top-level
``NAME = "..."`` and a ``STUDY``: found by reading their source, loaded by name. Their
descriptions are read off the source too (the module docstring, or the literal a ``STUDY =
Study(..., description=...)`` gives), so ``skinny experiment list`` imports none of them. Another
package adds its own through the entry-point group ``skinny_mj.experiments`` in its
pyproject::

    [project.entry-points."skinny_mj.experiments"]
    my-sweep = "my_package.my_sweep:STUDY"    # a skinny_mj.engine.study.Study
    my-other = "my_package.my_other"          # a module: its STUDY

An entry is a :class:`~skinny_mj.engine.study.Study`, or a module whose ``STUDY`` is one; anything
else is refused in one line when the study is asked for. Every registered study
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
from typing import TYPE_CHECKING, Any, NamedTuple

from skinny_mj.errors import SkinnyInputError

if TYPE_CHECKING:
    from skinny_mj.engine.study import Study

GROUP = "skinny_mj.experiments"
PACKAGE = "skinny_mj.experiments"


class Declared(NamedTuple):
    """What a study module's source declares: its ``NAME``, and its description when the
    source states it (None: only importing the module tells)."""

    name: str | None
    description: str | None


_DECLARED: dict[tuple[Path, int, int], Declared] = {}  # (path, mtime, size) -> its reading


def declared(path: Path) -> Declared:
    """Read a study module's source, without importing it: the string of its top-level
    ``NAME = "..."`` (None without one) and its description: the literal of a top-level
    ``STUDY = Study(..., description=...)`` (``description=__doc__`` or no ``STUDY``: the
    module docstring); None when that argument is any other expression."""
    try:
        stat = path.stat()
        key = (path.resolve(), stat.st_mtime_ns, stat.st_size)
        if key in _DECLARED:
            return _DECLARED[key]
        tree = ast.parse(path.read_text(encoding="utf-8"))
    except (OSError, SyntaxError, ValueError):
        return Declared(None, None)
    name, description = None, ast.get_docstring(tree, clean=False)
    for stmt in tree.body:
        if isinstance(stmt, ast.Assign) and len(stmt.targets) == 1:
            target, value = stmt.targets[0], stmt.value
        elif isinstance(stmt, ast.AnnAssign) and stmt.value is not None:
            target, value = stmt.target, stmt.value
        elif isinstance(stmt, ast.Import | ast.ImportFrom) \
                and "STUDY" in (a.asname or a.name for a in stmt.names):
            description = None  # a STUDY made elsewhere: importing it tells
            continue
        else:
            continue
        if not isinstance(target, ast.Name):
            continue
        if target.id == "NAME" and isinstance(value, ast.Constant) \
                and isinstance(value.value, str):
            name = value.value
        elif target.id == "STUDY":
            description = _study_description(value, description)
    _DECLARED[key] = Declared(name, description)
    return _DECLARED[key]


def _study_description(call: ast.expr, docstring: str | None) -> str | None:
    """The ``description=`` of a ``Study(...)`` call, or of a ``dataclasses.replace(...)``
    deriving one study from another, read as source (see :func:`declared`)."""
    func = call.func if isinstance(call, ast.Call) else None
    if getattr(func, "id", getattr(func, "attr", None)) not in ("Study", "replace"):
        return None
    for kw in call.keywords:
        if kw.arg == "description":
            if isinstance(kw.value, ast.Name) and kw.value.id == "__doc__":
                return docstring
            if isinstance(kw.value, ast.Constant) and isinstance(kw.value.value, str):
                return kw.value.value
            return None
    return None  # the Study's default: importing it tells


def declared_name(path: Path) -> str | None:
    """The string a module's top-level ``NAME = "..."`` sets, None without one."""
    return declared(path).name


def _package_sources() -> dict[str, tuple[str, Path]]:
    """name -> (module, source file) of the package's studies (none imported): a module
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
            found[name] = (".".join((PACKAGE, *rel.parts)), path)
    return found


def source_path(name: str) -> Path | None:
    """The source file of the package's own study ``name`` (None: not one of them)."""
    found = _package_sources().get(name)
    return None if found is None else found[1]


def _package_studies() -> dict[str, str]:
    """name -> module of the package's studies (none imported)."""
    return {name: module for name, (module, _) in _package_sources().items()}


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


def get(name: str) -> Study:
    """The :class:`~skinny_mj.engine.study.Study` registered as ``name``; an unknown name is a
    :class:`SkinnyInputError` listing the known ones."""
    from skinny_mj.engine.study import Study

    found = _package_studies()
    if name not in found:  # the package's own names win: no scan of the entry points
        found = _entries()
    if name not in found:
        known = ", ".join(sorted(found)) or f"none (is the package installed? group {GROUP})"
        raise SkinnyInputError(f"unknown experiment {name!r}; known: {known}")
    study = _load(found[name])
    if not isinstance(study, Study):
        raise SkinnyInputError(f"experiment {name!r} ({found[name]}) is not a Study (a "
                               "module's STUDY = skinny_mj.engine.study.Study(...))")
    return study


def doc(name: str) -> str:
    """The study's whole description, read off the source of the package's own studies
    (:func:`declared`), imported otherwise."""
    path = source_path(name)
    if path is not None and (text := declared(path).description) is not None:
        return text
    return get(name).description or ""


def describe(name: str) -> str:
    """The first paragraph of the study's description, whole, on one line ("" if none)."""
    return " ".join(doc(name).strip().split("\n\n")[0].split())
