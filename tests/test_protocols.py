"""Named protocols (skinny_mj.engine.protocols): declared readings applied to a study."""

from __future__ import annotations

import pytest
from skinny_mj.experiments import paper_d
from skinny_mj.experiments.paper_e import study as paper_e

from skinny_mj.cli.parser import main
from skinny_mj.engine import protocols, registry
from skinny_mj.engine.plan import plan
from skinny_mj.errors import SkinnyInputError


def test_every_reading_says_what_it_rests_on_and_reaches_its_studies():
    for protocol in protocols.PROTOCOLS.values():
        for reading in protocol.readings:
            assert len(reading.rests_on) > 80, reading.setting
            for name in reading.studies:
                study = protocols.apply(protocol.name, registry.get(name), name)
                base = plan(study).base.to_dict()
                assert all(base[k] == v for k, v in reading.overrides.items()), name
                assert all(study.params[k] == v for k, v in reading.params.items()), name


def test_thesis_reading_on_paper_e_keeps_each_rows_own_settings():
    study = protocols.apply("thesis", paper_e.STUDY, "paper-e")
    for row in ("1", "2", "5", "fig5a-nu0.1"):
        config, default = plan(study).config(row), plan(paper_e.STUDY).config(row)
        assert config.movement.trajectory == "ymca-recorded"
        assert config.method.u_error_gain == 2.0 != default.method.u_error_gain
        assert config.override({"movement.trajectory": "ymca", "method.u_error_gain": 1.0}) \
            == default  # nothing else changed: the row's method, noise, repetitions
    # --movement is the user's: it still wins over the reading
    assert plan(study, movement="ymca").config("5").movement.trajectory == "ymca"


def test_thesis_reading_reaches_paper_d_true_target_half():
    study = protocols.apply("thesis", paper_d.STUDY, "paper-d")
    both = plan(study).trainings("2")
    assert both["tt"].method.input_noise == 0.01
    assert both["fel"].method.u_error_gain == 2.0
    assert both["tt"].movement.trajectory == both["fel"].movement.trajectory == "ymca-recorded"
    assert plan(paper_d.STUDY).trainings("2")["tt"].method.input_noise == 0.0


def test_refusals_name_what_is_wrong_in_one_line(capsys):
    with pytest.raises(SkinnyInputError, match="reads no setting of 'generalization'"):
        protocols.apply("thesis", registry.get("generalization"), "generalization")
    with pytest.raises(SkinnyInputError,
                       match="unknown protocol 'nope'; protocols: thesis, gain-0.5, "):
        protocols.get("nope")
    assert main(["experiment", "paper-a", "--protocol", "thesis", "--quick"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "reads no setting of 'paper-a'" in err


def test_a_studys_help_names_the_protocols_that_read_its_settings():
    from skinny_mj.cli.study_help import study_help

    assert "Protocols (--protocol NAME): thesis (the training data;" in study_help("paper-e")
    assert "--protocol NAME" not in study_help("generalization")
    assert "b-noise-free (paper B's reservoir noise)" in " ".join(study_help("paper-b").split())
    assert "gain-0.5 (the scale of the feedback controller's u_error)" \
        in " ".join(study_help("paper-d").split())


def test_the_gain_band_and_paper_bs_noise_free_reservoir_set_only_their_key():
    for name, key, value, study_name in (("gain-0.5", "method.u_error_gain", 0.5, "paper-e"),
                                         ("gain-2", "method.u_error_gain", 2.0, "paper-e"),
                                         ("b-noise-free", "esn.noise_level", 0.0, "paper-b")):
        study = protocols.apply(name, registry.get(study_name), study_name)
        default = plan(registry.get(study_name))
        for row in (r.id for r in default.rows[:3]):
            config = plan(study).config(row)
            assert config.to_dict()[key] == value != default.config(row).to_dict()[key]
            assert config.override({key: default.config(row).to_dict()[key]}) \
                == default.config(row)
