"""ESN contracts: spectral radius, echo states, readouts, lockstep runs, noise streams,
persistence."""

import copy

import numpy as np
import pytest
from skinny_mj.controllers.esn import ESN, ESNConfig, run_generators, spectral_radius
from skinny_mj.controllers.readout import ridge_solve


def _inputs(n_runs=1, n_steps=60, n_in=3, seed=0):
    return np.random.default_rng(seed).uniform(-1, 1, (n_runs, n_steps, n_in))


@pytest.mark.parametrize("n, radius", [(50, 0.5), (200, 0.1), (600, 0.9)])
def test_spectral_radius_is_as_set(n, radius):
    esn = ESN(ESNConfig(2, 1, n_reservoir=n, spectral_radius=radius), n_runs=2, seed=1)
    for w in esn.W:
        assert np.max(np.abs(np.linalg.eigvals(w))) == pytest.approx(radius, rel=1e-6)
        assert np.count_nonzero(w) / n**2 == pytest.approx(min(1, 10 / n), rel=0.3)


def test_echo_state_property_two_initial_states_converge():
    esn = ESN(ESNConfig(3, 1, n_reservoir=100, spectral_radius=0.8), seed=2)
    u = _inputs(n_steps=200)
    esn.x = np.random.default_rng(5).uniform(-1, 1, esn.x.shape)
    _, xa = esn.run(u, noise=False)
    esn.reset()
    _, xb = esn.run(u, noise=False)
    start = np.abs(xa[0, 0] - xb[0, 0]).max()
    end = np.abs(xa[0, -1] - xb[0, -1]).max()
    assert start > 1e-2 and end < 1e-8


def test_pinv_readout_matches_closed_form_and_atanh_round_trips():
    esn = ESN(ESNConfig(3, 2, n_reservoir=40), seed=3)
    _, x = esn.run(_inputs())
    w_true = np.random.default_rng(0).normal(0, 0.3, (2, x.shape[-1]))
    targets = np.tanh(x @ w_true.T)  # reachable through the tanh readout
    esn.fit(x, targets)
    expected = (np.linalg.pinv(x[0]) @ np.arctanh(targets[0])).T
    np.testing.assert_allclose(esn.W_out[0], expected, atol=1e-10)
    np.testing.assert_allclose(esn.readout(x), targets, atol=1e-8)


def test_ridge_matches_normal_equations_and_tends_to_pinv():
    cfg = ESNConfig(3, 2, n_reservoir=30, readout="ridge", ridge_lambda=0.5,
                    readout_activation="identity")
    esn = ESN(cfg, seed=4)
    _, x = esn.run(_inputs(n_steps=100))
    y = np.random.default_rng(1).normal(size=(1, 100, 2))
    esn.fit(x, y)
    m = x[0]
    closed = np.linalg.solve(m.T @ m + 0.5 * np.eye(m.shape[1]), m.T @ y[0])
    np.testing.assert_allclose(esn.W_out[0], closed.T, atol=1e-10)
    pinv = np.linalg.pinv(m) @ y[0]
    far = np.abs(ridge_solve(m, y[0], 1e-2) - pinv).max()
    near = np.abs(ridge_solve(m, y[0], 1e-9) - pinv).max()
    assert near < 1e-4 < far


def test_targets_beyond_one_are_clipped_before_atanh():
    esn = ESN(ESNConfig(3, 1, n_reservoir=20), seed=5)
    _, x = esn.run(_inputs())
    esn.fit(x, np.full((1, x.shape[1], 1), 1.7))
    assert np.all(np.isfinite(esn.W_out))
    np.testing.assert_allclose(esn.readout(x), 0.99, atol=1e-6)


