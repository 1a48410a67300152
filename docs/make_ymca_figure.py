"""Render the four YMCA key poses of the synthesized movement into docs/ymca_<dof>d.png.

Run: MUJOCO_GL=egl python docs/make_ymca_figure.py
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

from skinny_mj.plant.render import render_png  # noqa: E402
from skinny_mj.trajectories import get, letter_end_steps  # noqa: E402

HERE = Path(__file__).resolve().parent


def main() -> None:
    for dof in (4, 8):
        traj = get("ymca", dof)
        fig, axes = plt.subplots(1, 4, figsize=(12, 3.4))
        with tempfile.TemporaryDirectory() as tmp:
            for ax, letter in zip(axes, "YMCA", strict=True):
                step = letter_end_steps()[letter]
                png = render_png(dof, Path(tmp) / f"{letter}.png", 320, 240,
                                 angles=traj.angles[step])
                ax.imshow(mpimg.imread(png)[20:200, 60:260])
                ax.set_title(f"{letter} (step {step})")
                ax.axis("off")
        fig.suptitle(f"synthesized YMCA, {'2D' if dof == 4 else '3D'} ({dof} DOF)")
        fig.tight_layout()
        fig.savefig(HERE / f"ymca_{'2d' if dof == 4 else '3d'}.png", dpi=80)
        plt.close(fig)


if __name__ == "__main__":
    main()
