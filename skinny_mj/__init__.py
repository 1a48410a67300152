"""Skinny-MJ: a MuJoCo two-arm torso ("Skinny") as a dm_control task, the movements
it imitates, and the glue that lets echo state networks learn to control it.

Heavy imports (mujoco, dm_control, rerun) happen on first use, so that
``skinny_mj.plant.body`` and ``skinny_mj.trajectories`` stay importable without them.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_LAZY = {
    "load": ("skinny_mj.plant.task", "load"),
    "Trajectory": ("skinny_mj.trajectories", "Trajectory"),
    "SkinnyInputError": ("skinny_mj.errors", "SkinnyInputError"),
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'skinny_mj' has no attribute {name!r}")


__all__ = sorted(_LAZY)
