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

import json
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from controllers._io import atomic_path

try:  # SciPy's CSC matrix-vector kernel (what csc_array @ vector calls)
    from scipy.sparse._sparsetools import csc_matvec as _csc_matvec
except ImportError:  # pragma: no cover - other SciPy layouts
    _csc_matvec = None

_NOISE_KINDS = ("uniform", "gaussian")
_ACTIVATIONS = ("tanh", "identity")
_READOUTS = ("pinv", "ridge")
_DTYPES = ("float64", "float32")
_NOISE_BLOCK = 256  # noise is drawn per run in blocks of this many steps
_SPARSE_BELOW = 0.25  # use a block-diagonal sparse matrix below this connectivity
_EXACT_EIG_MAX_N = 500  # exact eigenvalues up to this size, ARPACK above


@dataclass(frozen=True)
class ESNConfig:
    """Hyper-parameters of an echo state network (defaults: Jaeger's toolbox, SPEC §5).

    Attributes
    ----------
    n_inputs, n_outputs : sizes of u and y.
    n_reservoir : N, number of tanh units.
    spectral_radius : largest |eigenvalue| of W after rescaling (>= 0).
    connectivity : fraction of nonzero reservoir weights; None means min(1, 10/N).
    input_scaling : W_in ~ U[-s, s] (dense; the bias input column included).
    bias : value of the constant bias input.
    leak_rate : a in (0, 1]; 1 is the standard (non-leaky) ESN.
    noise_level : nu >= 0, reservoir state noise added after tanh.
    noise_kind : "uniform" (U[-nu/2, nu/2]) or "gaussian" (std nu).
    output_feedback : add W_back y(t-1) ~ U[-s, s] with s = feedback_scaling.
    readout_activation : "tanh" (targets through atanh, clipped to +-target_clip)
        or "identity".
    readout : "pinv" (Moore-Penrose, the thesis) or "ridge" (ridge_lambda).
    dtype : "float64" or "float32".
    """

    n_inputs: int
    n_outputs: int
    n_reservoir: int = 200
    spectral_radius: float = 0.5
    connectivity: float | None = None
    input_scaling: float = 1.0
    bias: float = 1.0
    leak_rate: float = 1.0
    noise_level: float = 0.0
    noise_kind: str = "uniform"
    output_feedback: bool = False
    feedback_scaling: float = 1.0
    readout_activation: str = "tanh"
    readout: str = "pinv"
    ridge_lambda: float = 1e-6
    target_clip: float = 0.99
    dtype: str = "float64"

    def __post_init__(self) -> None:
        checks = [
            (self.n_inputs >= 1, f"n_inputs must be >= 1, got {self.n_inputs}"),
            (self.n_outputs >= 1, f"n_outputs must be >= 1, got {self.n_outputs}"),
            (self.n_reservoir >= 1, f"reservoir size N must be >= 1, got {self.n_reservoir}"),
            (
                np.isfinite(self.spectral_radius) and self.spectral_radius >= 0,
                f"spectral radius must be >= 0, got {self.spectral_radius}",
            ),
            (
                self.connectivity is None or 0 < self.connectivity <= 1,
                f"connectivity must be in (0, 1], got {self.connectivity}",
            ),
            (self.input_scaling >= 0, f"input scaling must be >= 0, got {self.input_scaling}"),
            (0 < self.leak_rate <= 1, f"leak rate must be in (0, 1], got {self.leak_rate}"),
            (
                np.isfinite(self.noise_level) and self.noise_level >= 0,
                f"noise level must be >= 0, got {self.noise_level}",
            ),
            (self.noise_kind in _NOISE_KINDS, f"noise kind must be one of {_NOISE_KINDS}, "
             f"got {self.noise_kind!r}"),
            (self.readout_activation in _ACTIVATIONS, f"readout activation must be one of "
             f"{_ACTIVATIONS}, got {self.readout_activation!r}"),
            (self.readout in _READOUTS, f"readout must be one of {_READOUTS}, "
             f"got {self.readout!r}"),
            (self.ridge_lambda >= 0, f"ridge lambda must be >= 0, got {self.ridge_lambda}"),
            (0 < self.target_clip < 1, f"target clip must be in (0, 1), got {self.target_clip}"),
            (self.dtype in _DTYPES, f"dtype must be one of {_DTYPES}, got {self.dtype!r}"),
        ]
        for ok, message in checks:
            if not ok:
                raise ValueError(message)

    @property
    def density(self) -> float:
        """Fraction of nonzero reservoir weights actually used."""
        if self.connectivity is not None:
            return float(self.connectivity)
        return min(1.0, 10.0 / self.n_reservoir)

    @property
    def n_extended(self) -> int:
        """Length D of the extended state [x; u; 1] the readout sees."""
        return self.n_reservoir + self.n_inputs + 1


