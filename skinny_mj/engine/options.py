"""What every experiment's ``build`` does with ``skinny experiment``'s options, once.

``--movement --asf --dof --signals`` become config changes (:func:`movement_changes`),
and a sweep's frozen config is read back from its ``config.json``
(:func:`config_from_dict`).
"""

from __future__ import annotations

import dataclasses
from typing import Any

#: ``skinny experiment``'s options that change a study's runs, and the TrainConfig keys
#: each sets (a :class:`skinny_mj.engine.study.Study`'s base takes them as overrides).
OPTION_KEYS = {"movement": ("movement.trajectory", "movement.asf"), "dof": ("plant.dof",),
               "signals": ("plant.signals",)}
#: The same, as the fields of the config classes of studies in the older module form.
FIELD_KEYS = {"movement": ("trajectory", "asf"), "dof": ("dof",), "signals": ("signals",)}


def movement_changes(movement: str | None, asf: Any, dof: int | None, signals: str | None,
                     keys: dict[str, tuple[str, ...]] = FIELD_KEYS) -> dict[str, Any]:
    """The config keys to set (``keys``: option -> keys): only the options given (None:
    the paper's), and ``asf`` with a movement only, as a string (it is recorded in
    ``config.json``)."""
    changes: dict[str, Any] = {}
    if movement is not None:
        key, asf_key = keys["movement"]
        changes.update({key: movement, asf_key: None if asf is None else str(asf)})
    for option, value in (("dof", dof), ("signals", signals)):
        if value is not None:
            changes[keys[option][0]] = value
    return changes


def config_from_dict(cls: type, d: dict[str, Any]) -> Any:
    """The frozen dataclass ``cls`` from ``config.json``'s ``config``: keys it does not
    have are ignored, JSON lists become tuples again."""
    names = {f.name for f in dataclasses.fields(cls)}
    return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()
                  if k in names})
