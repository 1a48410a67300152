"""What every experiment's ``build`` does with ``skinny experiment``'s options, once.

``--movement --asf --dof --signals`` become config changes (:func:`movement_changes`),
and a sweep's frozen config is read back from its ``config.json``
(:func:`config_from_dict`).
"""

from __future__ import annotations

import dataclasses
from typing import Any


def movement_changes(movement: str | None, asf: str | None, dof: int | None,
                     signals: str | None) -> dict[str, Any]:
    """The config fields to replace: only the options given (None: the paper's), and
    ``asf`` with a movement only, as a string (it is recorded in ``config.json``)."""
    changes: dict[str, Any] = {k: v for k, v in (("trajectory", movement), ("dof", dof),
                                                 ("signals", signals)) if v is not None}
    if movement is not None:
        changes["asf"] = None if asf is None else str(asf)
    return changes


def config_from_dict(cls: type, d: dict[str, Any]) -> Any:
    """The frozen dataclass ``cls`` from ``config.json``'s ``config``: keys it does not
    have are ignored, JSON lists become tuples again."""
    names = {f.name for f in dataclasses.fields(cls)}
    return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()
                  if k in names})
