"""What the command line says to a user: a usage error in one line with a ``--help``
hint, each study's own ``--help``, whole descriptions in ``skinny experiment list``."""

from __future__ import annotations

import subprocess
import sys

import pytest

from skinny_mj.cli.parser import main
from skinny_mj.engine import registry


def _exit(argv, capsys) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        main(argv)
    out = capsys.readouterr()
    return info.value.code, out.out, out.err


@pytest.mark.parametrize("argv", [
    ["train", "--bogus"], ["train", "--epochs"], ["train", "--dof", "5"],
    ["experiment", "paper-e", "--runs", "x"], [], ["trajectory"], ["nonsense"]])
def test_usage_errors_are_one_line_with_a_help_hint_exit_2(argv, capsys):
    code, out, err = _exit(argv, capsys)
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("skinny") and "error:" in lines[0]
    assert lines[0].endswith("--help`)") and "usage:" not in err


def test_an_unknown_option_points_at_its_sub_command_help(capsys):
    code, _, err = _exit(["train", "--bogus", "1"], capsys)  # ("1": a KEY=VALUE position)
    assert code == 2
    assert err == ("skinny train: error: unrecognized arguments: --bogus "
                   "(see `skinny train --help`)\n")


def test_experiment_help_describes_that_study(capsys):
    code, paper_e, _ = _exit(["experiment", "paper-e", "--help"], capsys)
    assert code == 0
    exp = registry.get("paper-e").build()
    assert paper_e.startswith("skinny experiment paper-e\n")
    assert registry.describe("paper-e").split(",")[0] in paper_e
    for label in ("Rows (35", "Groups (--rows GROUP): table = 1, 2, 3, 4, 5, 6",
                  "Runs per row:", "Options: --movement: taken", "Cost: the full sweep is"):
        assert label in paper_e, label
    assert f"is {sum(r.runs or exp.runs for r in exp.rows)} runs" in paper_e
    code, bimanual, _ = _exit(["experiment", "bimanual-delay", "--help"], capsys)
    assert code == 0 and bimanual != paper_e
    flat = " ".join(bimanual.split())  # (the help wraps its lines)
    assert "--movement: refused" in flat and "--signals: refused;" in flat


def _help_imports(names: list[str]) -> dict[str, tuple[int, list[str]]]:
    """Per study, in turn in one fresh interpreter: the lines of its ``--help`` and which
    of SciPy and MuJoCo are imported after it."""
    probe = ("import contextlib, io, sys\n"
             "from skinny_mj.cli.parser import main\n"
             "for name in sys.argv[1:]:\n"
             "    with contextlib.redirect_stdout(io.StringIO()) as text:\n"
             "        with contextlib.suppress(SystemExit):\n"
             "            main(['experiment', name, '--help'])\n"
             "    heavy = sorted({m.split('.')[0] for m in sys.modules} & {'scipy', 'mujoco'})\n"
             "    print(name, len(text.getvalue().splitlines()), *heavy)\n")
    out = subprocess.run([sys.executable, "-c", probe, *names], capture_output=True,
                         text=True, check=True).stdout.splitlines()
    return {name: (int(n), heavy) for name, n, *heavy in map(str.split, out)}


def test_experiment_help_imports_neither_scipy_nor_mujoco():
    """Each study's ``--help`` loads none of the learning code's or the plant's heavy
    libraries (they are most of a start-up): building a sweep to describe it runs nothing,
    and a row's cost (paper C's loads its movement) is worked out only when scheduled."""
    names = registry.names()
    seen = _help_imports(names)
    assert sorted(seen) == names
    for name, (n_lines, heavy) in seen.items():
        assert n_lines > 5, name
        assert heavy == [], (name, heavy)


def test_experiment_help_of_a_study_that_cannot_build_still_describes_it(capsys, monkeypatch):
    from skinny_mj.engine.study import Study
    from skinny_mj.errors import SkinnyInputError

    def refuse(*_, **__):
        raise SkinnyInputError("figure-eight needs an extra: pip install x")
    monkeypatch.setattr(Study, "build", refuse)
    code, out, _ = _exit(["experiment", "figure-eight", "--help"], capsys)
    assert code == 0 and registry.describe("figure-eight")[:40] in " ".join(out.split())
    assert "Rows: not listed here: figure-eight needs an extra: pip install x" in out


def test_experiment_help_of_an_unknown_study_is_one_line_exit_2(capsys):
    code, out, err = _exit(["experiment", "no-such-study", "--help"], capsys)
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and "known: " in err and "paper-e" in err


def test_experiment_help_without_a_name_is_the_command_help(capsys):
    code, out, _ = _exit(["experiment", "--help"], capsys)
    assert code == 0 and out.startswith("usage: skinny experiment")


