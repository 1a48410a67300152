"""Sealed layers and what the package ships.

controllers/ (the learning) never imports the plant, the package ``skinny_mj`` never
imports ``experiments`` (it finds them through the ``skinny_mj.experiments`` entry
points), the parts import only their own modules and the parts of lower :data:`LEVELS`
(read from every import statement, those inside functions and under ``if TYPE_CHECKING:``
included), no modules import each other in a circle of any length, no module reads
another module's private attributes, few imports of the project's modules sit inside
functions (:data:`MAX_FUNCTION_IMPORTS`), and the wheel carries every package folder, the
MJCF and the CMU sample clips.
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
LAYERS = ("skinny_mj", "controllers", "experiments")  # the folders read
# Private names that are public API despite the underscore (namedtuple's).
PUBLIC_UNDERSCORE = {"_replace", "_fields", "_asdict", "_make", "_field_defaults"}
# Cross-module private reads allowed (none: each got a public accessor).
KNOWN_PRIVATE_READS: set[str] = set()

# -- the parts, as module-name prefixes ---------------------------------------------------
# The learning and the studies keep their folders at the top of the repository and install
# under skinny_mj (pyproject's package-dir): controllers/esn.py is skinny_mj.controllers.esn.
MAPPED = {folder: name for name, folder in tomllib.loads((ROOT / "pyproject.toml").read_text())[
    "tool"]["setuptools"]["package-dir"].items()}
CONTROLLERS = ("skinny_mj.controllers",)
EXPERIMENTS = ("skinny_mj.experiments",)
# The bodies by name and their arms as numbers (joints, ranges, signals, kinematics; read
# from each body's MJCF through skinny_mj.mjcf, never importing MuJoCo themselves): what a
# movement is made for.
BODY = ("skinny_mj.plant.body", "skinny_mj.plant.kinematics")
# Its MuJoCo model, the dm_control task, the plant adapters, the analytic ideal
# controller, changes of the body, pictures.
PLANT = ("skinny_mj.plant",)
# The Gymnasium envs over the plant (a movement by name: YMCA by default).
GYM = ("skinny_mj.gym",)
# What Skinny imitates (pure NumPy/SciPy: no mujoco, no dm_control).
MOVEMENTS = ("skinny_mj.trajectories",)
# One run: its configuration (dotted overrides, earlier versions' flat configs, presets),
# its parts, the training path, the torque additions, the learning rules' registry, the
# toolbox's protocol options, the imitation metrics, DTW, its memory estimates.
TRAINING = ("skinny_mj.training",)
# Many runs: the experiment engine, its sweep helpers, the registry of studies, a sweep's
# memory estimate.
ENGINE = ("skinny_mj.engine",)
# The `skinny` command: parser, handlers, flags (the configuration's flags; a run repeated
# from its files with --config), help texts, bench, viewer, the commands' memory checks.
COMMAND_LINE = ("skinny_mj.cli",)
# Shared by every part: errors, other packages' entry points (plugins), io, threads,
# progress, preflight (its memory check too), plots, the MJCF and its reader.
SHARED = ("skinny_mj.errors", "skinny_mj.plugins", "skinny_mj.io", "skinny_mj.threads",
          "skinny_mj.progress", "skinny_mj.preflight", "skinny_mj.plots", "skinny_mj.models",
          "skinny_mj.mjcf")
# rerun recordings of the body and their blueprint.
RECORDING = ("skinny_mj.recording", "skinny_mj.recording_layout")
# The package itself (this module only, not its sub-modules): skinny_mj.load, with the
# synthesized YMCA as its default movement.
FACADE = "skinny_mj"
PARTS = {"controllers": CONTROLLERS, "experiments": EXPERIMENTS, "body": BODY, "plant": PLANT,
         "gym": GYM, "movements": MOVEMENTS, "training": TRAINING, "engine": ENGINE,
         "command line": COMMAND_LINE, "shared": SHARED, "recording": RECORDING}
PACKAGE_PARTS = ("body", "plant", "gym", "movements", "training", "engine", "command line",
                 "shared", "recording", "facade")
#: The layers, bottom first: a module imports its own part and the parts of lower levels,
#: never a part of its own level or a higher one.
LEVELS = (
    ("controllers",),
    ("shared",),
    ("body",),
    ("movements", "plant", "recording"),
    ("gym",),
    ("training",),
    ("engine",),
    ("command line",),
    ("experiments", "facade"),
)
LEVEL = {part: i for i, parts in enumerate(LEVELS) for part in parts}
HEAVY = ("mujoco", "dm_control", "rerun")
BARE = ("controllers", "experiments")  # the folders' names, never import names
# (parts, what they must not import, why), beside the levels: a part may always import
# itself.
RULES = (
    (("controllers",), ("skinny_mj", *BARE, *HEAVY),
     "the learning is pure NumPy/SciPy, testable without the plant"),
    (PACKAGE_PARTS, (*EXPERIMENTS, *BARE), "studies are found by the registry, and the "
     "learning is imported as skinny_mj.controllers"),
    (("experiments",), BARE, "the learning is imported as skinny_mj.controllers"),
    (("movements", "body"), (*CONTROLLERS, *HEAVY),
     "a movement is data, usable without a controller or a simulator"),
)


def _under(name: str, prefixes) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def part_of(module: str) -> str | None:
    """The part a module belongs to: its longest prefix among :data:`PARTS`."""
    if module == FACADE:
        return "facade"
    best = max(((len(p), part) for part, prefixes in PARTS.items() for p in prefixes
                if _under(module, (p,))), default=None)
    return best[1] if best else None


def _imported_in_subprocess(code: str, tmp_path: Path) -> set[str]:
    """The names in ``sys.modules`` after running ``code`` in a fresh interpreter (started
    outside the repo, so the installed package is what it imports)."""
    env = {**os.environ, "MUJOCO_GL": "disabled"}
    script = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))\n"
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stdout.splitlines()[-1]))


def test_controllers_import_no_plant_package_or_experiment(tmp_path):
    modules = ["skinny_mj.controllers", "skinny_mj.controllers.esn", "skinny_mj.controllers.fel",
               "skinny_mj.controllers.feedback", "skinny_mj.controllers.forward_model",
               "skinny_mj.controllers.true_target", "skinny_mj.controllers.plant"]
    code = ("import importlib, pkgutil, skinny_mj.controllers as c\n"
            f"names = {modules!r}\n"
            "names += [m.name for m in pkgutil.walk_packages(c.__path__, "
            "'skinny_mj.controllers.')]\n"
            "for name in names:\n    importlib.import_module(name)\n")
    loaded = _imported_in_subprocess(code, tmp_path)
    assert "skinny_mj.controllers.esn" in loaded
    ours = {n for n in loaded if _under(n, ("skinny_mj", *BARE))}
    assert ours - {"skinny_mj"} == {n for n in ours if _under(n, CONTROLLERS)}, (
        "the learning loads no other module of the package")
    assert not {n.split(".")[0] for n in loaded} & {"mujoco", "dm_control", "rerun", *BARE}


def test_no_skinny_mj_module_imports_experiments(tmp_path):
    """Every module of the package (walked with pkgutil, none skipped but a ``__main__``,
    which runs a program; plus the mapped skinny_mj.models), and listing the registry,
    leave the studies unimported."""
    code = ("import importlib, pkgutil, skinny_mj\n"
            "def fail(name):\n    raise ImportError(name)\n"
            "names = [m.name for m in pkgutil.walk_packages(skinny_mj.__path__, 'skinny_mj.',"
            " onerror=fail) if not m.name.endswith('.__main__')] + ['skinny_mj.models']\n"
            "assert len(names) > 20, names\n"
            "for name in names:\n    importlib.import_module(name)\n"
            "import skinny_mj.engine.registry as registry\n"
            "assert 'paper-e' in registry.names()\n")
    loaded = _imported_in_subprocess(code, tmp_path)
    assert "skinny_mj.engine.registry" in loaded
    assert not {n for n in loaded if _under(n, (*EXPERIMENTS, *BARE))}


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[0] in MAPPED:
        parts[:1] = MAPPED[parts[0]].split(".")
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _statements(nodes):
    """Every import statement in ``nodes`` and under them: inside functions and under
    ``if TYPE_CHECKING:`` too (a circle of types is still one a reader untangles)."""
    for node in nodes:
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        yield from _statements(ast.iter_child_nodes(node))


def imports(path: Path, root: Path = ROOT) -> list[tuple[str, list[str]]]:
    """``(module, names)`` of every import in ``path``, module level and inside functions:
    ``import a.b`` gives ``("a.b", [])``, ``from a import b, c`` gives ``("a", ["b", "c"])``;
    relative imports are resolved against the file's package."""
    tree = ast.parse(path.read_text(), filename=str(path))
    name = _module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = []
    for node in _statements([tree]):
        if isinstance(node, ast.Import):
            found += [(alias.name, []) for alias in node.names]
        else:
            base = node.module or ""
            if node.level:
                parts = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(parts + ([node.module] if node.module else []))
            found.append((base, [alias.name for alias in node.names]))
    return found


