"""skinny_mj.training.fits: method.fit's values are a registry; a registered rule is chosen
by the key, refused on a body it does not run on, and a name is registered once."""

from __future__ import annotations

import pytest

from skinny_mj.errors import SkinnyInputError
from skinny_mj.training import fits
from skinny_mj.training.config import TrainConfig


@pytest.fixture
def registry(monkeypatch):
    monkeypatch.setattr(fits, "FITS", dict(fits.FITS))  # each test's own copy
    return fits.FITS


def test_a_registered_fit_is_a_value_of_method_fit_and_builds_its_rule(registry):
    made = []
    fits.register_fit("mine", lambda cfg, esn, steps: made.append(steps) or "rule",
                      bodies=("velocity",))
    cfg = TrainConfig().override({"method.fit": "mine"})
    assert fits.make_rule(cfg, esn=None, steps=311) == "rule" and made == [311]
    with pytest.raises(SkinnyInputError, match="runs on actuation=velocity"):
        cfg.override({"actuation": "torque"})


def test_a_name_is_registered_once_and_unknown_names_are_refused(registry):
    with pytest.raises(SkinnyInputError, match="registered already"):
        fits.register_fit("rls", lambda cfg, esn, steps: None)
    fits.register_fit("rls", lambda cfg, esn, steps: "new", bodies=("torque",), replace=True)
    with pytest.raises(SkinnyInputError, match="fit must be one of"):
        TrainConfig().override({"method.fit": "no-such-fit"})


def test_the_packages_fits_build_what_training_used_before(registry):
    assert fits.make_rule(TrainConfig(), None, 10) is None  # the loop's per-cycle default
    assert registry["ridge-select"].bodies == ("velocity",)
    assert registry["forgetting"].bodies == registry["rls"].bodies == ("torque",)



def build_named(cfg, esn, steps):
    """A builder a fit names as text (``"tests.test_fits:build_named"``)."""
    return ("named", steps)


def test_a_fit_may_name_its_builder_which_is_imported_when_the_rule_is_made(registry,
                                                                            monkeypatch):
    fits.register_fit("named", f"{__name__}:build_named")
    cfg = TrainConfig().override({"method.fit": "named"})
    assert fits.make_rule(cfg, None, 7) == ("named", 7)
    from skinny_mj.training import torque  # the remembering fits' builder, named in FITS

    monkeypatch.setattr(torque, "readout_fitter", lambda cfg, esn, steps: ("torque", steps))
    rls = TrainConfig().override({"actuation": "torque", "method.fit": "rls"})
    assert fits.make_rule(rls, None, 40) == ("torque", 40)


def test_a_fits_settings_are_keys_of_method_fit_and_sweep_axes(registry):
    from dataclasses import dataclass

    from skinny_mj.engine.grid import parse_assignment

    @dataclass(frozen=True)
    class Mine(fits.FitSettings):
        lam0: float = 1e-2
        decay: float = 0.2

    fit = fits.register_fit("mine", lambda cfg, esn, steps: (cfg.method.fit.lam0,
                                                             cfg.method.fit.decay), settings=Mine)
    assert fit is fits.FITS["mine"] and fit.settings is Mine  # what a package publishes
    cfg = TrainConfig().override({"method.fit.lam0": 0.1, "method.fit": "mine"})  # any order
    assert fits.make_rule(cfg, None, 1) == (0.1, 0.2)
    assert {k: v for k, v in cfg.to_dict().items() if k.startswith("method.fit")} == {
        "method.fit": "mine", "method.fit.lam0": 0.1, "method.fit.decay": 0.2}
    assert TrainConfig.from_dict(cfg.to_dict()) == cfg
    assert parse_assignment("method.fit.decay=0.5,0.9", cfg)[1] == [0.5, 0.9]
    with pytest.raises(SkinnyInputError, match="not a setting of method.fit=cycle"):
        TrainConfig().override({"method.fit.lam0": 0.1})
    with pytest.raises(SkinnyInputError, match="a FitSettings subclass"):
        fits.register_fit("bad", lambda cfg, esn, steps: None, settings=dict, replace=True)


def test_skinny_sweep_sweeps_both_settings_of_another_packages_rule(registry, monkeypatch,
                                                                  tmp_path):
    """A rule published through the entry-point group, as docs/adding-a-learning-rule.md
    says: ``skinny sweep`` finds it by name and sweeps its two hyper-parameters."""
    import json
    from dataclasses import dataclass
    from types import SimpleNamespace

    from skinny_mj.controllers.learning import CycleFit

    from skinny_mj import plugins
    from skinny_mj.cli.parser import main

    @dataclass(frozen=True)
    class Two(fits.FitSettings):
        kind: str = "two"
        lam0: float = 1e-2
        decay: float = 0.2

    built = []

    def make(cfg, esn, steps):
        built.append((cfg.method.fit.lam0, cfg.method.fit.decay))
        return CycleFit()

    published = SimpleNamespace(name="two", value="pkg:FIT", load=lambda: fits.Fit(make,
                                                                                 settings=Two))
    monkeypatch.setattr(plugins, "entry_points",
                        lambda group: [published] if group == fits.FIT_GROUP else [])
    plugins.load_group.cache_clear()
    try:
        assert main(["sweep", "method.fit=two", "method.fit.lam0=0.1,0.01",
                     "method.fit.decay=0.2,0.5", "method.epochs=1", "esn.n_reservoir=20",
                     "--runs", "1", "--workers", "1", "--out", str(tmp_path / "s"), "-q"]) == 0
    finally:
        plugins.load_group.cache_clear()
    grid = [(0.01, 0.2), (0.01, 0.5), (0.1, 0.2), (0.1, 0.5)]
    assert sorted(built) == grid  # each cell's training built the rule with its settings
    runs = [json.loads(p.read_text()) for p in (tmp_path / "s" / "runs").glob("*.json")]
    assert sorted((r["params"]["method.fit.lam0"], r["params"]["method.fit.decay"])
                  for r in runs) == grid
    assert all(r["status"] == "ok" and r["metrics"]["position_nrmse"] > 0 for r in runs)


def test_method_forgetting_is_an_alias_of_method_fit_forgetting():
    torque = {"actuation": "torque", "method.fit": "rls"}
    old = TrainConfig().override({**torque, "method.forgetting": 0.9})
    assert old == TrainConfig().override({**torque, "method.fit.forgetting": 0.9})
    assert old.method.fit == fits.ForgettingSettings("rls", 0.9) and old.method.forgetting == 0.9
    # an old run file lists it with every fit: checked, then of no use to the fit
    assert TrainConfig().override({"method.forgetting": 0.8}) == TrainConfig()
    for bad in ({"method.forgetting": 1.5}, {**torque, "method.fit.forgetting": -0.1}):
        with pytest.raises(SkinnyInputError, match=r"forgetting must be in \[0, 1\]"):
            TrainConfig().override(bad)
    switched = old.override({"method.fit": "forgetting"})  # the same settings type: kept
    assert switched.method.fit == fits.ForgettingSettings("forgetting", 0.9)
    assert old.override({"method.fit": "cycle"}).method.fit == fits.FitSettings("cycle")


def test_a_rule_reports_its_own_metrics():
    import numpy as np
    from skinny_mj.controllers.learning import CycleFit
    from skinny_mj.controllers.ridge_select import RidgeSelector

    assert CycleFit().metrics(0) == {}
    selector = RidgeSelector.__new__(RidgeSelector)
    selector.chosen = np.array([[0.1, np.nan]])
    assert selector.metrics(0) == {"ridge_lambda": [0.1, None]}
