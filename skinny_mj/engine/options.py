"""What a study does with ``skinny experiment``'s options, once.

``--movement --asf --body --signals`` become config changes of the study's base
(:func:`movement_changes`), unless the study takes one as a change of its rows or params
(:attr:`skinny_mj.engine.study.Study.own_options`).
"""

from __future__ import annotations

from typing import Any

from skinny_mj.training.config import DOF_KEY

#: ``skinny experiment``'s options that change a study's runs, and the TrainConfig keys
#: each sets (a :class:`skinny_mj.engine.study.Study`'s base takes them as overrides).
OPTION_KEYS = {"movement": ("movement.trajectory", "movement.asf"), "body": ("plant.body",),
               "signals": ("plant.signals",)}


def movement_changes(movement: str | None, asf: Any, body: str | int | None,
                     signals: str | None) -> dict[str, Any]:
    """The config keys to set (:data:`OPTION_KEYS`): only the options given (None: the
    study's), and ``asf`` with a movement only, as a string (it is recorded in
    ``config.json``). A ``body`` given as a number of hinges (``--dof 4|8``) sets
    ``plant.dof``: Skinny's body of that many for the study's actuation."""
    changes: dict[str, Any] = {}
    if movement is not None:
        key, asf_key = OPTION_KEYS["movement"]
        changes.update({key: movement, asf_key: None if asf is None else str(asf)})
    if isinstance(body, int):
        changes[DOF_KEY] = body
    elif body is not None:
        changes[OPTION_KEYS["body"][0]] = body
    if signals is not None:
        changes[OPTION_KEYS["signals"][0]] = signals
    return changes
