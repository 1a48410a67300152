"""Movements for Skinny to imitate: the :class:`Trajectory` value, the synthesized YMCA
and its derived movements (paper C), and motion capture (ASF/AMC, BVH) retargeted
onto Skinny's joints. NumPy/SciPy, no dm_control (a body's arms are read from its MJCF
with MuJoCo on first use).

>>> from skinny_mj.trajectories import get, load_movement
>>> traj = get("ymca", "2d")                        # 313 steps at 50 Hz
>>> traj, report = load_movement("clip.amc", "3d", asf="subject.asf")  # doctest: +SKIP
"""

from skinny_mj.trajectories.library import get, load_movement, names, resolve_trajectory
from skinny_mj.trajectories.retarget import ArmClip, RetargetReport, retarget
from skinny_mj.trajectories.samples import SAMPLE_ASF, SAMPLE_CLIPS, sample_clip
from skinny_mj.trajectories.trajectory import Trajectory, excerpt
from skinny_mj.trajectories.ymca import key_poses, letter_end_steps, ymca

__all__ = [
    "ArmClip",
    "RetargetReport",
    "SAMPLE_ASF",
    "SAMPLE_CLIPS",
    "Trajectory",
    "excerpt",
    "get",
    "key_poses",
    "letter_end_steps",
    "load_movement",
    "names",
    "resolve_trajectory",
    "retarget",
    "sample_clip",
    "ymca",
]
