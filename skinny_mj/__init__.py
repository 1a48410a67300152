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


def load(*args: Any, **kwargs: Any) -> Any:
    """Skinny imitating ``trajectory`` as a dm_control ``control.Environment``:
    :func:`skinny_mj.plant.task.load`, its arguments (``body``, ``signals``,
    ``trajectory``, ``sensor_noise``, ``seed``, ``max_speed_rad_s``, ``speed_factor``)
    given the same way. ``trajectory``: None (the synthesized YMCA), any movement name or
    file the command line's ``--trajectory`` takes (``"ym"``, ``"ymca@0.5"``,
    ``"babble:seed=3"``, ``"set:ymca+md_03.amc"``, ``"clip.csv@start=2"``), (T, n_dof)
    angles in rad or a :class:`~skinny_mj.trajectories.Trajectory`
    (:func:`skinny_mj.trajectories.resolve_trajectory`). The plant has no movement of its
    own; this package supplies the default and reads the names.
    """
    from skinny_mj import trajectories  # here, not above: importing skinny_mj stays light
    from skinny_mj.plant import task

    given = task.arguments(*args, **kwargs)
    given["trajectory"] = trajectories.resolve_trajectory(given["trajectory"], given["body"])
    return task.load(**given)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'skinny_mj' has no attribute {name!r}")


__all__ = sorted([*_LAZY, "load"])
