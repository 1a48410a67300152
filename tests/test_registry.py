"""The registry of studies: descriptions read off the source, in sync with the imported
studies, and listing the studies imports none of them."""

import subprocess
import sys

import pytest

from skinny_mj.engine import registry
from skinny_mj.errors import SkinnyInputError


def _imported_description(name: str) -> str:
    return registry.get(name).description or ""


@pytest.mark.parametrize("name", registry.names())
def test_description_read_off_the_source_is_the_imported_one(name):
    path = registry.source_path(name)
    assert path is not None, f"{name} is not one of the package's studies"
    read = registry.declared(path).description
    assert read is not None, f"{name}: its description is not readable from its source"
    assert read == _imported_description(name) != ""


def test_listing_and_describing_imports_no_study():
    probe = ("import sys\n"
             "from skinny_mj.cli.study_help import list_text\n"
             "text = list_text()\n"
             "loaded = [m for m in sys.modules if m.startswith('skinny_mj.experiments.')"
             " or m.startswith(('mujoco', 'scipy'))]\n"
             "print(len(text.splitlines()), loaded)\n")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True).stdout.split(maxsplit=1)
    assert int(out[0]) >= len(registry.names()) and out[1].strip() == "[]"


_STUDY = '''"""The module docstring."""
from skinny_mj.engine.study import Study

NAME = "toy-{kind}"
STUDY = Study(name=NAME, description={description})
'''


@pytest.mark.parametrize(("description", "read"), [
    ("__doc__", "The module docstring."),
    ('"A literal description."', "A literal description."),
    ('"built " + NAME', None),  # an expression: only importing the module tells
])
def test_declared_reads_name_and_description(tmp_path, description, read):
    path = tmp_path / "toy.py"
    path.write_text(_STUDY.format(kind="a", description=description))
    assert registry.declared(path) == registry.Declared("toy-a", read)
    path.write_text(_STUDY.format(kind="bb", description='"Changed."'))  # a new reading
    assert registry.declared(path) == registry.Declared("toy-bb", "Changed.")


def test_a_study_imported_from_elsewhere_is_described_by_importing_it(tmp_path):
    path = tmp_path / "other.py"
    path.write_text('"""Docstring."""\nfrom somewhere import STUDY\n\nNAME = "other"\n')
    assert registry.declared(path) == registry.Declared("other", None)


def test_a_derived_study_is_described_by_its_replace_call(tmp_path):
    path = tmp_path / "derived.py"
    path.write_text('"""Paper X on another body."""\nimport dataclasses\n'
                    'from somewhere import other\n\nNAME = "derived"\n'
                    'STUDY = dataclasses.replace(other.STUDY, name=NAME, description=__doc__)\n')
    assert registry.declared(path) == registry.Declared("derived", "Paper X on another body.")


def test_a_module_without_a_study_is_refused_in_one_line(monkeypatch):
    monkeypatch.setattr(registry, "_package_studies", lambda: {"bare": "json"})
    with pytest.raises(SkinnyInputError, match="'bare' .* is not a Study"):
        registry.get("bare")