def run_generators(seed: int | None, n_runs: int) -> list[np.random.Generator]:
    """One independent Generator per run, spawned from ``seed``."""
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n_runs)]


def spectral_radius(w: np.ndarray) -> float:
    """Largest absolute eigenvalue of a square matrix ``w`` (N, N)."""
    n = w.shape[0]
    if n <= _EXACT_EIG_MAX_N:
        return float(np.max(np.abs(np.linalg.eigvals(w))))
    try:
        vals = scipy.sparse.linalg.eigs(
            scipy.sparse.csr_array(w), k=6, which="LM", v0=np.ones(n), ncv=min(n - 1, 60),
            return_eigenvectors=False,
        )  # several eigenvalues and a wide Krylov space: k=1 can stop on a runner-up
        return float(np.max(np.abs(vals)))
    except scipy.sparse.linalg.ArpackNoConvergence:
        return float(np.max(np.abs(np.linalg.eigvals(w))))


def _draw_weights(cfg: ESNConfig, rng: np.random.Generator) -> dict[str, np.ndarray]:
    n = cfg.n_reservoir
    mask = rng.random((n, n)) < cfg.density
    w = np.where(mask, rng.uniform(-0.5, 0.5, (n, n)), 0.0)
    radius = spectral_radius(w)
    if radius > 0:
        w *= cfg.spectral_radius / radius
    w_in = cfg.input_scaling * rng.uniform(-1.0, 1.0, (n, cfg.n_inputs + 1))
    w_back = cfg.feedback_scaling * rng.uniform(-1.0, 1.0, (n, cfg.n_outputs))
    if not cfg.output_feedback:
        w_back[:] = 0.0
    return {"W": w, "W_in": w_in, "W_back": w_back}


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
        if rngs is None:
            rngs = run_generators(seed, n_runs)
        if len(rngs) != n_runs:
            raise ValueError(f"got {len(rngs)} generators for {n_runs} runs")
        self.cfg = cfg
        self.n_runs = n_runs
        self.rngs = list(rngs)
        self.dtype = np.dtype(cfg.dtype)
        drawn = [_draw_weights(cfg, g) for g in self.rngs]
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
            # CSC, not CSR: CSR's inner loop ends after a random number of terms (a
            # row's nonzeros), a mispredicted branch per row; CSC's scattered adds run
            # ~2x faster. Column by column, each output still sums its terms from the
            # first column to the last, as CSR did: the same numbers, bit for bit.
            a = self._sparse = scipy.sparse.block_diag(
                [scipy.sparse.csr_array(m) for m in self.W], format="csc"
            ).astype(dt)
            self._kernel_args = (a.shape[0], a.shape[1], a.indptr, a.indices, a.data)

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
            out *= level
            if out is not block:
                block[...] = out
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
        u1 = ext[:, n_res:, None]
        a = self._sparse
        if a is None:
            pre = np.matmul(self.W, self.x[..., None])[..., 0]
        else:  # W x summed from zero, then + W_in u1: bit for bit what CSR gave
            pre = np.zeros((n_runs, n_res), self.dtype)
            x = np.ascontiguousarray(self.x, self.dtype)
            if _csc_matvec is None:
                pre += (a @ x.reshape(-1)).reshape(n_runs, n_res)
            else:
                _csc_matvec(*self._kernel_args, x, pre)
        pre += np.matmul(self.W_in, u1)[..., 0]
        if cfg.output_feedback:
            y_prev = self.y if feedback is None else np.asarray(feedback, self.dtype)
            pre += np.matmul(self.W_back, y_prev[..., None])[..., 0]
        x = np.tanh(pre, out=pre)
        if cfg.leak_rate != 1.0:
            x = (1.0 - cfg.leak_rate) * self.x + cfg.leak_rate * x
        if noise and cfg.noise_level > 0:
            x += self._noise()
        self.x = x
        ext[:, :n_res] = x
        self.extended = ext
        self.y = self._activate(np.matmul(self.W_out, ext[..., None])[..., 0])
        return self.y

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
        a, kernel_args = self._sparse, self._kernel_args
        leak = cfg.leak_rate
        if leak != 1.0:
            kept = np.empty(width, self.dtype)
        add_noise = noise and cfg.noise_level > 0
        x = np.ascontiguousarray(self.x, self.dtype).reshape(-1)
        for t in range(n_steps):
            row = rows[t]
            if _csc_matvec is None:
                row += a @ x
            else:
                _csc_matvec(*kernel_args, x, row)
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
        m = np.asarray(states, np.float64)[:, washout:]
        s = np.asarray(targets, np.float64)[:, washout:]
        if self.cfg.readout_activation == "tanh":
            clip = self.cfg.target_clip
            s = np.arctanh(np.clip(s, -clip, clip))
        selected = np.ones(self.n_runs, bool) if runs is None else np.asarray(runs, bool)
        idx = np.flatnonzero(selected)
        if idx.size == 0:
            return
        if factors is not None:
            if self.cfg.readout != "pinv" or factors.shape != m.shape:
                raise ValueError("factors must be PinvFactors of the same states, for a "
                                 "pinv readout")
            w_t = factors.solve(s[idx], idx)
        elif self.cfg.readout == "pinv":  # (r, D, n_out); m[idx] would copy all the states
            w_t = pinv_solve(m if idx.size == self.n_runs else m[idx], s[idx])
        else:
            w_t = np.stack([ridge_solve(m[i], s[i], self.cfg.ridge_lambda) for i in idx])
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
        n_runs = arrays["W"].shape[0]
        esn = cls.__new__(cls)
        esn.cfg, esn.n_runs, esn.dtype = cfg, n_runs, np.dtype(cfg.dtype)
        esn.rngs = run_generators(seed, n_runs)
        esn._set_weights(arrays["W"], arrays["W_in"], arrays["W_back"], arrays["W_out"])
        esn.reset()
        esn.x, esn.y = arrays["x"].astype(esn.dtype), arrays["y"].astype(esn.dtype)
        return esn


