"""The ESN state loop's floor (``skinny_mj.cli.bench_floor``) computes what ``ESN.run`` does."""

import numpy as np
import pytest
from scipy.sparse._sparsetools import csc_matvec, csr_matvec
from skinny_mj.controllers.esn import ESN, ESNConfig

from skinny_mj.cli.bench_floor import (
    control_step_floor,
    esn_state_floor,
    floor_lines,
    package_lines_per_step,
    sparse_tanh_loop,
)


def _esn_and_inputs(n_res: int, connectivity=None):
    cfg = ESNConfig(n_inputs=3, n_outputs=2, n_reservoir=n_res, connectivity=connectivity)
    return ESN(cfg, seed=4), np.random.default_rng(5).uniform(-1, 1, (40, 3))


@pytest.mark.parametrize("n_res", [50, 200])
def test_floor_gives_esn_run_states_bit_for_bit(n_res):
    esn, inputs = _esn_and_inputs(n_res)
    states = esn.run(inputs[None], noise=False)[1][0, :, :n_res]
    floor = esn_state_floor(esn, inputs)
    assert np.array_equal(floor(), states)
    assert np.array_equal(floor(), states)  # from x = 0 again on every call


def test_csc_kernel_adds_the_same_terms_in_the_same_order_as_csr():
    esn, inputs = _esn_and_inputs(200)
    csr = esn.sparse_reservoir
    w_in = esn.W_in[0]
    u1 = np.concatenate([inputs, np.ones((len(inputs), 1))], axis=1)
    by_csr = sparse_tanh_loop(csr_matvec, csr, w_in, u1)()
    assert np.array_equal(sparse_tanh_loop(csc_matvec, csr.tocsc(), w_in, u1)(), by_csr)
    per_step = sparse_tanh_loop(csr_matvec, csr, w_in, u1, per_step_input=True)()
    assert np.max(np.abs(per_step - by_csr)) < 1e-12  # the drive's sum grouped otherwise
    assert not np.allclose(by_csr, 0.0)


def test_no_floor_for_a_dense_reservoir_and_no_line_without_one():
    esn, inputs = _esn_and_inputs(20, connectivity=0.5)
    assert esn.sparse_reservoir is None and esn_state_floor(esn, inputs) is None
    lines = floor_lines([{"N": 200, "reservoirpy_over_floor": 4.5},
                         {"N": 1000, "reservoirpy_over_floor": float("nan")}, {"skipped": "x"}])
    assert len(lines) == 1 and "N=200" in lines[0] and "4.5" in lines[0]


def test_control_step_floor_runs_the_physics_once_and_none_when_dense():
    calls = []
    esn = ESN(ESNConfig(n_inputs=3, n_outputs=2, n_reservoir=50), n_runs=3, seed=1)
    floor = control_step_floor(esn, lambda: calls.append(1), 300)  # crosses a noise block
    floor()
    assert calls == [1]
    dense, _ = _esn_and_inputs(20, connectivity=0.5)
    assert control_step_floor(dense, lambda: None, 5) is None


def test_package_lines_per_step_counts_only_the_package_per_step():
    assert package_lines_per_step(lambda k: sum(range(k)), 10) == 0.0  # no package code
    esn = ESN(ESNConfig(n_inputs=3, n_outputs=2, n_reservoir=20), seed=1)
    u = np.zeros((1, 3))

    def steps(k: int) -> None:
        for _ in range(k):
            esn.step(u, noise=False)

    per_step = package_lines_per_step(steps, 5)
    assert per_step > 5 and per_step == package_lines_per_step(steps, 9)  # the same each step
