"""Readout solvers of the ESN (:class:`skinny_mj.controllers.esn.ESN`): the Moore-Penrose
pseudo-inverse (the thesis) and ridge regression, each of stacked runs.

The readout W_out of run r solves  M_r W_out^T = S_r  for extended states M (R, T, D)
and targets S (R, T, n_out), D = N + n_in + 1:

- :func:`pinv_solve`: W_out^T = M^+ S, equal to ``np.linalg.pinv(M) @ S`` (to ~1e-13 on
  reservoir states), through one Householder QR per run and a triangular solve when R_M is
  safely full-rank (:func:`small_solver`), the SVD of R_M otherwise; wide M (T < D) via
  the QR of M^T (:func:`pinv_solve_wide`);
- :class:`PinvFactors`: the same factorization kept for many fits on the same states;
- :func:`ridge_solve`: (M^T M + lambda I) W = M^T S by Cholesky;
- :func:`solve_readout`: the one an :class:`~skinny_mj.controllers.reservoir.ESNConfig` asks for,
  targets through atanh for a tanh readout.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from skinny_mj.controllers.reservoir import ESNConfig

PINV_RCOND = 1e-15  # singular values below this x the largest count as zero (NumPy's)
# Below this estimated (1-norm) condition number of R_M no singular value is anywhere
# near the cutoff (kappa_2 <= D kappa_1, and the estimate is good to a small factor),
# so M^+ S is the plain least-squares solution.
PINV_DIRECT_COND = 1e10


def pinv_solve(m: np.ndarray, s: np.ndarray) -> np.ndarray:
    """M^+ S for stacked (R, T, D) M and (R, T, n) S, without forming M^+ or M's U.

    Per run, one Householder QR (LAPACK ``dgeqrf``) of [M | S] in a reused workspace
    gives R_M and Q^T S; then :func:`small_solver`. Equal to ``pinv(M) @ S`` to ~1e-13 on
    the thesis's reservoir states (condition ~5e3), at a fraction of its cost, and with
    one (T, D + n) buffer instead of several (R, T, D) copies (fresh pages of a few
    hundred MB cost as much system time as the solve). For many fits on the same M see
    :class:`PinvFactors`.
    """
    n_runs, n_steps, d = m.shape
    if n_steps < d:
        return pinv_solve_wide(m, s)
    work = np.empty((n_steps, d + s.shape[-1]), order="F")
    out = np.empty((n_runs, d, s.shape[-1]))
    for r in range(n_runs):
        work[:, :d] = m[r]
        work[:, d:] = s[r]
        qr = householder_qr(work)
        out[r] = small_solver(qr[:d, :d])(qr[:d, d:])  # R_M, Q^T S
    return out


def pinv_solve_wide(m: np.ndarray, s: np.ndarray) -> np.ndarray:
    """:func:`pinv_solve` for wide M (T < D: fewer samples than features, the
    interpolating regime of paper C). QR of M^T = Q R gives M = R^T Q^T, so
    M^+ S = Q (R^T)^+ S: a (T, T) solve and Q applied to it (LAPACK ``dormqr``), instead
    of the SVD of the whole (T, D) M."""
    n_runs, n_steps, d = m.shape
    n_out = s.shape[-1]
    work = np.empty((d, n_steps), order="F")
    out = np.empty((n_runs, d, n_out))
    lapack = _lapack()
    for r in range(n_runs):
        work[:] = m[r].T
        qr, tau = householder_qr(work, with_tau=True)
        c = np.zeros((d, n_out), order="F")
        c[:n_steps] = small_solver(qr[:n_steps, :n_steps], transpose=True)(s[r])
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
                qr, tau = householder_qr(np.array(m[r], order="F"), with_tau=True)
                self._qr.append((qr, tau))
                self._small.append(small_solver(np.array(qr[:d, :d], order="F")))

    def solve(self, s: np.ndarray, runs: np.ndarray | None = None) -> np.ndarray:
        """M^+ S for targets (r, T, n) of the runs ``runs`` (indices; default all)."""
        runs = np.arange(self.shape[0]) if runs is None else np.asarray(runs)
        if self._pinv is not None:
            return self._pinv[runs] @ s
        d, lapack = self.shape[2], _lapack()
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


def _lapack():
    """SciPy's LAPACK wrappers, imported on first use: a study's ``--help`` imports this
    module and needs no SciPy."""
    import scipy.linalg

    return scipy.linalg.lapack


def householder_qr(a: np.ndarray, with_tau: bool = False):
    """LAPACK ``dgeqrf`` of a Fortran-ordered ``a`` in place (R in its upper triangle,
    the reflectors below), with the blocked algorithm's workspace."""
    lapack = _lapack()
    lwork, _ = lapack.dgeqrf_lwork(*a.shape)
    qr, tau, _, info = lapack.dgeqrf(a, lwork=int(lwork), overwrite_a=True)
    if info != 0:  # pragma: no cover - LAPACK argument error
        raise np.linalg.LinAlgError(f"dgeqrf failed (info {info})")
    return (qr, tau) if with_tau else qr


