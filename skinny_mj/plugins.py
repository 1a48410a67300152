"""What other packages add through entry points: read once per process, each entry
checked to be of the kind its group holds."""

from __future__ import annotations

import functools
from importlib.metadata import entry_points
from typing import Any

from skinny_mj.errors import SkinnyInputError


@functools.cache
def load_group(group: str, kind: type, kind_name: str) -> tuple[tuple[str, Any], ...]:
    """(name, object) of every entry point of ``group``, loaded once per process; an entry
    that is not a ``kind`` is a :class:`SkinnyInputError` naming it and what it should be
    (``kind_name``), on every call."""
    found = []
    for ep in entry_points(group=group):
        obj = ep.load()
        if not isinstance(obj, kind):
            raise SkinnyInputError(f"entry point {ep.name!r} of {group} ({ep.value}) is not "
                                   f"a {kind_name}")
        found.append((ep.name, obj))
    return tuple(found)
