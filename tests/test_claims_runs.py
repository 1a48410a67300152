"""The runs the claims read (experiments/claims_runs.py): the plan covers every (study,
reading) key with a command that makes those runs (a band's points at the band's gains, in
order), the metrics derived from stored series, and the extract: scoring it gives what
scoring the sweep's folder gives, and `skinny claims` writes it and the page from it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from skinny_mj.experiments import claims_page as page
from skinny_mj.experiments import claims_runs as runs
from skinny_mj.experiments import claims_score as cs
from skinny_mj.experiments.claims_rules import READINGS

from skinny_mj.cli.parser import main
from skinny_mj.engine import protocols, registry
from skinny_mj.engine.plan import plan
from skinny_mj.engine.stats import to_jsonable


def test_the_plan_covers_every_key_the_claims_read():
    assert set(runs.PLAN) == set(cs.KEYS)
    for key, commands in runs.PLAN.items():
        assert commands or len(runs.NO_COMMAND[key]) > 60, key
        assert all(args[0] == key[0] for args in commands), key
        band = max(len(READINGS[r].band) for r in key[1].split("+"))
        assert len(commands) == (band or (1 if commands else 0)), key


def _planned(args: tuple[str, ...]):
    """The study a planned command sweeps, and its options (as `skinny experiment` plans)."""
    options = runs.command_options(args)
    study = registry.get(args[0])
    if options["protocol"]:
        study = protocols.apply(options["protocol"], study, args[0])
    return plan(study, movement=options["movement"])


@pytest.mark.parametrize("key", sorted(k for k, v in runs.PLAN.items() if v))
def test_each_command_makes_its_readings_runs(key):
    study, ran = key
    for point, args in enumerate(runs.PLAN[key]):
        planned = _planned(args)
        row = planned.rows[0].id
        config = planned.config(row)
        recorded = "recorded" in ran.split("+")
        assert (config.movement.trajectory == "ymca-recorded") == recorded, args
        gain = config.method.u_error_gain
        if "gain-band" in ran:
            assert gain == READINGS["gain-band"].band[point], args
        elif "fitted-gain-2" in ran:
            assert gain == 2.0
        elif study != "paper-b":
            assert gain == 1.0, args
        if study == "paper-d":
            noise = planned.params.get("tt_input_noise", 0.0)
            assert noise == (0.01 if "fitted-tt-noise" in ran else 0.0), args
        if study == "paper-b":
            default = plan(registry.get("paper-b")).config(row).esn
            want = {"default": (default.spectral_radius, default.noise_level),
                    "b-noise-free": (default.spectral_radius, 0.0),
                    "b-sr0.9-nu0.02": (0.9, 0.02)}[ran]
            assert (config.esn.spectral_radius, config.esn.noise_level) == want


@pytest.mark.parametrize("study", ["paper-e", "paper-e-explain"])
def test_paper_es_thesis_protocol_is_the_recorded_data_at_gain_2(study):
    """So its sweep is the gain band's top point too (one sweep, not two)."""
    thesis = _planned((study, "--protocol", "thesis"))
    same = _planned((study, "--movement", "ymca-recorded", "--protocol", "gain-2"))
    for row in thesis.rows:
        assert thesis.config(row.id) == same.config(row.id)
    assert thesis.params == same.params


def test_the_plan_prints_each_sweep_once_and_the_line_that_scores_them(capsys):
    assert main(["claims", "--plan"]) == 0
    lines = capsys.readouterr().out.splitlines()
    commands = [line for line in lines if line.startswith("skinny experiment")]
    assert len(commands) == len(set(commands)) == len(
        {args for v in runs.PLAN.values() for args in v})
    assert all(" --workers 1 --out results/claims-runs/" in c for c in commands)
    last = lines[-1]
    assert last.startswith("skinny claims --from ") and last.endswith(
        "--extract docs/results/claims-runs --page docs/results/claims.md")
    assert last.count("--from ") == sum(map(len, runs.PLAN.values()))


def test_derived_paper_b_metrics_compare_the_output_with_its_own_target():
    t = np.arange(400)
    desired = 30 * np.sin(2 * np.pi * t / 100)
    actual = 2 * desired + np.where(t % 2, 0.5, -0.5)  # twice the swing, plus a jitter
    out = runs.numeric_metrics("paper-b", {"relative_error_x1": 0.1, "traces": {"x1": {
        "desired": desired.tolist(), "actual": actual.tolist(), "leader": desired.tolist()}}})
    assert out["relative_error_x1"] == 0.1
    assert out["amplitude_ratio_x1"] == pytest.approx(2.0, rel=0.01)
    assert out["roughness_x1"] > 10  # the jitter's second difference dwarfs the sine's
    smooth = runs.numeric_metrics("paper-b", {"traces": {"x1": {
        "desired": desired.tolist(), "actual": (0.5 * desired).tolist()}}})
    assert smooth["roughness_x1"] == pytest.approx(0.5)
    assert smooth["amplitude_ratio_x1"] == pytest.approx(0.5)


