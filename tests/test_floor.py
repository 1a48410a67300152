"""The torque-limited floor (iLQR on the torque twin): its box QP, and that it is a floor."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from skinny_mj.training.feasible import load_movement
from skinny_mj.training.floor import box_qp, torque_floor


def test_box_qp_matches_the_best_vertex_face_search():
    rng = np.random.default_rng(0)
    for _ in range(20):
        m = rng.normal(size=(3, 3))
        h = m @ m.T + 0.1 * np.eye(3)
        g = rng.normal(size=3) * 3
        lo, hi = -np.ones(3), np.ones(3)
        x, free = box_qp(h, g, lo, hi, np.zeros(3))
        value = 0.5 * x @ h @ x + g @ x
        # brute force: every choice of held-at-lower / held-at-upper / free per component
        best = np.inf
        for held in itertools.product((None, -1.0, 1.0), repeat=3):
            fixed = np.array([v is not None for v in held])
            y = np.array([0.0 if v is None else v for v in held])
            if (~fixed).any():
                f = ~fixed
                y[f] = np.linalg.solve(h[np.ix_(f, f)], -(g[f] + h[np.ix_(f, fixed)] @ y[fixed]))
            if np.all(y >= lo - 1e-12) and np.all(y <= hi + 1e-12):
                best = min(best, 0.5 * y @ h @ y + g @ y)
        assert value == pytest.approx(best, abs=1e-9)
        assert np.all(np.abs(x[~free]) == 1.0)  # the held components sit on a bound


def test_the_floor_tracks_a_feasible_movement_and_beats_saturated_computed_torque():
    feasible = load_movement("ymca", 4)[0]
    short = type(feasible)(feasible.angles[:50], feasible.dt, "ymca-start")
    floor = torque_floor(short, 4, iterations=5)
    assert floor.joint_nrmse < 0.3 * floor.start_joint_nrmse
    assert np.abs(floor.commands).max() <= 1.0
    # an excerpt that asks more torque than the motors have: no exact tracking, but
    # better than computed torque clipped at the limits (the optimiser's start)
    fast = load_movement("md_02.amc@start=3,duration=1.2", 4)[0]
    hard = torque_floor(fast, 4, iterations=5)
    assert np.abs(hard.commands).max() == 1.0  # the limits bind
    assert 0 < hard.joint_nrmse < hard.start_joint_nrmse