def read_metadata(path: str | Path) -> dict:
    """The ``metadata`` dict saved with a network by :meth:`ESN.save` ({} if none)."""
    with np.load(Path(path), allow_pickle=False) as data:
        return json.loads(str(data["metadata"])) if "metadata" in data.files else {}


PINV_RCOND = 1e-15  # singular values below this x the largest count as zero (NumPy's)
# Below this estimated (1-norm) condition number of R_M no singular value is anywhere
# near the cutoff (kappa_2 <= D kappa_1, and the estimate is good to a small factor),
# so M^+ S is the plain least-squares solution.
PINV_DIRECT_COND = 1e10


def pinv_solve(m: np.ndarray, s: np.ndarray) -> np.ndarray:
    """M^+ S for stacked (R, T, D) M and (R, T, n) S, without forming M^+ or M's U.

    Per run, one Householder QR (LAPACK ``dgeqrf``) of [M | S] in a reused workspace
    gives R_M and Q^T S; then :func:`_small_solver`. Equal to ``pinv(M) @ S`` to ~1e-13 on
    the thesis's reservoir states (condition ~5e3), at a fraction of its cost, and with
    one (T, D + n) buffer instead of several (R, T, D) copies (fresh pages of a few
    hundred MB cost as much system time as the solve). For many fits on the same M see
    :class:`PinvFactors`.
    """
    n_runs, n_steps, d = m.shape
    if n_steps < d:
        return _pinv_solve_wide(m, s)
    work = np.empty((n_steps, d + s.shape[-1]), order="F")
    out = np.empty((n_runs, d, s.shape[-1]))
    for r in range(n_runs):
        work[:, :d] = m[r]
        work[:, d:] = s[r]
        qr = _householder_qr(work)
        out[r] = _small_solver(qr[:d, :d])(qr[:d, d:])  # R_M, Q^T S
    return out


def _pinv_solve_wide(m: np.ndarray, s: np.ndarray) -> np.ndarray:
    """:func:`pinv_solve` for wide M (T < D: fewer samples than features, the
    interpolating regime of paper C). QR of M^T = Q R gives M = R^T Q^T, so
    M^+ S = Q (R^T)^+ S: a (T, T) solve and Q applied to it (LAPACK ``dormqr``), instead
    of the SVD of the whole (T, D) M."""
    n_runs, n_steps, d = m.shape
    n_out = s.shape[-1]
    work = np.empty((d, n_steps), order="F")
    out = np.empty((n_runs, d, n_out))
    lapack = scipy.linalg.lapack
    for r in range(n_runs):
        work[:] = m[r].T
        qr, tau = _householder_qr(work, with_tau=True)
        c = np.zeros((d, n_out), order="F")
        c[:n_steps] = _small_solver(qr[:n_steps, :n_steps], transpose=True)(s[r])
        out[r], _, info = lapack.dormqr("L", "N", qr, tau, c, max(1, 64 * n_out),
                                        overwrite_c=True)
        if info != 0:  # pragma: no cover - LAPACK argument error
            raise np.linalg.LinAlgError(f"dormqr failed (info {info})")
    return out


