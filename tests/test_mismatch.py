"""The mismatch study's runs: one training tested on several plants, the payload switch."""

from skinny_mj.experiments.mismatch import study

from skinny_mj.engine.study import Row
from skinny_mj.training.perform import SwitchHook


class _Hook:
    def __init__(self):
        self.calls = []

    def begin(self, plant, n_steps):
        self.calls.append(("begin", n_steps))

    def after_step(self, t, plant):
        self.calls.append(("after", t))


def test_switch_hook_changes_the_plant_once_at_its_cycle_and_step():
    inner, fired = _Hook(), []
    hook = SwitchHook(inner, cycle=1, step=2, change=lambda: fired.append(len(inner.calls)))
    for _ in range(3):
        hook.begin(None, 4)
        for t in range(3):
            hook.after_step(t, None)
    assert len(fired) == 1 and inner.calls[fired[0] - 1] == ("after", 2)
    assert inner.calls.count(("begin", 4)) == 3


def test_one_esn_training_is_tested_at_k0_k1_and_on_changed_plants():
    config = study.STUDY.base.override({**study.ESN, "plant.dof": 4, "movement.trajectory": "y",
                                        "method.epochs": 1})
    row = Row("t", {}, params={"also": ("payload1", "delay")}, shape=study.ESN_SHAPE)
    (out,) = study.STUDY.run(config, row, [0])
    for key in ("position_nrmse", "position_nrmse_k1", "position_nrmse_on_payload1",
                "position_nrmse_on_delay"):
        assert 0 < out[key] < 10
    assert 0 < out["rms_error_deg_on_payload1"] < 180
    assert out["position_nrmse_on_payload1"] != out["position_nrmse"]


def test_every_mismatch_has_a_row_per_controller_and_body():
    ids = {r.id for r in study.ROWS}
    for bd in study.BODIES:
        for m in study.MISMATCHES:
            for c in study.CONTROLLERS:
                assert study.row_id(bd, m, c) in ids


def test_a_refitting_performance_learns_after_the_switch_and_a_frozen_one_does_not():
    """The payload switch, performed by one trained network three ways: frozen, refitted
    every cycle by its training's rule, and refitted with faster forgetting: alike in the
    first cycle, apart from the first refit on."""
    import pytest
    from skinny_mj.experiments.mismatch import switch

    from skinny_mj.training.result import Perform

    config = study.STUDY.base.override({**study.ESN, "plant.dof": 4, "movement.trajectory": "y",
                                        "method.epochs": 2})
    curves = {}
    for learner in ("esn-frozen", "esn-refit", "esn-refit-0.5"):
        row = Row("t", {}, shape=switch.shape(learner))
        (out,) = study.STUDY.run(config, row, [0])
        curves[learner] = out["curve"]
    frozen, refit, fast = curves["esn-frozen"], curves["esn-refit"], curves["esn-refit-0.5"]
    assert refit[0] == frozen[0] == fast[0]
    assert all(a != pytest.approx(b, rel=1e-6) for a, b in zip(refit[1:], frozen[1:], strict=True))
    assert all(a != pytest.approx(b, rel=1e-6) for a, b in zip(fast[2:], refit[2:], strict=True))
    with pytest.raises(ValueError, match="not both"):
        Perform("p", 3, 0.5, 1, refit=True, rls_forgetting=0.99)


def test_the_long_rows_lengthen_their_row_on_its_seeds_and_the_group_holds_both():
    by_id = {r.id: r for r in study.ROWS}
    for bd, (mismatches, runs) in study.LONG.items():
        for m in mismatches:
            short = by_id[study.row_id(bd, m, "esn")]
            long = by_id[f"{short.id}-x{study.LONG_FACTOR}"]
            assert long.seeds_of == short.id and long.runs == runs
            assert long.overrides == {**short.overrides,
                                      "method.epochs": study.EPOCHS * study.LONG_FACTOR}
            assert short.id in study.GROUPS["long"]
    assert all(r.endswith("-delay-esn") for r in study.GROUPS["delay-esn"])