@pytest.mark.parametrize("connectivity", [None, 0.5])  # sparse and dense reservoir paths
def test_lockstep_runs_equal_single_runs(connectivity):
    cfg = ESNConfig(3, 2, n_reservoir=80, noise_level=0.2, connectivity=connectivity)
    n_runs = 3
    batch = ESN(cfg, n_runs=n_runs, seed=11)
    u = _inputs(n_runs=n_runs, n_steps=300)  # > one noise block
    yb, xb = batch.run(u)
    batch.fit(xb, np.tanh(xb[..., :2]))
    yb2, _ = batch.run(u)
    for r, gen in enumerate(run_generators(11, n_runs)):
        single = ESN(cfg, n_runs=1, rngs=[gen])
        ys, xs = single.run(u[r : r + 1])
        single.fit(xs, np.tanh(xs[..., :2]))
        ys2, _ = single.run(u[r : r + 1])
        np.testing.assert_allclose(ys[0], yb[r], rtol=0, atol=1e-12)
        np.testing.assert_allclose(ys2[0], yb2[r], rtol=0, atol=1e-12)
    assert not np.allclose(yb2[0], yb2[1])  # runs really differ


def test_lockstep_steps_equal_single_steps_bitwise():
    # the control loop's path: step() with a sparse reservoir, noise across a block edge
    cfg = ESNConfig(3, 2, n_reservoir=80, noise_level=0.2)
    n_runs = 3
    u = _inputs(n_runs=n_runs, n_steps=300)
    batch = ESN(cfg, n_runs=n_runs, seed=13)
    yb = np.stack([batch.step(u[:, t]) for t in range(u.shape[1])], axis=1)
    for r, gen in enumerate(run_generators(13, n_runs)):
        single = ESN(cfg, n_runs=1, rngs=[gen])
        ys = np.stack([single.step(u[r : r + 1, t]) for t in range(u.shape[1])], axis=1)
        np.testing.assert_array_equal(ys[0], yb[r])
        np.testing.assert_array_equal(single.x[0], batch.x[r])


@pytest.mark.parametrize("leak_rate, n_runs, dtype", [(1.0, 1, "float64"), (0.6, 3, "float64"),
                                                      (0.6, 1, "float32")])
def test_run_equals_stepping(leak_rate, n_runs, dtype):
    cfg = ESNConfig(3, 2, n_reservoir=60, noise_level=0.1, leak_rate=leak_rate, dtype=dtype)
    u = _inputs(n_runs=n_runs, n_steps=300)
    ran, stepped = ESN(cfg, n_runs=n_runs, seed=14), ESN(cfg, n_runs=n_runs, seed=14)
    ran.W_out[:] = stepped.W_out[:] = np.random.default_rng(2).normal(0, 0.1, ran.W_out.shape)
    y_run, x_run = ran.run(u)
    y_step = np.stack([stepped.step(u[:, t]) for t in range(u.shape[1])], axis=1)
    atol = 1e-12 if dtype == "float64" else 1e-5
    np.testing.assert_allclose(y_run, y_step, rtol=0, atol=atol)
    np.testing.assert_allclose(x_run[:, -1], stepped.extended, rtol=0, atol=atol)
    np.testing.assert_allclose(ran.x, stepped.x, rtol=0, atol=atol)


@pytest.mark.parametrize("kind, dtype", [("uniform", "float64"), ("gaussian", "float64"),
                                         ("uniform", "float32")])
def test_noise_is_each_runs_own_stream_in_blocks(kind, dtype):
    # W = 0 and W_in = 0: the state is the noise alone, nu(t) = x(t)
    cfg = ESNConfig(1, 1, n_reservoir=30, spectral_radius=0.0, input_scaling=0.0,
                    noise_level=0.2, noise_kind=kind, dtype=dtype)
    gens = run_generators(15, 2)
    esn = ESN(cfg, n_runs=2, rngs=gens)
    twins = [copy.deepcopy(g) for g in gens]  # the streams right after the weights
    _, x = esn.run(np.zeros((2, 200, 1)))
    stepped = np.empty((2, 100, 30), dtype)
    for t in range(100):
        esn.step(np.zeros((2, 1)))
        stepped[:, t] = esn.x
    for r, g in enumerate(twins):
        draw = g.random if kind == "uniform" else g.standard_normal
        blocks = [draw((256, 30)) for _ in range(2)]  # B = 256 steps a block, per run
        if kind == "uniform":
            blocks = [b - 0.5 for b in blocks]
        expected = (np.concatenate(blocks) * 0.2).astype(dtype)
        np.testing.assert_array_equal(x[r, :, :30], expected[:200])
        np.testing.assert_array_equal(stepped[r], expected[200:300])


