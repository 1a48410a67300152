"""No GLFW noise without a display: the rendering backend dm_control picks by itself.

With ``MUJOCO_GL`` unset, dm_control tries GLFW, then EGL, then OSMesa, taking the first
whose import succeeds. Without a display GLFW cannot work, but its ``glfw.init()`` only
*warns* ("X11: The DISPLAY environment variable is missing") instead of failing, so
dm_control keeps GLFW and prints that warning on the first ``skinny_mj.load``. When no
display is set and the user chose no backend, :func:`install` makes ``glfw`` (when it is
first imported) raise its errors instead: GLFW's init fails quietly and dm_control falls
through to EGL or OSMesa (or to no renderer) exactly as its own order says. A backend the
user chose (``MUJOCO_GL``) is never changed.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import os
import sys
from types import ModuleType


def _no_display() -> bool:
    return sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class _RaisingGlfw(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Imports ``glfw`` with its real loader, then sets ``ERROR_REPORTING = "raise"``."""

    def __init__(self) -> None:
        self._loader: importlib.abc.Loader | None = None

    def find_spec(self, name, path=None, target=None):  # noqa: ANN001 (importlib's API)
        if name != "glfw":
            return None
        sys.meta_path.remove(self)  # once: the real finders locate the package
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None:
            return spec
        self._loader, spec.loader = spec.loader, self
        return spec

    def create_module(self, spec):  # noqa: ANN001
        return self._loader.create_module(spec)

    def exec_module(self, module: ModuleType) -> None:
        self._loader.exec_module(module)
        module.ERROR_REPORTING = "raise"


def install() -> None:
    """Quiet GLFW's failure when there is no display and ``MUJOCO_GL`` is unset."""
    if "MUJOCO_GL" in os.environ or not _no_display():
        return
    if "glfw" in sys.modules:  # imported before us: its errors now raise too
        sys.modules["glfw"].ERROR_REPORTING = "raise"
    elif not any(isinstance(f, _RaisingGlfw) for f in sys.meta_path):
        sys.meta_path.insert(0, _RaisingGlfw())
