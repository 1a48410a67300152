"""Echo state network (Jaeger) with a leading run axis.

R independent networks ("runs", each with its own weights drawn from its own
``Generator``) step in lockstep: states are ``(R, N)``, weights ``(R, ...)``. Run ``r``
of a batch produces exactly the numbers of a single network built from run ``r``'s
generator, so batching is a speed-up, never a change of the experiment.

Update (Jaeger's toolbox, SPEC §3/§5)::

    x(t) = (1 - a) x(t-1) + a tanh(W_in [u(t); 1] + W x(t-1) + W_back y(t-1)) + nu(t)
    y(t) = f_out(W_out [x(t); u(t); 1])

with leak rate ``a`` (1 = the thesis), reservoir noise ``nu`` uniform in
``[-level/2, level/2]`` (default; "0.2 effectively adds 10 % noise") or Gaussian with
std ``level``, and ``f_out`` = tanh (targets fitted through atanh) or identity.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from skinny_mj.controllers._io import atomic_path
from skinny_mj.controllers.readout import PinvFactors, solve_readout
from skinny_mj.controllers.reservoir import ESNConfig, draw_weights, run_generators, spectral_radius

# The hyper-parameters and the weight draw live in skinny_mj.controllers.reservoir, the readout
# solvers in skinny_mj.controllers.readout; these names stay importable from here.
__all__ = ["ESN", "ESNConfig", "read_metadata", "run_generators", "spectral_radius"]

if TYPE_CHECKING:
    import scipy.sparse

_NOISE_BLOCK = 256  # noise is drawn per run in blocks of this many steps
_SPARSE_BELOW = 0.25  # use a block-diagonal sparse matrix below this connectivity


class ESN:
    """R echo state networks stepping in lockstep.

    Parameters
    ----------
    cfg : ESNConfig
    n_runs : R, number of independent networks.
    seed : seeds the per-run generators (``run_generators(seed, n_runs)``).
    rngs : alternatively one Generator per run (weights, then reservoir noise).

    Attributes
    ----------
    W : (R, N, N) reservoir weights.  W_in : (R, N, n_in + 1), last column = bias.
    W_back : (R, N, n_out).  W_out : (R, n_out, D) readout, zero until fitted.
    x : (R, N) reservoir state.  y : (R, n_out) last output (or teacher).
    extended : (R, D) the last [x; u; bias] (what ``fit`` regresses on).
    """

    def __init__(
        self,
        cfg: ESNConfig,
        n_runs: int = 1,
        seed: int | None = None,
        rngs: Sequence[np.random.Generator] | None = None,
    ) -> None:
        if n_runs < 1:
            raise ValueError(f"n_runs must be >= 1, got {n_runs}")
        if None in (cfg.n_inputs, cfg.n_outputs, cfg.noise_level):
            raise ValueError("a network needs n_inputs, n_outputs and noise_level set, got "
                             f"{cfg.n_inputs}, {cfg.n_outputs}, {cfg.noise_level}")
        if rngs is None:
            rngs = run_generators(seed, n_runs)
        if len(rngs) != n_runs:
            raise ValueError(f"got {len(rngs)} generators for {n_runs} runs")
        self.cfg = cfg
        self.n_runs = n_runs
        self.rngs = list(rngs)
        self.dtype = np.dtype(cfg.dtype)
        drawn = [draw_weights(cfg, g) for g in self.rngs]
        self._set_weights(
            np.stack([d["W"] for d in drawn]),
            np.stack([d["W_in"] for d in drawn]),
            np.stack([d["W_back"] for d in drawn]),
            np.zeros((n_runs, cfg.n_outputs, cfg.n_extended)),
        )
        self.reset()

    # -- weights -------------------------------------------------------------------
    def _set_weights(self, w, w_in, w_back, w_out) -> None:
        dt = self.dtype
        self.W, self.W_in = w.astype(dt), w_in.astype(dt)
        self.W_back, self.W_out = w_back.astype(dt), w_out.astype(dt)
        self._sparse = None
        if self.cfg.density < _SPARSE_BELOW:
            # CSR: each output sums its terms from the first column to the last, starting
            # from what the output array holds. SciPy's CSR kernel ran 1-15 % faster than
            # its CSC kernel on the same matrix (benchmarks/esn_floor.py, on an AVX-512
            # Xeon); both add the same terms in the same order: the same bits.
            import scipy.sparse  # here: `skinny experiment NAME --help` needs no SciPy

            a = self._sparse = scipy.sparse.block_diag(
                [scipy.sparse.csr_array(m) for m in self.W], format="csr"
            ).astype(dt)
            a.sort_indices()
            self._kernel_args = (a.shape[0], a.shape[1], a.indptr, a.indices, a.data)
            # SciPy's CSR matrix-vector kernel (what csr_array @ vector calls), if exposed
            self._matvec = getattr(getattr(scipy.sparse, "_sparsetools", None), "csr_matvec",
                                   None)

    def _noise(self) -> np.ndarray:
        """Reservoir noise nu(t) of all runs, (R, N): a view into ``_noise_buf``."""
        if self._noise_pos >= _NOISE_BLOCK:
            self._draw_noise_block()
        self._noise_pos += 1
        return self._noise_buf[self._noise_pos - 1]

    def _draw_noise_block(self) -> None:
        """Refill ``_noise_buf`` (B, R, N) with the next B steps of every run's stream:
        per run, B x N numbers drawn (into a scratch block, or in place when the run's
        slice is contiguous) and scaled in place, the numbers of ``g.random((B, N))``.
        float32 noise is float64 noise rounded (a float32 draw is another stream)."""
        r, n, level = self.n_runs, self.cfg.n_reservoir, self.cfg.noise_level
        buf = getattr(self, "_noise_buf", None)
        if buf is None or buf.shape != (_NOISE_BLOCK, r, n) or buf.dtype != self.dtype:
            buf = self._noise_buf = np.empty((_NOISE_BLOCK, r, n), self.dtype)
        scratch = None
        for run, g in enumerate(self.rngs):
            block = buf[:, run]  # (B, N), contiguous only when R = 1
            out = block
            if not (block.flags.c_contiguous and block.dtype == np.float64):
                if scratch is None:
                    scratch = np.empty((_NOISE_BLOCK, n))
                out = scratch
            if self.cfg.noise_kind == "uniform":  # U[-level/2, level/2)
                g.random(out=out)
                out -= 0.5
            else:
                g.standard_normal(out=out)
            np.multiply(out, level, out=block)  # scaled and, from a scratch block, copied
        self._noise_pos = 0

    # -- verbs ---------------------------------------------------------------------
    def reset(self) -> None:
        """Reservoir state and last output to zero (noise streams continue)."""
        r, cfg = self.n_runs, self.cfg
        self.x = np.zeros((r, cfg.n_reservoir), self.dtype)
        self.y = np.zeros((r, cfg.n_outputs), self.dtype)
        self.extended = np.zeros((r, cfg.n_extended), self.dtype)
        if not hasattr(self, "_noise_pos"):
            self._noise_pos = _NOISE_BLOCK

    def step(
        self, u: np.ndarray, noise: bool = True, feedback: np.ndarray | None = None,
        out_extended: np.ndarray | None = None,
    ) -> np.ndarray:
        """Advance one step.

        Parameters
        ----------
        u : (R, n_in) input.
        noise : add reservoir noise (if the config's level is > 0).
        feedback : (R, n_out) teacher value for y(t-1) (teacher forcing); None uses
            the network's own last output.
        out_extended : optional C-contiguous (R, D) array of the ESN's dtype to hold
            the new extended state (what :attr:`extended` then is), e.g. a row of
            the caller's state record: saves a copy per step.

        Returns
        -------
        y : (R, n_out) output.
        """
        cfg, n_runs, n_res = self.cfg, self.n_runs, self.cfg.n_reservoir
        # The extended state [x; u; bias] is filled in place; u1 = [u; bias] is its tail.
        ext = out_extended
        if ext is None:
            ext = np.empty((n_runs, cfg.n_extended), self.dtype)
        elif ext.shape != (n_runs, cfg.n_extended) or ext.dtype != self.dtype \
                or not ext.flags.c_contiguous:
            raise ValueError(f"out_extended must be a C-contiguous {self.dtype} array of "
                             f"shape {(n_runs, cfg.n_extended)}")
        ext[:, n_res:-1] = np.reshape(u, (n_runs, cfg.n_inputs))
        ext[:, -1] = cfg.bias
        a, pre = self._sparse, np.zeros((n_runs, n_res), self.dtype)
        if a is None:
            pre = np.matmul(self.W, self.x[..., None])[..., 0]
        elif self._matvec is None:  # W x summed from zero, then + W_in u1: bit for bit CSR's
            pre += (a @ np.ascontiguousarray(self.x, self.dtype).reshape(-1)).reshape(pre.shape)
        else:
            self._matvec(*self._kernel_args, np.ascontiguousarray(self.x, self.dtype), pre)
        pre += np.matmul(self.W_in, ext[:, n_res:, None])[..., 0]
        if cfg.output_feedback:
            y_prev = self.y if feedback is None else np.asarray(feedback, self.dtype)
            pre += np.matmul(self.W_back, y_prev[..., None])[..., 0]
        x = np.tanh(pre, out=pre)
        if cfg.leak_rate != 1.0:
            x = (1.0 - cfg.leak_rate) * self.x + cfg.leak_rate * x
        if noise and cfg.noise_level > 0:
            x += self._noise()
        self.x = ext[:, :n_res] = x
        self.extended = ext
        y = np.matmul(self.W_out, ext[..., None])[..., 0]
        self.y = np.tanh(y, out=y) if cfg.readout_activation == "tanh" else y
        return self.y

    def inputs_of(self, extended: np.ndarray) -> np.ndarray:
        """The inputs u (..., n_in) inside extended states ``extended`` (..., D), a view,
        with each state's bias entry set: what a caller fills before :meth:`stepper`'s
        step advances on that state."""
        extended[..., -1] = self.cfg.bias
        return extended[..., self.cfg.n_reservoir:-1]

    def stepper(self, noise: bool = True) -> Callable[[np.ndarray, np.ndarray], None]:
        """:meth:`step` built once for a loop: ``step(ext, y)`` advances one step on
        ``ext`` (R, D), a C-contiguous extended-state row whose inputs and bias are
        already in place (:meth:`inputs_of`), writes the new state into it and the output
        into ``y`` (R, n_out, C-contiguous). The same numbers as :meth:`step` with
        ``out_extended=ext``; :attr:`y` is then ``y`` itself. Without a sparse reservoir,
        with output feedback, a leak or float32 states it is :meth:`step` (the common
        loop is what it speeds up)."""
        cfg, n_res, matvec = self.cfg, self.cfg.n_reservoir, getattr(self, "_matvec", None)
        if matvec is None or cfg.output_feedback or cfg.leak_rate != 1.0 \
                or self.dtype != np.float64:
            def plain(ext: np.ndarray, y: np.ndarray) -> None:
                y[...] = self.step(ext[:, n_res:-1], noise=noise, out_extended=ext)
            return plain
        args, w_in, w_out = self._kernel_args, self.W_in, self.W_out
        shape, add_noise = (self.n_runs, n_res), noise and cfg.noise_level > 0
        tanh_out = cfg.readout_activation == "tanh"

        def step(ext: np.ndarray, y: np.ndarray) -> None:
            pre = np.zeros(shape, self.dtype)  # W x summed from zero, then + W_in [u; 1]
            matvec(*args, np.ascontiguousarray(self.x, self.dtype), pre)
            pre += np.matmul(w_in, ext[:, n_res:, None])[..., 0]
            np.tanh(pre, out=pre)
            if add_noise:  # self._noise(), inline
                if self._noise_pos >= _NOISE_BLOCK:
                    self._draw_noise_block()
                pre += self._noise_buf[self._noise_pos]
                self._noise_pos += 1
            self.x = ext[:, :n_res] = pre
            self.extended, self.y = ext, np.matmul(w_out, ext[..., None], out=y[..., None])[..., 0]
            if tanh_out:
                np.tanh(y, out=y)

        return step

    def run(
        self,
        inputs: np.ndarray,
        noise: bool = True,
        teacher: np.ndarray | None = None,
        washout: int = 0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Drive the networks with ``inputs`` (R, T, n_in) from the current state.

        ``teacher`` (R, T, n_out) forces the fed-back output: step t sees teacher[t-1]
        (the current ``y`` at t = 0), and afterwards ``y`` holds teacher[T-1] so a free
        run can continue. Returns outputs Y (R, T - washout, n_out) and extended
        states X (R, T - washout, D).
        """
        inputs = np.asarray(inputs)
        if teacher is None and not self.cfg.output_feedback and self._sparse is not None:
            return self._run_driven(inputs, noise, washout)
        n_steps = inputs.shape[1]
        ys = np.empty((self.n_runs, n_steps, self.cfg.n_outputs), self.dtype)
        xs = np.empty((self.n_runs, n_steps, self.cfg.n_extended), self.dtype)
        for t in range(n_steps):
            fb = None if teacher is None or t == 0 else teacher[:, t - 1]
            ys[:, t] = self.step(inputs[:, t], noise=noise, feedback=fb)
            xs[:, t] = self.extended
        if teacher is not None:
            self.y = np.asarray(teacher[:, -1], self.dtype).copy()
        return ys[:, washout:], xs[:, washout:]

    def _run_driven(self, inputs: np.ndarray, noise: bool, washout: int
                    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`run` without output feedback: the input drive W_in [u; 1] of every
        step in one product, then a loop of only the sparse reservoir update (+ leak,
        + noise), then the readout of all steps in one product. Equal to stepping up to
        float rounding (~1e-15: the sums are grouped differently).

        The loop allocates nothing: each step's row of ``rows`` (T, R*N) holds the
        drive, the kernel adds W x to it, tanh overwrites it in place, and it is the
        next step's x. With one run, the rows are the reservoir part of the returned
        states themselves (contiguous within a row); with R runs, one copy at the end.
        """
        cfg, n_res = self.cfg, self.cfg.n_reservoir
        n_runs, n_steps, width = self.n_runs, inputs.shape[1], self.n_runs * n_res
        xs = np.empty((n_runs, n_steps, cfg.n_extended), self.dtype)
        xs[:, :, n_res:-1] = inputs
        xs[:, :, -1] = cfg.bias
        if n_runs == 1:
            rows = xs[0, :, :n_res]  # (T, N), each row contiguous
        else:
            rows = np.empty((n_steps, width), self.dtype)
        by_run = rows.reshape(n_steps, n_runs, n_res)  # a view in both cases
        np.matmul(xs[:, :, n_res:], np.swapaxes(self.W_in, 1, 2),
                  out=by_run.transpose(1, 0, 2))  # drive (R, T, N)
        a, kernel_args, matvec = self._sparse, self._kernel_args, self._matvec
        leak = cfg.leak_rate
        if leak != 1.0:
            kept = np.empty(width, self.dtype)
        add_noise = noise and cfg.noise_level > 0
        x = np.ascontiguousarray(self.x, self.dtype).reshape(-1)
        for t in range(n_steps):
            row = rows[t]
            if matvec is None:
                row += a @ x
            else:
                matvec(*kernel_args, x, row)
            np.tanh(row, out=row)
            if leak != 1.0:  # (1 - a) x + a tanh(.), as in step
                np.multiply(x, 1.0 - leak, out=kept)
                row *= leak
                row += kept
            if add_noise:
                row_by_run = by_run[t]
                row_by_run += self._noise()
            x = row
        if n_runs > 1:
            xs[:, :, :n_res] = by_run.transpose(1, 0, 2)
        self.x = x.reshape(n_runs, n_res).copy()
        self.extended = xs[:, -1].copy()
        ys = self.readout(xs)
        self.y = ys[:, -1].copy()
        return ys[:, washout:], xs[:, washout:]

    def _activate(self, z: np.ndarray) -> np.ndarray:
        return np.tanh(z) if self.cfg.readout_activation == "tanh" else z

    def readout(self, states: np.ndarray) -> np.ndarray:
        """Outputs (R, T, n_out) of the current readout for extended states (R, T, D)."""
        return self._activate(np.einsum("rtd,rod->rto", states, self.W_out))

    def fit(
        self,
        states: np.ndarray,
        targets: np.ndarray,
        washout: int = 0,
        runs: np.ndarray | None = None,
        factors: PinvFactors | None = None,
    ) -> None:
        """Fit W_out per run: (W_out)^T = M^+ S (pinv) or ridge via Cholesky.

        Parameters
        ----------
        states : (R, T, D) extended states M.
        targets : (R, T, n_out) desired outputs (through atanh for a tanh readout).
        washout : leading steps to drop.
        runs : (R,) bool, which runs to refit (others keep their readout).
        factors : optional :class:`PinvFactors` of these same states (after the
            washout), reused across fits (pinv readout only).
        """
        selected = np.ones(self.n_runs, bool) if runs is None else np.asarray(runs, bool)
        idx = np.flatnonzero(selected)
        if idx.size == 0:
            return
        w_t = solve_readout(self.cfg, np.asarray(states, np.float64)[:, washout:],
                            np.asarray(targets, np.float64)[:, washout:], idx, factors)
        self.W_out[idx] = np.swapaxes(w_t, 1, 2).astype(self.dtype)

    # -- health and persistence ----------------------------------------------------
    def diverged(self) -> list[str | None]:
        """Per run: None if healthy, else why it diverged (non-finite or saturated)."""
        reasons: list[str | None] = []
        for r in range(self.n_runs):
            if not (np.all(np.isfinite(self.x[r])) and np.all(np.isfinite(self.W_out[r]))):
                reasons.append("non-finite reservoir state or readout (NaN/inf)")
            elif np.mean(np.abs(self.x[r])) > 0.999:
                reasons.append(f"saturated reservoir: mean |x| = {np.mean(np.abs(self.x[r])):.4f}")
            else:
                reasons.append(None)
        return reasons

    def is_diverged(self) -> np.ndarray:
        """(R,) bool: NaN/inf in state or readout, or saturation (mean |x| > 0.999)."""
        return np.array([reason is not None for reason in self.diverged()])

    # -- selection and persistence -------------------------------------------------
    @property
    def sparse_reservoir(self) -> scipy.sparse.csr_array | None:
        """Every run's W as one block-diagonal CSR matrix (R N, R N), the one ``step``
        multiplies by; None when W is dense (connectivity >= 0.25)."""
        return self._sparse

    def select(self, runs: Sequence[int]) -> ESN:
        """A new ESN of the runs ``runs`` (indices, in that order), holding copies of
        their weights, state (x, y, extended), generators and buffered noise: stepping it
        gives, bit for bit, what those runs give inside this batch (left unchanged)."""
        idx = np.asarray(runs, dtype=np.intp).reshape(-1)
        if idx.size == 0 or np.any((idx < 0) | (idx >= self.n_runs)):
            raise ValueError(f"runs must be indices in [0, {self.n_runs}), got {list(runs)}")
        out = self._assemble(self.cfg, [copy.deepcopy(self.rngs[i]) for i in idx], self.W[idx],
                             self.W_in[idx], self.W_back[idx], self.W_out[idx])
        out.x, out.y, out.extended = self.x[idx], self.y[idx], self.extended[idx]  # copies
        out._noise_pos = self._noise_pos
        if hasattr(self, "_noise_buf"):
            out._noise_buf = self._noise_buf[:, idx]  # (B, r, N), a C-contiguous copy
        return out

    @classmethod
    def _assemble(cls, cfg: ESNConfig, rngs: list[np.random.Generator], w: np.ndarray,
                  w_in: np.ndarray, w_back: np.ndarray, w_out: np.ndarray) -> ESN:
        """An ESN of these weights (R leading) and generators, in its reset state."""
        esn = cls.__new__(cls)
        esn.cfg, esn.n_runs, esn.dtype = cfg, len(rngs), np.dtype(cfg.dtype)
        esn.rngs = rngs
        esn._set_weights(w, w_in, w_back, w_out)
        esn.reset()
        return esn

    def save(self, path: str | Path, metadata: dict | None = None) -> None:
        """Write weights + config JSON (+ a JSON ``metadata`` dict, e.g. the plant the
        network was trained on) to an .npz (no pickle), atomically."""
        with atomic_path(Path(path)) as tmp, open(tmp, "wb") as fh:
            np.savez(
                fh, config=np.array(json.dumps(asdict(self.cfg))), W=self.W, W_in=self.W_in,
                W_back=self.W_back, W_out=self.W_out, x=self.x, y=self.y,
                metadata=np.array(json.dumps(metadata or {})),
            )

    @classmethod
    def load(cls, path: str | Path, seed: int | None = None) -> ESN:
        """Read an .npz written by :meth:`save`; ``seed`` seeds future noise."""
        with np.load(Path(path), allow_pickle=False) as data:
            cfg = ESNConfig(**json.loads(str(data["config"])))
            arrays = {k: data[k] for k in ("W", "W_in", "W_back", "W_out", "x", "y")}
        esn = cls._assemble(cfg, run_generators(seed, arrays["W"].shape[0]), arrays["W"],
                            arrays["W_in"], arrays["W_back"], arrays["W_out"])
        esn.x, esn.y = arrays["x"].astype(esn.dtype), arrays["y"].astype(esn.dtype)
        return esn


def read_metadata(path: str | Path) -> dict:
    """The ``metadata`` dict saved with a network by :meth:`ESN.save` ({} if none)."""
    with np.load(Path(path), allow_pickle=False) as data:
        return json.loads(str(data["metadata"])) if "metadata" in data.files else {}