def test_experiment_list_shows_whole_descriptions(capsys):
    assert main(["experiment", "list"]) == 0
    listed = " ".join(capsys.readouterr().out.split())
    for name in registry.names():
        shown = registry.describe(name).replace("``", "`")  # RST literals as Markdown's
        assert f"{name} {shown}" in listed, name
        assert registry.describe(name).endswith((".", "?", ")")), name  # a whole sentence


def test_measured_time_per_run_comes_from_earlier_sweeps(tmp_path):
    import json

    from skinny_mj.cli.study_help import measured_here

    assert measured_here("paper-e", tmp_path) is None
    for stamp, rows in (("a", [(2.0, 10), (4.0, 10)]), ("b", [(3.0, 20)])):
        (tmp_path / "paper-e" / stamp).mkdir(parents=True)
        (tmp_path / "paper-e" / stamp / "results.json").write_text(json.dumps({"rows": [
            {"n": n, "n_error": 0, "wall_s": {"mean": w, "total": w * n}} for w, n in rows]}))
    said = measured_here("paper-e", tmp_path)
    assert said.startswith("3.0 s of one worker per run, mean of 40 runs in 2 earlier")


# -- skinny bench: a skipped figure says what to install; a value at its goal's edge ------
def test_bench_names_the_extra_a_skipped_figure_needs(monkeypatch):
    import sys as _sys

    from skinny_mj.cli import bench

    monkeypatch.setitem(_sys.modules, "reservoirpy", None)  # as if not installed
    figure = bench.esn_run_vs_reservoirpy(20, 5, 1)
    assert "reservoirpy" in figure["skipped"] and 'pip install -e ".[bench]"' in figure["skipped"]
    figures = {"esn_run_vs_reservoirpy": [figure, figure], "load_avg_start": (1.0,) * 3,
               "load_avg_end": (1.0,) * 3, "cpu_count": 2}
    figures["summary"] = bench.summary(figures)
    row = next(line for line in bench.table(figures).splitlines()
               if line.startswith("esn_run_vs_reservoirpy_N200"))
    assert "skipped" in row and 'pip install -e ".[bench]"' in row


@pytest.mark.parametrize(("value", "op", "goal", "printed"), [
    (2.0004, "<=", 2.0, "2.0004"), (1.99999, "<=", 2.0, "1.99999"), (2.0, "<=", 2.0, "2"),
    (2.9999996, ">=", 3.0, "2.9999996"), (3.0 + 1e-12, ">=", 3.0, repr(3.0 + 1e-12)),
    (12.04, ">=", 6.0, "12"), (-5.4712, "<=", -4.5, "-5.47")])
def test_bench_prints_a_value_at_its_goals_edge_in_full(value, op, goal, printed):
    from skinny_mj.cli.bench_summary import shown

    assert shown(value, op, goal) == printed


def test_bench_table_shows_why_a_value_misses_its_goal():
    from skinny_mj.cli import bench

    figures = {"torque_over_kinematic": {"ratio": 2.0004}, "load_avg_start": (1.0,) * 3,
               "load_avg_end": (1.0,) * 3, "cpu_count": 2}
    figures["summary"] = bench.summary(figures)
    row = next(line for line in bench.table(figures).splitlines()
               if line.startswith("torque_over_kinematic"))
    assert row.split() == ["torque_over_kinematic", "2.0004", "<=", "2", "NO"]
    assert "--quick" not in bench.table(figures)
    figures["quick"] = True  # one epoch per row: a smoke test, and the table says so
    assert "torque_over_kinematic times one epoch" in bench.table(figures)


# -- skinny trajectory list: every source of a movement, in columns that hold -------------
def test_trajectory_list_names_every_source(capsys):
    from skinny_mj.trajectories import SAMPLE_ASF, SAMPLE_CLIPS, names

    assert main(["trajectory", "list"]) == 0
    out = capsys.readouterr().out
    words = out.split()
    for name in names():
        assert name in words, name
    for clip in SAMPLE_CLIPS:
        assert f"{clip}.amc" in words
    assert SAMPLE_ASF.name in out
    for kind in (".npz", ".csv", ".amc", ".bvh", "babble:seed=", "set:", "@start="):
        assert kind in out, kind


def test_trajectory_list_columns_hold_for_long_names():
    from skinny_mj.cli.movement_list import MAX_NAME, columns

    rows = [("a", "short"), ("ymca-recorded-unit2d", "x " * 60),
            ("n" * (MAX_NAME + 5), "a name longer than the column")]
    lines = columns(rows, width=60)
    assert all(len(line) <= 60 for line in lines if "n" * MAX_NAME not in line)
    starts = {line.index("short") if "short" in line else None for line in lines} - {None}
    assert starts == {lines[1].index("x")}  # descriptions start in one column
    long_at = lines.index("  " + "n" * (MAX_NAME + 5))  # a long name on its own line
    below = lines[long_at + 1:]
    assert " ".join(line.strip() for line in below) == "a name longer than the column"
    assert {len(line) - len(line.lstrip()) for line in below} == starts
