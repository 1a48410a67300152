"""Floors ``skinny bench`` times beside its figures: the least any implementation pays.

The floor of an ESN state loop is the least any loop built on SciPy's sparse product pays.
``skinny bench`` times it beside ``ESN.run`` and reservoirpy's ``Reservoir.run``, so that
reservoirpy's time over the floor (the largest speed-up over reservoirpy that any loop on
the same product and NumPy's tanh can reach) is measured in the same run as the ratio
itself; ``benchmarks/esn_floor.py`` times it beside other products. The floor of a control
step starts from the bare physics of R separate robots (:func:`separate_robots`); its full
floor (:func:`control_step_floor`) adds the reservoir's own per-step work to the physics.
:func:`package_lines_per_step` counts the package's Python lines a control step runs.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np


def sparse_tanh_loop(kernel: Callable, w, w_in: np.ndarray, u1: np.ndarray,
                     per_step_input: bool = False) -> Callable[[], np.ndarray]:
    """A callable returning the states (T, N) of x(t) = tanh(W_in u1(t) + W x(t-1)) from
    x = 0, with nothing but SciPy's kernel and an in-place tanh per step.

    Parameters
    ----------
    kernel : SciPy's ``csr_matvec`` or ``csc_matvec`` (adds W x to its output in place).
    w : W (N, N), a SciPy sparse array in that kernel's format.
    w_in : (N, K) input weights, the bias weights included.
    u1 : (T, K) inputs with the bias input.
    per_step_input : one ``W_in u1(t)`` product per step (as reservoirpy does) instead of
        the input drive of all steps in one product beforehand (as ``ESN.run`` does).
    """
    args = (w.shape[0], w.shape[1], w.indptr, w.indices, w.data)
    n_steps, n_units = u1.shape[0], w.shape[0]

    def loop() -> np.ndarray:
        rows = np.empty((n_steps, n_units))
        if not per_step_input:
            np.matmul(u1, w_in.T, out=rows)
        x = np.zeros(n_units)
        for t in range(n_steps):
            row = rows[t]
            if per_step_input:
                np.matmul(w_in, u1[t], out=row)
            kernel(*args, x, row)
            np.tanh(row, out=row)
            x = row
        return rows

    return loop


def esn_state_floor(esn, inputs: np.ndarray) -> Callable[[], np.ndarray] | None:
    """:func:`sparse_tanh_loop` on one-run ``esn``'s own weights (CSR, the kernel ``ESN``
    uses) for ``inputs`` (T, n_in): the same states ``esn.run`` gives from its reset state,
    bit for bit. None when the ESN's W is dense."""
    if esn.sparse_reservoir is None:
        return None
    from scipy.sparse._sparsetools import csr_matvec

    u1 = np.concatenate([inputs, np.full((len(inputs), 1), esn.cfg.bias)], axis=1)
    return sparse_tanh_loop(csr_matvec, esn.sparse_reservoir, esn.W_in[0], u1)


def floor_lines(esn_figures: list[dict]) -> list[str]:
    """Lines of ``skinny bench``'s table: reservoirpy over the floor, per N (the most any
    loop on SciPy's product and NumPy's tanh can gain over reservoirpy)."""
    lines = []
    for fig in esn_figures:
        if np.isfinite(fig.get("reservoirpy_over_floor", np.nan)):
            label = f"  reservoirpy over floor N={fig['N']}"
            lines.append(f"{label:<30} {fig['reservoirpy_over_floor']:>10.3g} {'-':>8}  "
                         "(the most any loop on SciPy's product can reach)")
    return lines


def separate_robots(plant) -> tuple:
    """R separate one-robot ``MjData`` posed as ``plant`` (a ``BatchPlant``) starts, for
    ``mujoco.rollout``: (the one-robot model, one ``MjData``, (R, S) full-physics states)."""
    import mujoco

    from skinny_mj.plant.model import load_model

    one, spec = load_model(plant.body), mujoco.mjtState.mjSTATE_FULLPHYSICS
    data = mujoco.MjData(one)
    states = np.empty((plant.n_runs, mujoco.mj_stateSize(one, spec)))
    plant.layout.set_joint_angles(data, plant.setup.start_rad)
    mujoco.mj_forward(one, data)
    for r in range(plant.n_runs):
        mujoco.mj_getState(one, data, states[r], spec)
    return one, data, states


def control_step_floor(esn, physics: Callable[[], object], n_steps: int
                       ) -> Callable[[], None] | None:
    """The least a control step of ``esn``'s R runs pays: ``physics()`` (the bare physics
    of the ``n_steps`` steps, in C), then per step the sparse product W x of every run
    (SciPy's kernel on the block-diagonal CSR matrix), an in-place tanh and the reservoir
    noise added, the noise drawn in blocks as ``ESN`` draws it. No input product, no
    readout, no feedback, no bookkeeping. None when the ESN's W is dense."""
    a = esn.sparse_reservoir
    if a is None:
        return None
    from scipy.sparse._sparsetools import csr_matvec

    args = (a.shape[0], a.shape[1], a.indptr, a.indices, a.data)
    block, n_res = 256, esn.cfg.n_reservoir
    rngs = [np.random.default_rng(r) for r in range(esn.n_runs)]
    noise = np.empty((block, esn.n_runs, n_res))
    drawn = np.empty((block, n_res))

    def loop() -> None:
        physics()
        x = np.zeros(a.shape[0])
        for t in range(n_steps):
            if t % block == 0:
                for r, g in enumerate(rngs):
                    g.random(out=drawn)
                    np.subtract(drawn, 0.5, out=drawn)
                    np.multiply(drawn, esn.cfg.noise_level, out=noise[:, r])
            row = np.zeros(a.shape[0])
            csr_matvec(*args, x, row)
            np.tanh(row, out=row)
            row += noise[t % block].reshape(-1)
            x = row

    return loop


def package_lines_per_step(run_steps: Callable[[int], object], n_steps: int) -> float:
    """Lines of the package's own Python (``skinny_mj`` and its controllers) executed per
    step by ``run_steps(k)`` (a control loop of k steps): the lines of ``n_steps`` steps less
    those of one step, over ``n_steps - 1``, so set-up and clean-up do not count."""
    import skinny_mj
    import skinny_mj.controllers

    roots = tuple(str(Path(m.__file__).parent) + "/" for m in (skinny_mj, skinny_mj.controllers))
    counts = [0]

    def tracer(frame, event, arg):
        if not frame.f_code.co_filename.startswith(roots):
            return None
        if event == "line":
            counts[0] += 1
        return tracer

    def lines(k: int) -> int:
        counts[0] = 0
        previous = sys.gettrace()
        sys.settrace(tracer)
        try:
            run_steps(k)
        finally:
            sys.settrace(previous)
        return counts[0]

    one = lines(1)
    return (lines(n_steps) - one) / (n_steps - 1)
