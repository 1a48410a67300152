"""One run: its configuration, its parts, the training loop, the torque
additions and the imitation metrics.

``from skinny_mj.training import train`` (any public name of :mod:`skinny_mj.training.loop`)
works: the name is looked up there on first use, so importing ``skinny_mj.training.config``
does not load the training loop.
"""

from __future__ import annotations

import importlib
from typing import Any


def __getattr__(name: str) -> Any:
    if name.startswith("_"):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    try:  # a submodule first (from skinny_mj.training import config: no loop import)
        return importlib.import_module(f"{__name__}.{name}")
    except ModuleNotFoundError as err:
        if err.name != f"{__name__}.{name}":
            raise
    return getattr(importlib.import_module(f"{__name__}.loop"), name)
