"""Sealed layers and what the package ships.

controllers/ (the learning) never imports the plant, the package ``skinny_mj`` never
imports ``experiments`` (it finds them through the ``skinny_mj.experiments`` entry
points), no module reads another module's private attributes, and the wheel carries
every package folder, the MJCF and the CMU sample clips.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LAYERS = ("skinny_mj", "controllers", "experiments")
# Private names that are public API despite the underscore (namedtuple's).
PUBLIC_UNDERSCORE = {"_replace", "_fields", "_asdict", "_make", "_field_defaults"}
# Cross-module private reads allowed (none: each got a public accessor).
KNOWN_PRIVATE_READS: set[str] = set()


def _imported_in_subprocess(code: str, tmp_path: Path) -> set[str]:
    """Top-level names in ``sys.modules`` after running ``code`` in a fresh interpreter
    (started outside the repo, so the installed package is what it imports)."""
    env = {**os.environ, "MUJOCO_GL": "disabled"}
    script = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))\n"
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return {name.split(".")[0] for name in json.loads(done.stdout.splitlines()[-1])}


def test_controllers_import_no_plant_package_or_experiment(tmp_path):
    modules = ["controllers", "controllers.esn", "controllers.fel", "controllers.feedback",
               "controllers.forward_model", "controllers.true_target", "controllers.plant"]
    code = ("import importlib, pkgutil, controllers\n"
            f"names = {modules!r}\n"
            "names += [m.name for m in pkgutil.walk_packages(controllers.__path__, "
            "'controllers.')]\n"
            "for name in names:\n    importlib.import_module(name)\n")
    loaded = _imported_in_subprocess(code, tmp_path)
    assert "controllers" in loaded
    assert not loaded & {"mujoco", "dm_control", "skinny_mj", "experiments"}


def test_no_skinny_mj_module_imports_experiments(tmp_path):
    """Every module of the package (walked with pkgutil, none skipped, plus the mapped
    skinny_mj.models), and listing the registry, leave ``experiments`` unimported."""
    code = ("import importlib, pkgutil, skinny_mj\n"
            "def fail(name):\n    raise ImportError(name)\n"
            "names = [m.name for m in pkgutil.walk_packages(skinny_mj.__path__, 'skinny_mj.',"
            " onerror=fail)] + ['skinny_mj.models']\n"
            "assert len(names) > 20, names\n"
            "for name in names:\n    importlib.import_module(name)\n"
            "from skinny_mj import registry\n"
            "assert 'paper-e' in registry.names()\n")
    loaded = _imported_in_subprocess(code, tmp_path)
    assert "skinny_mj" in loaded and "experiments" not in loaded


def _private(name: str) -> bool:
    dunder = name.startswith("__") and name.endswith("__")
    return name.startswith("_") and not dunder and name not in PUBLIC_UNDERSCORE


def _own_private_names(tree: ast.Module) -> set[str]:
    """Private names a module defines itself: functions, classes and methods, attributes
    its code sets on ``self``/``cls``, and names assigned at module or class level."""
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)
            body = node.body if isinstance(node, ast.ClassDef) else []
        elif isinstance(node, ast.Module):
            body = node.body
        else:
            body = []
        for stmt in body:
            targets = stmt.targets if isinstance(stmt, ast.Assign) else (
                [stmt.target] if isinstance(stmt, ast.AnnAssign) else [])
            names |= {t.id for t in targets if isinstance(t, ast.Name)}
        if (isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store)
                and isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")):
            names.add(node.attr)
    return names


def private_reads(root: Path = ROOT) -> set[str]:
    """``path: expression`` of every use of another module's private attribute in the
    layers: ``obj._name`` (obj not self/cls/super(), ``_name`` not defined in this module)
    and ``from a.project.module import _name``."""
    found: set[str] = set()
    for layer in LAYERS:
        for path in sorted((root / layer).rglob("*.py")):
            tree = ast.parse(path.read_text(), filename=str(path))
            own, where = _own_private_names(tree), path.relative_to(root).as_posix()
            for node in ast.walk(tree):
                if isinstance(node, ast.Attribute) and _private(node.attr):
                    value = node.value
                    if isinstance(value, ast.Name) and value.id in ("self", "cls"):
                        continue
                    if (isinstance(value, ast.Call) and isinstance(value.func, ast.Name)
                            and value.func.id == "super"):
                        continue
                    if node.attr not in own:
                        found.add(f"{where}: {ast.unparse(node)}")
                elif (isinstance(node, ast.ImportFrom) and node.module
                      and node.module.split(".")[0] in LAYERS):
                    found |= {f"{where}: from {node.module} import {alias.name}"
                              for alias in node.names if _private(alias.name)}
    return found


def test_the_private_read_scan_finds_what_it_should(tmp_path):
    (tmp_path / "skinny_mj").mkdir()
    (tmp_path / "skinny_mj" / "a.py").write_text(
        "from controllers.esn import _hidden\n"
        "class A:\n    _kind = 1\n    def __init__(self, esn):\n        self._mine = 1\n"
        "        esn._sparse\n        other = A(esn)\n        other._mine, other._kind\n"
        "        self._mine, super()._x, esn.cfg._replace(), esn.__dict__\n")
    assert private_reads(tmp_path) == {"skinny_mj/a.py: esn._sparse",
                                       "skinny_mj/a.py: from controllers.esn import _hidden"}


def test_no_new_private_reads_of_other_modules():
    """No cross-module private read beyond the known ones (listed for the lead)."""
    assert private_reads() <= KNOWN_PRIVATE_READS


def test_no_module_reads_another_modules_private_attributes():
    assert private_reads() == set()


# -- what the package ships -------------------------------------------------------------
def _setuptools() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]


def test_every_package_folder_is_listed_in_pyproject():
    """pyproject lists its packages (so ``models/`` can ship as skinny_mj.models): a new
    package folder must be added there, or a non-editable install leaves it out."""
    listed = set(_setuptools()["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for layer in LAYERS for p in (ROOT / layer).rglob("__init__.py")}
    assert found <= listed, f"add to [tool.setuptools] packages: {sorted(found - listed)}"


def test_models_and_sample_clips_are_package_data():
    import skinny_mj.model as model
    from skinny_mj.trajectories import SAMPLE_ASF, SAMPLE_CLIPS, load_movement, sample_clip

    assert _setuptools()["package-dir"]["skinny_mj.models"] == "models"
    if not os.environ.get(model.MODELS_ENV_VAR):
        assert (model.models_dir() / "scene_2d.xml").is_file()
    assert SAMPLE_ASF.is_file() and (SAMPLE_ASF.parent / "README.md").is_file()
    for name in SAMPLE_CLIPS:
        assert sample_clip(name) == sample_clip(f"{name}.amc") and sample_clip(name).is_file()
    traj, _ = load_movement(sample_clip("md_03"), 8)  # finds the .asf beside it
    assert len(traj) > 100
    with pytest.raises(ValueError, match="md_02"):
        sample_clip("md_99")


def test_studies_are_found_from_the_package():
    """Every module of ``experiments`` that sets NAME is a study (none is listed twice in
    pyproject); ``experiments.get`` is the registry's."""
    import experiments
    from skinny_mj import registry
    from skinny_mj.errors import SkinnyInputError

    modules = {p.stem for p in (ROOT / "experiments").glob("*.py")
               if registry.declared_name(p) is not None}
    assert len(modules) == len(registry.names()) and "paper_e" in modules
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"].get(
        "entry-points", {}).get(registry.GROUP, {})
    assert not set(declared) & set(registry.names())
    study = registry.get("paper-e")
    assert study is sys.modules["experiments.paper_e"].STUDY and experiments.get("paper-e") is study
    assert registry.describe("paper-e") == experiments.describe("paper-e") != ""
    with pytest.raises(SkinnyInputError, match="paper-a, paper-b"):
        registry.get("paper-z")