def small_solver(r_m: np.ndarray, transpose: bool = False
                  ) -> Callable[[np.ndarray], np.ndarray]:
    """x = A^+ b for A the (D, D) upper triangle ``r_m`` (``transpose``: its transpose).
    When A is safely full-rank (LAPACK's estimate of its condition number under
    :data:`PINV_DIRECT_COND`, far from where ``np.linalg.pinv`` drops a singular value,
    at :data:`PINV_RCOND` x the largest), one triangular solve: the least-squares
    solution is then the pseudo-inverse's. Otherwise the SVD of R: singular values under
    the cutoff dropped, as ``np.linalg.pinv`` does. The solver reads ``r_m`` when
    called."""
    lapack = _lapack()
    rcond, _ = lapack.dtrcon(r_m, norm="1")
    if rcond * PINV_DIRECT_COND > 1.0:
        return lambda b: lapack.dtrtrs(r_m, b, trans=int(transpose))[0]
    if not np.all(np.isfinite(r_m)):  # a diverged run's states (NaN/inf): the SVD would
        # raise "did not converge"; a NaN readout lets health() fail that run with a reason
        return lambda b: np.full(np.shape(b), np.nan)
    u, sv, vt = np.linalg.svd(np.triu(r_m))  # R = U S V^T, R^T = V S U^T
    large = sv > PINV_RCOND * sv.max()
    inv = np.divide(1.0, sv, out=np.zeros_like(sv), where=large)
    if transpose:
        return lambda b: u @ (inv[:, None] * (vt @ b))
    return lambda b: vt.T @ (inv[:, None] * (u.T @ b))


def ridge_solve(m: np.ndarray, s: np.ndarray, ridge_lambda: float) -> np.ndarray:
    """Solve (M^T M + lambda I) W = M^T S by Cholesky; M (T, D), S (T, n) -> W (D, n)."""
    import scipy.linalg

    gram = m.T @ m + ridge_lambda * np.eye(m.shape[1])
    try:
        return scipy.linalg.cho_solve(scipy.linalg.cho_factor(gram), m.T @ s)
    except np.linalg.LinAlgError:
        # lambda too small for a rank-deficient M (e.g. a constant-zero input): solve the
        # same problem as least squares on [M; sqrt(lambda) I], which needs no PD Gram.
        aug_m = np.vstack([m, np.sqrt(ridge_lambda) * np.eye(m.shape[1])])
        aug_s = np.vstack([s, np.zeros((m.shape[1], s.shape[1]))])
        return np.linalg.lstsq(aug_m, aug_s, rcond=None)[0]


def linear_targets(cfg: ESNConfig, targets: np.ndarray) -> np.ndarray:
    """``targets`` as float64 in the readout's linear domain: through atanh, clipped to
    +-``cfg.target_clip``, for a tanh readout; as they are otherwise."""
    s = np.asarray(targets, np.float64)
    if cfg.readout_activation == "tanh":
        s = np.arctanh(np.clip(s, -cfg.target_clip, cfg.target_clip))
    return s


def solve_readout(cfg: ESNConfig, states: np.ndarray, targets: np.ndarray, runs: np.ndarray,
                  factors: PinvFactors | None = None) -> np.ndarray:
    """(W_out)^T (r, D, n_out) of the runs ``runs`` (r indices into R), fitted as ``cfg``
    says (``readout``, ``ridge_lambda``) to extended states M ``states`` (R, T, D) and
    desired outputs ``targets`` (R, T, n_out), the latter through atanh (clipped to
    +-``target_clip``) for a tanh readout. ``factors``: :class:`PinvFactors` of these same
    states (pinv readout only)."""
    m = np.asarray(states, np.float64)
    s = linear_targets(cfg, targets)
    if factors is not None:
        if cfg.readout != "pinv" or factors.shape != m.shape:
            raise ValueError("factors must be PinvFactors of the same states, for a "
                             "pinv readout")
        return factors.solve(s[runs], runs)
    if cfg.readout == "pinv":  # (r, D, n_out); m[runs] would copy all the states
        return pinv_solve(m if runs.size == m.shape[0] else m[runs], s[runs])
    return np.stack([ridge_solve(m[i], s[i], cfg.ridge_lambda) for i in runs])