class PinvFactors:
    """The pinv readout's factorization of stacked states M (R, T, D), for many fits on
    the same states with different targets (paper E's Fig. 3 cycles, true-target
    training without noise: the teacher-forced states repeat bit for bit). One QR and
    small solver per run up front; each :meth:`solve` is then Q^T S (LAPACK ``dormqr``)
    and the small solve, a few percent of a fresh :func:`pinv_solve`."""

    def __init__(self, m: np.ndarray):
        m = np.asarray(m, np.float64)
        self.shape = m.shape
        n_runs, n_steps, d = m.shape
        self._pinv = np.linalg.pinv(m, rcond=PINV_RCOND) if n_steps < d else None
        self._qr: list[tuple[np.ndarray, np.ndarray]] = []
        self._small: list[Callable[[np.ndarray], np.ndarray]] = []
        if self._pinv is None:
            for r in range(n_runs):
                qr, tau = _householder_qr(np.array(m[r], order="F"), with_tau=True)
                self._qr.append((qr, tau))
                self._small.append(_small_solver(np.array(qr[:d, :d], order="F")))

    def solve(self, s: np.ndarray, runs: np.ndarray | None = None) -> np.ndarray:
        """M^+ S for targets (r, T, n) of the runs ``runs`` (indices; default all)."""
        runs = np.arange(self.shape[0]) if runs is None else np.asarray(runs)
        if self._pinv is not None:
            return self._pinv[runs] @ s
        d, lapack = self.shape[2], scipy.linalg.lapack
        out = np.empty((runs.size, d, s.shape[-1]))
        for k, r in enumerate(runs):
            qr, tau = self._qr[r]
            c = np.array(s[k], order="F")
            qt_s, _, info = lapack.dormqr("L", "T", qr, tau, c, max(1, 64 * c.shape[1]),
                                          overwrite_c=True)
            if info != 0:  # pragma: no cover - LAPACK argument error
                raise np.linalg.LinAlgError(f"dormqr failed (info {info})")
            out[k] = self._small[r](qt_s[:d])
        return out


def _householder_qr(a: np.ndarray, with_tau: bool = False):
    """LAPACK ``dgeqrf`` of a Fortran-ordered ``a`` in place (R in its upper triangle,
    the reflectors below), with the blocked algorithm's workspace."""
    lapack = scipy.linalg.lapack
    lwork, _ = lapack.dgeqrf_lwork(*a.shape)
    qr, tau, _, info = lapack.dgeqrf(a, lwork=int(lwork), overwrite_a=True)
    if info != 0:  # pragma: no cover - LAPACK argument error
        raise np.linalg.LinAlgError(f"dgeqrf failed (info {info})")
    return (qr, tau) if with_tau else qr


def _small_solver(r_m: np.ndarray, transpose: bool = False
                  ) -> Callable[[np.ndarray], np.ndarray]:
    """x = A^+ b for A the (D, D) upper triangle ``r_m`` (``transpose``: its transpose).
    When A is safely full-rank (LAPACK's estimate of its condition number under
    :data:`PINV_DIRECT_COND`, far from where ``np.linalg.pinv`` drops a singular value,
    at :data:`PINV_RCOND` x the largest), one triangular solve: the least-squares
    solution is then the pseudo-inverse's. Otherwise the SVD of R: singular values under
    the cutoff dropped, as ``np.linalg.pinv`` does. The solver reads ``r_m`` when
    called."""
    lapack = scipy.linalg.lapack
    rcond, _ = lapack.dtrcon(r_m, norm="1")
    if rcond * PINV_DIRECT_COND > 1.0:
        return lambda b: lapack.dtrtrs(r_m, b, trans=int(transpose))[0]
    u, sv, vt = np.linalg.svd(np.triu(r_m))  # R = U S V^T, R^T = V S U^T
    large = sv > PINV_RCOND * sv.max()
    inv = np.divide(1.0, sv, out=np.zeros_like(sv), where=large)
    if transpose:
        return lambda b: u @ (inv[:, None] * (vt @ b))
    return lambda b: vt.T @ (inv[:, None] * (u.T @ b))


def ridge_solve(m: np.ndarray, s: np.ndarray, ridge_lambda: float) -> np.ndarray:
    """Solve (M^T M + lambda I) W = M^T S by Cholesky; M (T, D), S (T, n) -> W (D, n)."""
    gram = m.T @ m + ridge_lambda * np.eye(m.shape[1])
    try:
        return scipy.linalg.cho_solve(scipy.linalg.cho_factor(gram), m.T @ s)
    except np.linalg.LinAlgError:
        # lambda too small for a rank-deficient M (e.g. a constant-zero input): solve the
        # same problem as least squares on [M; sqrt(lambda) I], which needs no PD Gram.
        aug_m = np.vstack([m, np.sqrt(ridge_lambda) * np.eye(m.shape[1])])
        aug_s = np.vstack([s, np.zeros((m.shape[1], s.shape[1]))])
        return np.linalg.lstsq(aug_m, aug_s, rcond=None)[0]