def test_derived_fig3_counts_at_the_declared_tolerances():
    curve = (0.9 ** np.arange(400)).tolist()  # excess 0.9^i: within 1 % at i = 44
    out = runs.numeric_metrics("paper-e", {"convergence_curve": curve})
    assert out == {"cycles_to_converge_tol1": 45.0, "cycles_to_converge_tol5": 30.0,
                   "cycles_to_converge_tol10": 23.0}
    assert runs.numeric_metrics("paper-e", {"position_nrmse": 0.1}) == {"position_nrmse": 0.1}


def _sweep(folder: Path, n: int = 20) -> Path:
    """A paper-e sweep on the recorded data: rows 2 and 4, with a series the extract drops."""
    rng = np.random.default_rng(3)
    (folder / "runs").mkdir(parents=True)
    for i, (row, mean) in enumerate((("2", 0.1), ("4", 0.05))):
        for k in range(n):
            failed = (row, k) == ("4", 0)
            metrics = {"position_nrmse": mean * (1 + 0.1 * rng.standard_normal()),
                       "motor_nrmse": 0.2, "wall_s": 1.0, "train_curve_position_nrmse": [0.3]}
            rec = {"experiment": "paper-e", "row": row, "row_index": i, "run_index": k,
                   "seed": 100 * i + k, "status": "failed" if failed else "ok",
                   "metrics": {} if failed else metrics}
            (folder / "runs" / f"{row}-{rec['seed']}.json").write_text(json.dumps(rec))
    (folder / "config.json").write_text(json.dumps({
        "experiment": "paper-e", "seeding": "row-id", "base_seed": 0,
        "options": {"quick": False, "movement": "ymca-recorded", "protocol": None}}))
    return folder


def test_an_extract_scores_as_its_folder_and_keeps_only_what_the_claims_read(tmp_path):
    folder = _sweep(tmp_path / "sweep")
    key = ("paper-e", "recorded")
    sweep = cs.Sweep(folder, key)
    data = sweep.extract
    assert data["command"] == "skinny experiment paper-e --movement ymca-recorded"
    assert data["seeding"] == "row-id" and data["point"] == 0
    assert set(data["metrics_read"]) >= {"position_nrmse", "motor_nrmse", "train_wall_s"}
    first = data["rows"]["4"][0]
    assert first == {"run": 0, "seed": 100, "status": "failed", "metrics": {}}
    assert set(data["rows"]["2"][0]["metrics"]) == {"position_nrmse", "motor_nrmse"}
    path = tmp_path / runs.extract_name(key)
    path.write_text(runs.extract_text(to_jsonable(data)))
    assert json.loads(path.read_text()) == data
    from_folder = cs.score({key: [folder]})
    from_extract = cs.score({key: [path]})
    assert page.markdown(from_extract) == page.markdown(from_folder)
    assert cs.counts(from_extract) == cs.counts(from_folder)
    e4 = next(c for c in from_extract["claims"] if c["id"] == "E4")["columns"][1]
    assert e4["column"] == "recorded" and e4["outcome"] == "not testable"  # one run failed
    assert "row 4: 19 ok runs with position_nrmse (1 failed, 0 errored, of 20)" in e4["reason"]


def test_the_command_writes_the_extracts_and_the_page_and_rescores_them(tmp_path, capsys):
    folder = _sweep(tmp_path / "sweep")
    doc = tmp_path / "claims.md"
    doc.write_text(f"# Claims\n\nProse.\n\n{cs.BEGIN}\nold\n{cs.END}\n\nMore prose.\n")
    extracts = tmp_path / "extracts"
    assert main(["claims", "--from", f"paper-e:recorded={folder}", "--extract",
                 str(extracts), "--page", str(doc)]) == 0
    assert [p.name for p in extracts.iterdir()] == ["paper-e.recorded.json"]
    text = doc.read_text()
    assert text.startswith("# Claims\n\nProse.\n\n") and text.endswith("\n\nMore prose.\n")
    assert "\nold\n" not in text and "| paper-e | recorded: `skinny experiment paper-e" in text
    assert not (tmp_path / "results").exists()  # --page alone writes no results folder
    before = text
    assert main(["claims", "--extracts", str(extracts), "--page", str(doc)]) == 0
    assert doc.read_text() == before
    assert page.page_matches(before, cs.score(cs.extract_sources(extracts)))
    capsys.readouterr()
    assert main(["claims", "--extracts", str(extracts), "--page", str(tmp_path / "x.md")]) == 2
    assert main(["claims", "--page", str(doc)]) == 2
    err = capsys.readouterr().err
    assert "cannot read the page" in err and "give the sweeps" in err