def test_one_run_split_from_a_lockstep_esn_continues_its_noise():
    from skinny_mj.training.loop import esn_run  # reads _noise_buf as (B, R, N)

    cfg = ESNConfig(3, 2, n_reservoir=40, noise_level=0.2)
    u = _inputs(n_runs=3, n_steps=400)
    batch = ESN(cfg, n_runs=3, seed=16)
    batch.run(u[:, :100])
    one = esn_run(batch, 1)
    y_one, _ = one.run(u[1:2, 100:])
    y_batch, _ = batch.run(u[:, 100:])
    np.testing.assert_array_equal(y_one[0], y_batch[1])


@pytest.mark.parametrize("n_reservoir, dtype, feedback", [
    (80, "float64", False),  # sparse W (density 1/8), the driven run path
    (20, "float32", True),   # dense W, output feedback
])
def test_select_continues_the_chosen_runs_bit_for_bit(n_reservoir, dtype, feedback):
    """select() copies runs out of a batch (weights, state, generators, buffered noise):
    the copies continue exactly as those runs do inside the batch, across a noise-block
    boundary, and the batch is left as it was (it continues after the copies)."""
    cfg = ESNConfig(3, 2, n_reservoir=n_reservoir, noise_level=0.2, dtype=dtype,
                    output_feedback=feedback, readout_activation="identity")
    u = _inputs(n_runs=3, n_steps=400)
    batch = ESN(cfg, n_runs=3, seed=21)
    _, x = batch.run(u[:, :100], noise=True)
    batch.fit(x, np.sin(x[..., :2]))  # a nonzero readout, so y is checked too
    for t in range(100, 110):
        batch.step(u[:, t])
    chosen = {(2,): batch.select([2]), (0, 2): batch.select([0, 2])}
    continued = {}
    for runs, part in chosen.items():
        assert part.n_runs == len(runs)
        np.testing.assert_array_equal(part.W_out, batch.W_out[list(runs)])
        ys = [part.step(u[list(runs), t]) for t in range(110, 150)]
        y_run, x_run = part.run(u[list(runs), 150:], noise=True)
        continued[runs] = (np.stack(ys, 1), y_run, x_run, part.x, part.y)
    ys = [batch.step(u[:, t]).copy() for t in range(110, 150)]
    y_run, x_run = batch.run(u[:, 150:], noise=True)
    reference = (np.stack(ys, 1), y_run, x_run, batch.x, batch.y)
    for runs, got in continued.items():
        for a, b in zip(got, reference, strict=True):
            np.testing.assert_array_equal(a, b[list(runs)])
    with pytest.raises(ValueError):
        batch.select([3])


def test_gaussian_and_uniform_noise_have_the_documented_spread():
    for kind, std in [("uniform", 0.2 / np.sqrt(12)), ("gaussian", 0.2)]:
        cfg = ESNConfig(1, 1, n_reservoir=200, spectral_radius=0.0, noise_level=0.2,
                        noise_kind=kind, input_scaling=0.0)
        esn = ESN(cfg, seed=6)
        _, x = esn.run(np.zeros((1, 100, 1)))
        assert np.std(x[0, :, :200]) == pytest.approx(std, rel=0.05)
        if kind == "uniform":
            assert np.abs(x[0, :, :200]).max() <= 0.1


