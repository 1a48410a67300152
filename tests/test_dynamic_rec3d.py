"""The dynamic study's screen of the recorded-like 3D YMCA (``--rows rec-3d``) and the later
3D general candidates: each a declared row with its changes on the seeds of the row it is
compared with, none in ``--quick``, none moving an earlier row's seeds."""

from __future__ import annotations

import numpy as np


def _plan(**kw):
    from skinny_mj.experiments.dynamic import study as dynamic

    from skinny_mj.engine.plan import plan

    return dynamic, plan(dynamic.STUDY, **kw)


def _changed(p, row_id: str, base_id: str) -> dict:
    base = p.config(base_id).to_dict()
    return {k: v for k, v in p.config(row_id).to_dict().items()
            if base[k] != v and k != "learning_cycles"}  # (derived from rule.cycles)


def test_screen_rows_are_their_base_with_their_changes_on_its_seeds():
    dynamic, p = _plan()
    screen = p.groups()["rec-3d"]
    assert len(screen) == len(dynamic.REC_3D_SCREEN) + 1  # + the PD alone with the poles
    for v, changes in dynamic.REC_3D_SCREEN.items():
        row_id = f"3d-rec-fel-arm-{v}"
        assert row_id in screen
        assert _changed(p, row_id, "3d-rec-fel-arm") == changes
    omega = dynamic.REC_3D_SCREEN[dynamic.REC_3D_CHOICE]["actuation.omega"]
    assert _changed(p, f"3d-rec-arm-pd-omega{omega:g}", "3d-rec-arm-pd") == {
        "actuation.omega": omega}
    for row_id, changes in dynamic.GENERAL_3D_LATE.items():
        assert _changed(p, row_id, "3d-general-babble60+ymca") == changes
    ymca = f"3d-ymca-fel-arm-{dynamic.REC_3D_CHOICE}"
    assert _changed(p, ymca, "3d-ymca-fel-arm") == dynamic.REC_3D_SCREEN[dynamic.REC_3D_CHOICE]
    # paired: the engine gives a row with seeds_of its twin's seeds (tests/test_three_d.py)
    seeds_of = {r.row_id: r.seeds_of for r in p.experiment().rows}
    assert {seeds_of[r] for r in screen} == {"3d-rec-fel-arm"}
    assert seeds_of[ymca] == "3d-ymca-fel-arm"
    assert {seeds_of[r] for r in dynamic.GENERAL_3D_LATE} == {"3d-general-babble60+ymca"}


def test_new_rows_come_last_and_stay_out_of_quick():
    dynamic, p = _plan()
    ids = [r.row.id for r in p.rows]
    new = [*p.groups()["rec-3d"], *p.groups()["ymca-3d"], *dynamic.GENERAL_3D_LATE,
           "3d-general"]
    assert ids[-len(new):] == new  # appended: no earlier row's seeds move
    quick = {r.row.id for r in _plan(quick=True)[1].rows}
    assert not quick & set(new)  # (the 3D preset too: the quick sweep stays as it was)
    assert set(dynamic.QUICK_ROWS) == quick


def test_the_chosen_poles_make_the_teacher_alone_track_the_recorded_ymca_closer():
    """The change the screen chose is the teacher's: its PD alone, at the chosen poles,
    tracks the recorded-like 3D YMCA closer than at the row's 5 rad/s."""
    from skinny_mj.training.loop import train_batch

    dynamic, p = _plan()
    err = {}
    omega = dynamic.REC_3D_SCREEN[dynamic.REC_3D_CHOICE]["actuation.omega"]
    chosen = f"3d-rec-arm-pd-omega{omega:g}"
    for row_id in ("3d-rec-arm-pd", chosen):
        (out,) = train_batch(p.config(row_id), [0])
        assert not out.failed
        err[row_id] = out.test.position_nrmse
    assert np.isfinite(list(err.values())).all()
    assert err[chosen] < 0.5 * err["3d-rec-arm-pd"]
