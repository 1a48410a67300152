"""What a study does with ``skinny experiment``'s options, once.

``--movement --asf --dof --signals`` become config changes of the study's base
(:func:`movement_changes`), unless the study takes one as a change of its rows or params
(:attr:`skinny_mj.engine.study.Study.own_options`).
"""

from __future__ import annotations

from typing import Any

#: ``skinny experiment``'s options that change a study's runs, and the TrainConfig keys
#: each sets (a :class:`skinny_mj.engine.study.Study`'s base takes them as overrides).
OPTION_KEYS = {"movement": ("movement.trajectory", "movement.asf"), "dof": ("plant.dof",),
               "signals": ("plant.signals",)}


def movement_changes(movement: str | None, asf: Any, dof: int | None,
                     signals: str | None) -> dict[str, Any]:
    """The config keys to set (:data:`OPTION_KEYS`): only the options given (None: the
    study's), and ``asf`` with a movement only, as a string (it is recorded in
    ``config.json``)."""
    changes: dict[str, Any] = {}
    if movement is not None:
        key, asf_key = OPTION_KEYS["movement"]
        changes.update({key: movement, asf_key: None if asf is None else str(asf)})
    for option, value in (("dof", dof), ("signals", signals)):
        if value is not None:
            changes[OPTION_KEYS[option][0]] = value
    return changes
