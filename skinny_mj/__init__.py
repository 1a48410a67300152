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
    "Trajectory": ("skinny_mj.trajectories", "Trajectory"),
    "SkinnyInputError": ("skinny_mj.errors", "SkinnyInputError"),
}


def load(dof: int = 4, signals: str = "cartesian", trajectory: Any = None, *args: Any,
         **kwargs: Any) -> Any:
    """Skinny imitating ``trajectory`` (None: the synthesized YMCA), as a dm_control
    ``control.Environment``: :func:`skinny_mj.plant.task.load`, whose other arguments
    (``actuation``, ``sensor_noise``, ``seed``, ``max_speed_rad_s``, ``speed_factor``)
    it passes on. The plant has no movement of its own; this package supplies the default.
    """
    from skinny_mj import trajectories  # here, not above: importing skinny_mj stays light
    from skinny_mj.plant import task

    if trajectory is None:
        trajectory = trajectories.get("ymca", dof)
    return task.load(dof, signals, trajectory, *args, **kwargs)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'skinny_mj' has no attribute {name!r}")


__all__ = sorted([*_LAZY, "load"])
