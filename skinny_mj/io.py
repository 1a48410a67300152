"""Atomic file writes: results, recordings and caches appear whole or not at all; and a
page's computed section (between two marker lines) rewritten in place."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from skinny_mj.controllers._io import atomic_path as _atomic_path
from skinny_mj.errors import SkinnyInputError

# One implementation for the whole project: controllers/ may not import skinny_mj,
# so the context manager lives there and is re-exported here.
atomic_path = _atomic_path


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def atomic_write_text(path: str | Path, text: str) -> Path:
    return atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(
    path: str | Path, obj: Any, *, default: Callable[[Any], Any] | None = None
) -> Path:
    """Write ``obj`` as indented JSON (NaN is refused: a result is a number or absent)."""
    text = json.dumps(obj, indent=2, sort_keys=False, allow_nan=False, default=default)
    return atomic_write_text(path, text + "\n")


def _section_span(page: str, begin: str, end: str) -> tuple[int, int] | None:
    """Where the section from ``begin`` to the end of ``end`` lies in ``page``, or None."""
    start, stop = page.find(begin), page.find(end)
    return None if start < 0 or stop < start else (start, stop + len(end))


def page_section(page: str, begin: str, end: str) -> str | None:
    """The section of ``page`` from the line ``begin`` to the line ``end`` (markers and
    the final newline included); None when the page lacks either marker."""
    span = _section_span(page, begin, end)
    return None if span is None else page[span[0]:span[1]] + "\n"


def read_page_with_section(path: str | Path, begin: str, end: str) -> str:
    """The page at ``path``, refused (:class:`SkinnyInputError`, one line) when it cannot
    be read or lacks the section (:func:`page_section`) a command is to rewrite."""
    try:
        page = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise SkinnyInputError(f"cannot read the page ({exc.strerror})", path=path) from None
    if _section_span(page, begin, end) is None:
        raise SkinnyInputError(f"no computed section: put the lines {begin} and {end} where "
                               "the table goes", path=path)
    return page


def write_page_section(path: str | Path, begin: str, end: str, section: str) -> Path:
    """Replace the section (:func:`page_section`) of the page at ``path`` with ``section``
    (markers included); the rest of the page is kept byte for byte."""
    page = read_page_with_section(path, begin, end)
    start, stop = _section_span(page, begin, end)
    rest = page[stop + 1:] if page[stop:stop + 1] == "\n" else page[stop:]
    return atomic_write_text(path, page[:start] + section + rest)
