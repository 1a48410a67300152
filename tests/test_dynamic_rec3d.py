"""The dynamic study's stiffer 3D teacher (``--rows omega20``): each row is its base row
with the poles and forgetting of :data:`STIFF`, on that row's seeds, none in ``--quick``."""

from __future__ import annotations

import numpy as np


def _plan(**kw):
    from skinny_mj.experiments.dynamic import study as dynamic

    from skinny_mj.engine.plan import plan

    return dynamic, plan(dynamic.STUDY, **kw)


def _changed(p, row_id: str, base_id: str) -> dict:
    base = p.config(base_id).to_dict()
    return {k: v for k, v in p.config(row_id).to_dict().items()
            if base[k] != v and k != "learning_cycles"}  # (derived from method.cycles)


def test_stiff_rows_are_their_base_with_the_stiffer_teacher_on_its_seeds():
    dynamic, p = _plan()
    group = p.groups["omega20"]
    pairs = {"3d-rec-fel-arm-omega20+forget0.9": "3d-rec-fel-arm",
             "3d-ymca-fel-arm-omega20+forget0.9": "3d-ymca-fel-arm",
             "3d-rec-arm-pd-omega20": "3d-rec-arm-pd"}
    assert set(group) == set(pairs)
    for row_id, base_id in pairs.items():
        want = dynamic.STIFF if "fel" in row_id else {"actuation.omega": 20.0}
        assert _changed(p, row_id, base_id) == want
    # paired: the engine gives a row with seeds_of its twin's seeds (tests/test_three_d.py)
    seeds_of = {r.id: r.seeds_of for r in p.rows}
    assert [seeds_of[r] for r in pairs] == ["3d-rec-fel-arm", "3d-ymca-fel-arm", "3d-rec-fel-arm"]


def test_quick_leaves_out_the_stiff_rows_the_held_out_choice_and_the_3d_preset():
    dynamic, p = _plan()
    quick = {r.id for r in _plan(quick=True)[1].rows}
    assert set(dynamic.QUICK_ROWS) == quick
    assert {r.id for r in p.rows} - quick == {*p.groups["omega20"], *p.groups["held-out"],
                                             "3d-general"}


def test_the_stiffer_poles_make_the_teacher_alone_track_the_recorded_ymca_closer():
    """Its PD alone, at 20 rad/s, tracks the recorded-like 3D YMCA closer than at the arm
    rows' 5 rad/s."""
    from skinny_mj.training.loop import train_batch

    _, p = _plan()
    err = {}
    for row_id in ("3d-rec-arm-pd", "3d-rec-arm-pd-omega20"):
        (out,) = train_batch(p.config(row_id), [0])
        assert not out.failed
        err[row_id] = out.test.position_nrmse
    assert np.isfinite(list(err.values())).all()
    assert err["3d-rec-arm-pd-omega20"] < 0.5 * err["3d-rec-arm-pd"]