class RLS:
    """Recursive least squares for R readouts in lockstep (the FORCE rule of Sussillo &
    Abbott 2009 is RLS on the network's own output).

    After the samples (x_1, s_1) ... (x_T, s_T), with forgetting factor ``forgetting``
    = 1 and P_0 = I / lambda, W equals the ridge solution
    (M^T M + lambda I)^-1 M^T S of :func:`ridge_solve` on the same data (exactly in
    exact arithmetic: both minimise the same quadratic); with forgetting g < 1 each
    old sample's weight decays by g per step (memory about 1 / (1 - g) steps).

    Parameters
    ----------
    w : (R, n_out, D) readouts, updated IN PLACE (pass ``esn.W_out`` to train an ESN
        online; a float64 array).
    ridge_lambda : lambda > 0 of P_0 = I / lambda (ignored when ``p0`` is given).
    forgetting : g in (0, 1].
    p0 : optional (R, D, D) initial inverse Gram (e.g. :meth:`from_states`).

    Attributes
    ----------
    P : (R, D, D) the running inverse of the (forgetting-weighted) Gram + lambda I.
    """

    def __init__(self, w: np.ndarray, ridge_lambda: float = 1.0, forgetting: float = 1.0,
                 p0: np.ndarray | None = None):
        if w.ndim != 3 or w.dtype != np.float64:
            raise ValueError(f"w must be a (R, n_out, D) float64 array, got {w.shape} {w.dtype}")
        if not 0 < forgetting <= 1:
            raise ValueError(f"forgetting factor must be in (0, 1], got {forgetting}")
        n_runs, _, d = w.shape
        if p0 is None:
            if not ridge_lambda > 0:
                raise ValueError(f"RLS needs ridge lambda > 0, got {ridge_lambda}")
            p0 = np.broadcast_to(np.eye(d) / ridge_lambda, (n_runs, d, d))
        if p0.shape != (n_runs, d, d):
            raise ValueError(f"p0 must be {(n_runs, d, d)}, got {p0.shape}")
        # C order: a copy of a broadcast P_0 would keep the runs' axis innermost, and
        # every product with P would then take NumPy's slow strided loop
        self.W, self.forgetting = w, float(forgetting)
        self.P = np.array(p0, np.float64, order="C")
        self._outer = np.empty_like(self.P)  # update's (R, D, D) scratch buffer

    @classmethod
    def from_states(cls, w: np.ndarray, states: np.ndarray, ridge_lambda: float,
                    forgetting: float = 1.0) -> RLS:
        """RLS that continues a ridge fit on ``states`` (R, T, D): P_0 = (M^T M +
        lambda I)^-1, so (forgetting 1) further updates give ridge on all the data."""
        m = np.asarray(states, np.float64)
        gram = np.swapaxes(m, 1, 2) @ m + ridge_lambda * np.eye(m.shape[2])
        return cls(w, forgetting=forgetting, p0=np.linalg.inv(gram))

    def update(self, x: np.ndarray, target: np.ndarray,
               runs: np.ndarray | None = None) -> np.ndarray:
        """One sample per run: x (R, D) extended state, target (R, n_out) (in the
        readout's linear domain). ``runs``: (R,) bool, runs to update (others keep W
        and P). Returns the a-priori error target - W x (R, n_out)."""
        x = np.asarray(x, np.float64)
        px = np.matmul(self.P, x[..., None])[..., 0]  # (R, D)
        gain = px / (self.forgetting + np.sum(x * px, axis=1))[:, None]  # (R, D)
        err = np.asarray(target, np.float64) - np.matmul(self.W, x[..., None])[..., 0]
        # P <- (P - gain px^T) / g in place, through one (R, D, D) buffer kept between
        # calls (two fresh (R, D, D) arrays per sample cost more than the arithmetic)
        sel = np.ones(len(x), bool) if runs is None else np.asarray(runs, bool)
        for r in [slice(None)] if sel.all() else np.flatnonzero(sel):
            outer = np.multiply(gain[r, :, None], px[r, None, :], out=self._outer[r])
            np.subtract(self.P[r], outer, out=self.P[r])
            if self.forgetting != 1.0:  # x / 1.0 == x exactly
                np.divide(self.P[r], self.forgetting, out=self.P[r])
            self.W[r] += err[r, :, None] * gain[r, None, :]
        return err


def rls_solve(m: np.ndarray, s: np.ndarray, ridge_lambda: float,
              forgetting: float = 1.0) -> np.ndarray:
    """W (D, n) from RLS run over the rows of M (T, D), S (T, n) from W = 0, P_0 = I /
    lambda: with ``forgetting`` 1 the same problem as :func:`ridge_solve`."""
    w = np.zeros((1, s.shape[1], m.shape[1]))
    rls = RLS(w, ridge_lambda, forgetting)
    for t in range(m.shape[0]):
        rls.update(m[t][None], s[t][None])
    return w[0].T
