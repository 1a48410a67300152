"""skinny_mj.training.fits: rule.fit's values are a registry; a registered rule is chosen
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


def test_a_registered_fit_is_a_value_of_rule_fit_and_builds_its_rule(registry):
    made = []
    fits.register_fit("mine", lambda cfg, esn, steps: made.append(steps) or "rule",
                      bodies=("velocity",))
    cfg = TrainConfig().override({"rule.fit": "mine"})
    assert fits.make_rule(cfg, esn=None, steps=311) == "rule" and made == [311]
    with pytest.raises(SkinnyInputError, match="runs on actuation=velocity"):
        cfg.override({"actuation": "torque"})


def test_a_name_is_registered_once_and_unknown_names_are_refused(registry):
    with pytest.raises(SkinnyInputError, match="registered already"):
        fits.register_fit("rls", lambda cfg, esn, steps: None)
    fits.register_fit("rls", lambda cfg, esn, steps: "new", bodies=("torque",), replace=True)
    with pytest.raises(SkinnyInputError, match="fit must be one of"):
        TrainConfig().override({"rule.fit": "no-such-fit"})


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
    cfg = TrainConfig().override({"rule.fit": "named"})
    assert fits.make_rule(cfg, None, 7) == ("named", 7)
    from skinny_mj.training import torque  # the remembering fits' builder, named in FITS

    monkeypatch.setattr(torque, "readout_fitter", lambda cfg, esn, steps: ("torque", steps))
    rls = TrainConfig().override({"actuation": "torque", "rule.fit": "rls"})
    assert fits.make_rule(rls, None, 40) == ("torque", 40)