def test_output_feedback_teacher_forcing():
    cfg = ESNConfig(1, 1, n_reservoir=30, output_feedback=True, readout_activation="identity")
    esn = ESN(cfg, seed=7)
    u = _inputs(n_steps=20, n_in=1)
    teacher = np.sin(np.arange(20))[None, :, None] * 0.5
    _, x_forced = esn.run(u, noise=False, teacher=teacher)
    assert esn.y[0, 0] == teacher[0, -1, 0]
    esn.reset()
    _, x_free = esn.run(u, noise=False)
    assert np.allclose(x_forced[0, 0], x_free[0, 0])  # same first step (y = 0)
    assert not np.allclose(x_forced[0, 5], x_free[0, 5])


def test_divergence_detection_and_save_load(tmp_path):
    esn = ESN(ESNConfig(3, 2, n_reservoir=25, noise_level=0.1), n_runs=3, seed=8)
    _, x = esn.run(_inputs(n_runs=3))
    esn.fit(x, np.tanh(x[..., :2]))
    assert not esn.is_diverged().any()
    path = tmp_path / "model.npz"
    esn.save(path)
    loaded = ESN.load(path)
    u = _inputs(n_runs=3, seed=1)
    y1, _ = esn.run(u, noise=False)
    y2, _ = loaded.run(u, noise=False)
    np.testing.assert_array_equal(y1, y2)
    assert loaded.cfg == esn.cfg
    esn.x[1] = 1.0
    esn.W_out[2, 0, 0] = np.nan
    reasons = esn.diverged()
    assert reasons[0] is None and "saturated" in reasons[1] and "NaN" in reasons[2]
    np.testing.assert_array_equal(esn.is_diverged(), [False, True, True])


def test_float32_runs():
    esn = ESN(ESNConfig(3, 2, n_reservoir=20, dtype="float32"), seed=9)
    y, x = esn.run(_inputs())
    assert y.dtype == np.float32 and x.dtype == np.float32


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"n_reservoir": 0}, "reservoir size"),
        ({"spectral_radius": -0.1}, "spectral radius"),
        ({"noise_level": -1.0}, "noise level"),
        ({"noise_kind": "pink"}, "noise kind"),
        ({"readout": "lasso"}, "readout"),
        ({"readout_activation": "relu"}, "readout activation"),
    ],
)
def test_bad_config_reads_well(kwargs, words):
    with pytest.raises(ValueError, match=words):
        ESNConfig(2, 1, **kwargs)


def test_spectral_radius_helper_large_matrix_uses_arpack():
    w = np.diag(np.linspace(-0.3, 0.7, 600))
    assert spectral_radius(w) == pytest.approx(0.7, rel=1e-8)


@pytest.mark.parametrize("shape", [(2, 300, 25), (1, 40, 40), (2, 12, 30), (2, 30, 80)])
@pytest.mark.parametrize("deficient", ["columns", "rows"])
def test_pinv_solve_is_numpys_pinv_including_rank_deficient(shape, deficient):
    """The QR readout solve gives pinv(M) @ S: tall, square and wide M, rank-deficient
    by a duplicated and an all-zero column, or (the wide case's own) a duplicated and
    an all-zero row, whose null space the minimum-norm solution must leave out."""
    from skinny_mj.controllers.readout import pinv_solve

    rng = np.random.default_rng(sum(shape))
    m = rng.normal(size=shape)
    if deficient == "columns":
        m[..., 3] = m[..., 1]
        m[..., 5] = 0.0
    else:
        m[:, 3] = m[:, 1]
        m[:, 5] = 0.0
    s = rng.normal(size=(*shape[:2], 3))
    np.testing.assert_allclose(pinv_solve(m, s), np.linalg.pinv(m) @ s, rtol=0, atol=1e-10)


