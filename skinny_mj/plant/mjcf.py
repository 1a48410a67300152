"""Reading a body's MJCF with errors a user can act on: a malformed or edited file is a
:class:`~skinny_mj.errors.SkinnyInputError` naming the file and line, in one line.

MuJoCo reports an error inside an ``<include>``d file at the including element
("Element 'include', line 3", or line 0), without the file's name. On a failure, the
files are read again one by one, the includes first: the first one that fails on its
own (as XML, or as MJCF) is the one named.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import mujoco

from skinny_mj.errors import SkinnyInputError

_LINE = re.compile(r"line(?: number)?[ =](\d+)", re.IGNORECASE)


def read_model(path: Path) -> mujoco.MjModel:
    """``mujoco.MjModel.from_xml_path(path)``; a bad file is a :class:`SkinnyInputError`."""
    return _guarded(path, lambda: mujoco.MjModel.from_xml_path(str(path)))


def read_spec(path: Path) -> mujoco.MjSpec:
    """``mujoco.MjSpec.from_file(path)``; a bad file is a :class:`SkinnyInputError`."""
    return _guarded(path, lambda: mujoco.MjSpec.from_file(str(path)))


def compile_spec(spec: mujoco.MjSpec, path: Path) -> mujoco.MjModel:
    """``spec.compile()`` for a spec read from ``path``; an error is a
    :class:`SkinnyInputError` naming the file it comes from."""
    return _guarded(path, spec.compile)


def _guarded(path: Path, read: Callable):
    try:
        return read()
    except ValueError as err:
        raise mjcf_error(Path(path), err) from None


def mjcf_error(path: Path, err: BaseException) -> SkinnyInputError:
    """The one-line error for MuJoCo's ``err`` on reading ``path``: the innermost file
    that fails on its own, with its line where one is known."""
    files, parents = _files(path)
    for f in files:  # well-formed XML first: ElementTree knows the line of any file
        try:
            ET.parse(f)
        except ET.ParseError as bad:
            line, column = bad.position if bad.position else (None, None)
            what = re.sub(r":? line \d+, column \d+$", "", _squash(bad))
            if not f.read_bytes().strip():
                return SkinnyInputError("empty file, not an MJCF", path=f)
            return SkinnyInputError(f"not well-formed XML: {what} (column {column})",
                                    path=f, line=line)
        except OSError as bad:
            by = f" (included by {parents[f].name})" if f in parents else ""
            return SkinnyInputError(f"cannot read the file: {bad.strerror}{by}", path=f)
    for f in reversed(files[1:]):  # an included file that fails alone
        try:
            mujoco.MjSpec.from_file(str(f)).compile()
        except ValueError as alone:
            line = _line(alone)
            if line:
                return SkinnyInputError(f"MJCF error: {_text(alone)}", path=f, line=line)
    return SkinnyInputError(f"MJCF error: {_text(err)}", path=path, line=_line(err))


def _files(path: Path) -> tuple[list[Path], dict[Path, Path]]:
    """``path`` and the files it includes (MuJoCo resolves an include against the
    main file's folder), outermost first, and each included file's includer; what
    cannot be parsed is left unexpanded."""
    out, todo, parents = [], [Path(path)], {}
    while todo:
        f = todo.pop(0)
        if f in out:
            continue
        out.append(f)
        try:
            root = ET.parse(f).getroot()
        except (ET.ParseError, OSError):
            continue
        for inc in root.iter("include"):
            if inc.get("file"):
                child = Path(path).parent / inc.get("file")
                parents.setdefault(child, f)
                todo.append(child)
    return out, parents


def _line(err: BaseException) -> int | None:
    found = [int(n) for n in _LINE.findall(str(err))]
    return next((n for n in found if n > 0), None)


def _text(err: BaseException) -> str:
    """MuJoCo's message without its prefixes and the element's position."""
    lines = [ln.strip() for ln in str(err).splitlines() if ln.strip()]
    kept = [ln for ln in lines if not ln.startswith("Element ")]
    element = next((ln for ln in lines if ln.startswith("Element ")), "")
    text = " ".join(kept) or str(err)
    text = re.sub(r"^(XML Error: |Error: )", "", text)
    name = re.search(r"Element (name '[^']*'|'[^']*')", element)
    return _squash(text) + (f" (element {name.group(1)})" if name else "")


def _squash(err: object) -> str:
    return " ".join(str(err).split())
