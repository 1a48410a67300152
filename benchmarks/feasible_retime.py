"""The shipped clips made feasible for the torque twin: uniformly slowed vs re-timed locally.

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/feasible_retime.py

Per clip and body, a markdown table (``docs/results/dynamic.md``): the clip's duration as
shipped, uniformly slowed to the fastest feasible speed
(:func:`skinny_mj.training.feasible.fastest_uniform_speed`: within the limits, the
study's ``FEASIBLE_SPEED``; and within 0.9 of them, the re-timing's margin), and
re-timed locally (:func:`skinny_mj.training.feasible.retime_movement`, 0.9 of the
limits), in seconds; the share of the re-timed clip's steps played at the shipped speed;
the peak held step torque over its limit of each version; and the share of the needed
torque that is gravity (:func:`skinny_mj.plant.path_dynamics.gravity_share`) of the
uniformly slowed and the re-timed clip. About 15 s of CPU.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "disabled")

from skinny_mj.training import feasible  # noqa: E402
from skinny_mj.trajectories import load_movement  # noqa: E402

CLIPS = ("md_02.amc", "md_03.amc")
BODIES = {4: "2D", 8: "3D"}


def main() -> None:
    margin = feasible.TORQUE_MARGIN
    print(f"| clip, body | shipped (s) | uniform ≤ 1.0 (s) | uniform ≤ {margin:g} (s) | "
          f"re-timed ≤ {margin:g} (s) | re-timed at full speed | peak \\|τ\\|/limit: shipped "
          "/ uniform ≤ 1.0 / re-timed | gravity share: uniform ≤ 1.0 / re-timed |")
    print("|---|---|---|---|---|---|---|---|")
    for dof, name in BODIES.items():
        for clip in CLIPS:
            traj = load_movement(clip, dof)[0]
            speed = feasible.fastest_uniform_speed(traj, dof)
            speed_m = feasible.fastest_uniform_speed(traj, dof, limit_ratio=margin)
            uniform = traj.resample(speed)
            re = feasible.retime_movement(traj, dof, margin)
            peaks = [feasible.peak_torque_ratio(t, dof) for t in (traj, uniform)]
            print(f"| {clip.removesuffix('.amc')}, {name} | {traj.duration_s:.2f} | "
                  f"{uniform.duration_s:.2f} (× {speed:g}) | "
                  f"{traj.resample(speed_m).duration_s:.2f} (× {speed_m:g}) | "
                  f"{re.trajectory.duration_s:.2f} | {100 * re.full_speed_share():.0f} % | "
                  f"{peaks[0]:.2f} / {peaks[1]:.2f} / {re.peak_torque_ratio:.2f} | "
                  f"{100 * feasible.gravity_share_of(uniform, dof):.0f} % / "
                  f"{100 * feasible.gravity_share_of(re.trajectory, dof):.0f} % |", flush=True)


if __name__ == "__main__":
    main()
