"""Atomic file writes: results, recordings and caches appear whole or not at all."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from skinny_mj.controllers._io import atomic_path as _atomic_path

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
