"""Offscreen pictures of Skinny from the ``front`` camera (used by ``skinny render``).

Rendering needs an OpenGL backend chosen before mujoco is imported: this module sets
``MUJOCO_GL=egl`` unless the caller chose one. Run it in a fresh process
(``python -m skinny_mj.plant.render --body 2d --out skinny_2d.png``) if mujoco may already be
imported with ``MUJOCO_GL=disabled`` (as in the test suite).
"""

from __future__ import annotations

import argparse
import os
import warnings
from pathlib import Path

import numpy as np

from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.io import atomic_path
from skinny_mj.plant.body import BodyLike, body_of
from skinny_mj.preflight import GL_OFF

# A pose that shows every DOF: right arm raised and bent, left arm half raised.
#: A pose that shows every hinge, by Skinny's joint names (another body: the middle of
#: each range).
_SHOW_POSE = {
    ("shoulder_abduction", "elbow_flexion"): [2.3, 0.9, 1.2, 0.4],
    ("shoulder_abduction", "shoulder_flexion", "shoulder_rotation", "elbow_flexion"):
        [2.3, 0.3, 0.4, 0.9, 1.2, -0.3, -0.4, 0.4],
}


def check_rendering() -> None:
    """Refuse (:class:`SkinnyInputError`, one line) to render with ``MUJOCO_GL`` set to a
    value that turns rendering off, saying how to turn it on."""
    value = os.environ.get("MUJOCO_GL")
    if value is not None and value.strip().lower() in GL_OFF:
        raise SkinnyInputError(f"rendering is off (MUJOCO_GL={value}): run with "
                               "MUJOCO_GL=egl (GPU or Mesa EGL) or MUJOCO_GL=osmesa (software)")


def _no_backend(exc: Exception) -> SkinnyEnvironmentError:
    if "GLContext" in str(exc):  # mujoco was imported with rendering off, in this process
        return SkinnyEnvironmentError(
            "rendering is off in this process (mujoco was imported with MUJOCO_GL="
            "disabled): render in a new process with MUJOCO_GL=egl (or osmesa)")
    return SkinnyEnvironmentError(
        f"no OpenGL rendering backend (MUJOCO_GL={os.environ.get('MUJOCO_GL')!r}: "
        f"{type(exc).__name__}: {exc}); install EGL or OSMesa (Debian: libegl1, "
        "libosmesa6) and set MUJOCO_GL=egl or osmesa")


def render_png(
    which: BodyLike,
    path: str | Path,
    width: int = 640,
    height: int = 480,
    angles: np.ndarray | None = None,
) -> Path:
    """Render a body from the ``front`` camera to a PNG file.

    Parameters
    ----------
    which : the body (its name, :data:`skinny_mj.plant.body.BODIES`).
    path : output .png (written atomically).
    width, height : image size in pixels, at most 640 x 480 (the offscreen buffer).
    angles : (n_dof,) joint angles, rad; default a pose that shows every DOF.

    Returns
    -------
    The path written.
    """
    check_rendering()
    os.environ.setdefault("MUJOCO_GL", "egl")
    import matplotlib.image

    try:  # the GL backend is loaded at import: osmesa without libOSMesa fails here
        with warnings.catch_warnings():  # glfw warns without a display; the error says so
            warnings.simplefilter("ignore")
            import mujoco
    except Exception as exc:
        raise _no_backend(exc) from None

    from skinny_mj.plant.model import load_model
    from skinny_mj.plant.physics import Layout

    if not (0 < width <= 640 and 0 < height <= 480):
        raise SkinnyInputError(f"image size must be within 640 x 480, got {width} x {height}")
    skinny = body_of(which)
    model = load_model(skinny)
    data = mujoco.MjData(model)
    if angles is None:
        angles = _SHOW_POSE.get(skinny.arms.joints, skinny.joint_ranges().mean(axis=1))
    q = np.asarray(angles, dtype=float)
    if q.shape != (skinny.dof,) or not np.all(np.isfinite(q)):
        raise SkinnyInputError(f"angles must be {skinny.dof} finite numbers (rad), got "
                               f"{q.shape}")
    Layout(model, skinny).set_joint_angles(data, q)
    mujoco.mj_forward(model, data)
    try:
        with warnings.catch_warnings():  # glfw warns per failed call; the error says it all
            warnings.simplefilter("ignore")
            renderer = mujoco.Renderer(model, height=height, width=width)
    except Exception as exc:  # each backend fails its own way (FatalError, AttributeError..)
        raise _no_backend(exc) from None
    try:
        renderer.update_scene(data, camera="front")
        pixels = renderer.render()
    finally:
        renderer.close()
    path = Path(path)
    with atomic_path(path) as tmp:
        matplotlib.image.imsave(tmp, pixels, format="png")
    return path


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="Render Skinny from the front camera.")
    parser.add_argument("--body", default="2d", help="the body (default 2d)")
    parser.add_argument("--out", type=Path, required=True, help="output .png")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    args = parser.parse_args(argv)
    print(render_png(args.body, args.out, args.width, args.height))


if __name__ == "__main__":
    main()
