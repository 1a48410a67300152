"""Without a display the Python API is quiet: dm_control skips GLFW (which can only fail
there) instead of printing GLFW's "DISPLAY missing" warning on the first load, and a
backend the user chose with ``MUJOCO_GL`` is left as it is."""

from __future__ import annotations

import json
import os
import subprocess
import sys

_PROBE = """
import json, os, skinny_mj
env = skinny_mj.load(body="2d")
env.reset(); env.step([0.0] * 4)
from dm_control import _render
print(json.dumps({"backend": _render.BACKEND, "gl": os.environ.get("MUJOCO_GL")}))
"""


def _run(**env_changes: str | None) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items()
           if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL")}
    env.update({k: v for k, v in env_changes.items() if v is not None})
    env["OMP_NUM_THREADS"] = "1"
    return subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                          env=env, timeout=120)


def test_no_display_no_choice_loads_without_glfw_noise():
    result = _run()
    assert result.returncode == 0, result.stderr[-2000:]
    assert "GLFW" not in result.stderr and "DISPLAY" not in result.stderr, result.stderr
    probe = json.loads(result.stdout.strip().splitlines()[-1])
    assert probe["backend"] != "glfw"  # EGL, OSMesa or none: whatever this machine has
    assert probe["gl"] is None  # the user's environment is not rewritten


def test_a_chosen_backend_is_kept():
    result = _run(MUJOCO_GL="disabled")
    assert result.returncode == 0, result.stderr[-2000:]
    probe = json.loads(result.stdout.strip().splitlines()[-1])
    assert probe == {"backend": "off", "gl": "disabled"}  # dm_control's name for it