def imported_names(path: Path, root: Path = ROOT) -> set[str]:
    """Every module name ``path`` imports (:func:`imports`): ``from a import b`` gives
    ``a`` and ``a.b`` (b may be a module)."""
    return {n for base, names in imports(path, root) for n in [base, *(
        f"{base}.{name}" for name in names)]}


def layer_violations(root: Path = ROOT) -> set[str]:
    """``path imports name (why)`` for every import that breaks one of :data:`RULES`."""
    found: set[str] = set()
    for layer in LAYERS:
        for path in sorted((root / layer).rglob("*.py")):
            module, names = _module_name(path, root), imported_names(path, root)
            part = part_of(module)
            for who, banned, why in RULES:
                if part in who:
                    found |= {f"{path.relative_to(root).as_posix()} imports {n} ({why})"
                              for n in names if _under(n, banned) and part_of(n) != part}
    return found


def import_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """Module -> the modules of the three folders it imports (:func:`imports`: any level,
    inside functions and under ``if TYPE_CHECKING:`` too). ``from a import b`` imports the
    module ``a.b`` when it is one, else ``a``; a module importing its own package is no
    edge (the package comes first)."""
    modules = {_module_name(p, root) for layer in LAYERS for p in (root / layer).rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for layer in LAYERS:
        for path in sorted((root / layer).rglob("*.py")):
            module, names = _module_name(path, root), set()
            for base, aliases in imports(path, root):
                subs = {f"{base}.{a}" for a in aliases} & modules
                names |= subs | ({base} if len(subs) < len(aliases) or not aliases else set())
            graph[module] = {n for n in names & modules
                             if n != module and not module.startswith(n + ".")}
    return graph


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import circles of ``graph``, of any length: its strongly connected components
    of two modules or more (Tarjan's algorithm), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = stack[stack.index(v):]
            del stack[stack.index(v):]
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def layer_climbs(graph: dict[str, set[str]]) -> set[str]:
    """``a imports b (part -> part)`` for every import of a part on the importer's own level
    of :data:`LEVELS` or a higher one."""
    found: set[str] = set()
    for a, targets in graph.items():
        for b in targets:
            pa, pb = part_of(a), part_of(b)
            if pa is not None and pb is not None and pa != pb and LEVEL[pb] >= LEVEL[pa]:
                found.add(f"{a} imports {b} ({pa} -> {pb})")
    return found


def _plant(root: Path, module: str, code: str) -> str:
    path = root.joinpath(*module.split(".")).with_suffix(".py")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(code)
    return path.relative_to(root).as_posix()


def test_the_import_scan_reads_every_import_and_finds_a_planted_violation(tmp_path):
    """The planted modules are named from the parts' data, so this holds in any layout."""
    movement, sibling = f"{MOVEMENTS[0]}.a", f"{MOVEMENTS[0]}.b"
    parts, torque, perturb = (
        "skinny_mj.training.parts",
        "skinny_mj.training.torque",
        "skinny_mj.plant.perturb",
    )
    assert part_of(parts) == part_of(torque) == "training" and part_of(perturb) == "plant"
    up = "." * (MOVEMENTS[0].count(".") + 1) + parts.removeprefix("skinny_mj.")  # relative
    package, _, leaf = torque.rpartition(".")
    a = _plant(tmp_path, movement, f"import numpy as np\nfrom . import b\n"
               f"def f():\n    from {up} import train\n    import skinny_mj.controllers.metrics\n")
    _plant(tmp_path, sibling, f"def g():\n    from {MOVEMENTS[0]} import a\n")
    _plant(tmp_path, perturb,
           f"class P:\n    def m(self):\n        from {package} import {leaf}\n")
    c = _plant(tmp_path, "skinny_mj.controllers.esn", "def f():\n    import mujoco\n")
    _plant(tmp_path, parts, "def train():\n    pass\n")
    _plant(tmp_path, torque, "")
    assert imported_names(tmp_path / a, tmp_path) == {
        "numpy", MOVEMENTS[0], sibling, parts, f"{parts}.train", "skinny_mj.controllers.metrics"}
    assert {v.split(" (")[0] for v in layer_violations(tmp_path)} == {
        f"{a} imports skinny_mj.controllers.metrics", f"{c} imports mujoco"}
    graph = import_graph(tmp_path)
    assert {v.split(" (")[0] for v in layer_climbs(graph)} == {
        f"{movement} imports {parts}", f"{perturb} imports {torque}"}
    assert import_cycles(graph) == [[movement, sibling]]


def test_a_circle_of_any_length_is_found_through_types_and_functions(tmp_path):
    _plant(tmp_path, "skinny_mj.x", "import skinny_mj.y\n")
    _plant(tmp_path, "skinny_mj.y", "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
           "    from skinny_mj.z import Z\n")
    _plant(tmp_path, "skinny_mj.z", "def f():\n    from skinny_mj import x\n")
    _plant(tmp_path, "skinny_mj.w", "import skinny_mj.x\n")  # on the way in, not in the circle
    graph = import_graph(tmp_path)
    assert import_cycles(graph) == [["skinny_mj.x", "skinny_mj.y", "skinny_mj.z"]]
    graph["skinny_mj.y"].clear()
    assert import_cycles(graph) == []


def test_every_import_keeps_the_layering_rules():
    assert layer_violations() == set()


def test_no_import_climbs_a_layer():
    """Every import is of the importer's own part or of a part on a lower level."""
    assert layer_climbs(import_graph()) == set()


def test_every_module_is_placed_in_a_part_or_is_shared():
    """A new module at the top of skinny_mj must be placed in a part of :data:`PARTS` (named
    shared, or moved into a part's package)."""
    modules = {_module_name(p, ROOT) for p in (ROOT / "skinny_mj").rglob("*.py")
               if p.name != "__main__.py"}  # a package's program, placed with its package
    packages = {m for m in modules if any(n.startswith(m + ".") for n in modules)}
    assert {m for m in modules - packages if part_of(m) is None} == set()
    assert set(PARTS) | {"facade"} == {part for level in LEVELS for part in level}


def test_no_import_circles():
    """No modules of the package, the learning or the studies import each other in a
    circle: a study names its report as text, the report imports the study."""
    graph = import_graph()
    circles = import_cycles(graph)
    assert not circles, "import circles:\n" + "\n".join(
        f"{len(c)} modules:\n" + "\n".join(f"  {m} -> {sorted(graph[m] & set(c))}" for m in c)
        for c in circles)


#: The most imports of the project's own modules inside functions (imports belong at the
#: top of a module unless a measured start-up cost says otherwise).
MAX_FUNCTION_IMPORTS = 30


def function_imports(root: Path = ROOT) -> list[str]:
    """``path:line module`` of every import of the project's own modules (the three
    folders, relative imports too) made inside a function or method."""
    own = ("skinny_mj", *BARE)
    found: list[str] = []

    def visit(node, path: Path, inside: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if inside and isinstance(child, ast.Import | ast.ImportFrom):
                names = [a.name for a in child.names] if isinstance(child, ast.Import) \
                    else ["." if child.level else child.module or ""]
                for name in names:
                    if name == "." or _under(name, own):
                        found.append(f"{path.relative_to(root).as_posix()}:{child.lineno} "
                                     f"{name}")
            visit(child, path, inside or isinstance(
                child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda))

    for layer in LAYERS:
        for path in sorted((root / layer).rglob("*.py")):
            visit(ast.parse(path.read_text(), filename=str(path)), path, False)
    return found


def test_the_function_import_count_reads_functions_and_methods_only(tmp_path):
    a = _plant(tmp_path, "skinny_mj.a", "import skinny_mj.b\nimport numpy\n"
               "def f():\n    import numpy\n    from . import b\n"
               "class C:\n    def m(self):\n        from skinny_mj.controllers import esn\n"
               "        def g():\n            import experiments.x\n")
    assert function_imports(tmp_path) == [f"{a}:5 .", f"{a}:8 skinny_mj.controllers",
                                          f"{a}:10 experiments.x"]


def test_imports_of_the_project_sit_at_the_top_of_modules():
    found = function_imports()
    assert len(found) <= MAX_FUNCTION_IMPORTS, "\n".join(found)


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
        "from skinny_mj.controllers.esn import _hidden\n"
        "class A:\n    _kind = 1\n    def __init__(self, esn):\n        self._mine = 1\n"
        "        esn._sparse\n        other = A(esn)\n        other._mine, other._kind\n"
        "        self._mine, super()._x, esn.cfg._replace(), esn.__dict__\n")
    assert private_reads(tmp_path) == {
        "skinny_mj/a.py: esn._sparse",
        "skinny_mj/a.py: from skinny_mj.controllers.esn import _hidden"}


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
    found = {_module_name(p, ROOT) for layer in LAYERS for p in (ROOT / layer).rglob(
        "__init__.py")}
    assert found <= listed, f"add to [tool.setuptools] packages: {sorted(found - listed)}"


def test_models_and_sample_clips_are_package_data():
    import skinny_mj.plant.body as body
    from skinny_mj.trajectories import SAMPLE_ASF, SAMPLE_CLIPS, load_movement, sample_clip

    assert _setuptools()["package-dir"]["skinny_mj.models"] == "models"
    if not os.environ.get(body.MODELS_ENV_VAR):
        for name in body.BODIES:  # every shipped body's files
            assert body.body_of(name).path().is_file()
    assert SAMPLE_ASF.is_file() and (SAMPLE_ASF.parent / "README.md").is_file()
    for name in SAMPLE_CLIPS:
        assert sample_clip(name) == sample_clip(f"{name}.amc") and sample_clip(name).is_file()
    traj, _ = load_movement(sample_clip("md_03"), 8)  # finds the .asf beside it
    assert len(traj) > 100
    with pytest.raises(ValueError, match="md_02"):
        sample_clip("md_99")


def test_studies_are_found_from_the_package():
    """Every module of ``experiments/`` (or ``experiments/<folder>/study.py``) that sets
    NAME is a study (none is listed twice in pyproject); ``experiments.get`` is the
    registry's."""
    import skinny_mj.experiments as experiments

    from skinny_mj.engine import registry
    from skinny_mj.errors import SkinnyInputError

    modules = {p.stem if p.stem != "study" else p.parent.name
               for p in [*(ROOT / "experiments").glob("*.py"),
                         *(ROOT / "experiments").glob("*/study.py")]
               if registry.declared_name(p) is not None}
    assert len(modules) == len(registry.names()) and "paper_e" in modules
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"].get(
        "entry-points", {}).get(registry.GROUP, {})
    assert not set(declared) & set(registry.names())
    study = registry.get("paper-e")
    assert study is sys.modules["skinny_mj.experiments.paper_e.study"].STUDY
    assert experiments.get("paper-e") is study
    assert registry.describe("paper-e") == experiments.describe("paper-e") != ""
    with pytest.raises(SkinnyInputError, match="paper-a, paper-b"):
        registry.get("paper-z")