def test_pinv_solve_takes_both_branches_and_both_equal_pinv():
    """Well-conditioned M: the triangular solve; rank-deficient M (a duplicated
    column): the SVD with NumPy's cutoff. Both give pinv(M) @ S."""
    from skinny_mj.controllers import readout as readout_module

    rng = np.random.default_rng(7)
    m = rng.normal(size=(2, 200, 30))
    m[1, :, 4] = m[1, :, 2]
    s = rng.normal(size=(2, 200, 2))
    calls = []
    svd = np.linalg.svd

    def counting_svd(*args, **kwargs):
        calls.append(1)
        return svd(*args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(readout_module.np.linalg, "svd", counting_svd)
        got = readout_module.pinv_solve(m, s)
    assert len(calls) == 1  # only the nearly rank-deficient run needed the SVD
    np.testing.assert_allclose(got[0], np.linalg.pinv(m[0]) @ s[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(got[1], np.linalg.pinv(m[1]) @ s[1], rtol=0, atol=1e-12)


def test_step_writes_the_extended_state_where_asked_and_checks_the_array():
    cfg = ESNConfig(3, 2, n_reservoir=30)
    a, b = ESN(cfg, n_runs=2, seed=4), ESN(cfg, n_runs=2, seed=4)
    u = np.random.default_rng(0).uniform(-1, 1, (5, 2, 3))
    record = np.zeros((5, 2, cfg.n_extended))
    for t in range(5):
        np.testing.assert_array_equal(a.step(u[t]), b.step(u[t], out_extended=record[t]))
        np.testing.assert_array_equal(a.extended, record[t])
    assert np.shares_memory(b.extended, record[4])
    for bad in (np.zeros((2, cfg.n_extended), np.float32), np.zeros((2, cfg.n_extended + 1)),
                np.zeros((cfg.n_extended, 2)).T):
        with pytest.raises(ValueError):
            b.step(u[0], out_extended=bad)


def test_pinv_factors_reused_equal_fresh_fits():
    """PinvFactors of fixed states solves any targets like a fresh pinv, for all runs
    or a subset, and fit(factors=...) refuses factors of other states."""
    from skinny_mj.controllers.readout import PinvFactors

    esn = ESN(ESNConfig(3, 2, n_reservoir=40), n_runs=3, seed=5)
    _, x = esn.run(np.random.default_rng(1).uniform(-1, 1, (3, 120, 3)), noise=False)
    factors = PinvFactors(x)
    rng = np.random.default_rng(2)
    for _ in range(3):
        s = rng.normal(size=(3, 120, 2))
        np.testing.assert_allclose(factors.solve(s), np.linalg.pinv(x) @ s, rtol=0, atol=1e-10)
        np.testing.assert_allclose(factors.solve(s[[0, 2]], np.array([0, 2])),
                                   np.linalg.pinv(x[[0, 2]]) @ s[[0, 2]], rtol=0, atol=1e-10)
    targets = np.tanh(rng.normal(size=(3, 120, 2)))
    fresh = ESN(esn.cfg, n_runs=3, seed=5)
    fresh.fit(x, targets)
    esn.fit(x, targets, factors=factors)
    np.testing.assert_allclose(esn.W_out, fresh.W_out, rtol=0, atol=1e-10)
    with pytest.raises(ValueError):
        esn.fit(x[:, 10:], targets[:, 10:], factors=factors)


@pytest.mark.parametrize("readout", ["tanh", "identity"])
@pytest.mark.parametrize("noise", [True, False])
def test_stepper_gives_the_steps_numbers_bit_for_bit(readout, noise):
    cfg = ESNConfig(3, 2, n_reservoir=40, readout_activation=readout)
    a, b = ESN(cfg, n_runs=3, seed=4), ESN(cfg, n_runs=3, seed=4)
    a.W_out[:] = b.W_out[:] = np.random.default_rng(1).normal(0, 0.3, a.W_out.shape)
    u = np.random.default_rng(0).uniform(-1, 1, (300, 3, 3))  # crosses a noise block
    record, ys = np.zeros((300, 3, cfg.n_extended)), np.zeros((300, 3, 2))
    b.inputs_of(record)[:] = u
    step = b.stepper(noise)
    for t in range(300):
        want = a.step(u[t], noise=noise)
        step(record[t], ys[t])
        np.testing.assert_array_equal(ys[t], want)
        np.testing.assert_array_equal(record[t], a.extended)
    np.testing.assert_array_equal(a.x, b.x)
    assert a._noise_pos == b._noise_pos
