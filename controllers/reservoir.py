"""The reservoir an ESN (:class:`skinny_mj.controllers.esn.ESN`) is made of: its hyper-parameters
(:class:`ESNConfig`, defaults from Jaeger's toolbox) and the random weights they describe,
drawn per run from that run's own ``Generator`` (:func:`run_generators`,
:func:`draw_weights`, :func:`spectral_radius`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_NOISE_KINDS = ("uniform", "gaussian")
_ACTIVATIONS = ("tanh", "identity")
_READOUTS = ("pinv", "ridge")
_DTYPES = ("float64", "float32")
_EXACT_EIG_MAX_N = 500  # exact eigenvalues up to this size, ARPACK above


@dataclass(frozen=True)
class ESNConfig:
    """Hyper-parameters of an echo state network (defaults: Jaeger's toolbox, SPEC §5).

    Attributes
    ----------
    n_inputs, n_outputs : sizes of u and y (None: not yet known, e.g. in a training
        config whose plant sets them; a network needs them).
    n_reservoir : N, number of tanh units.
    spectral_radius : largest |eigenvalue| of W after rescaling (>= 0).
    connectivity : fraction of nonzero reservoir weights; None means min(1, 10/N).
    input_scaling : W_in ~ U[-s, s] (dense; the bias input column included).
    bias : value of the constant bias input.
    leak_rate : a in (0, 1]; 1 is the standard (non-leaky) ESN.
    noise_level : nu >= 0, reservoir state noise added after tanh (None: chosen by the
        config's user, e.g. by the learning rule; a network needs a number).
    noise_kind : "uniform" (U[-nu/2, nu/2]) or "gaussian" (std nu).
    output_feedback : add W_back y(t-1) ~ U[-s, s] with s = feedback_scaling.
    readout_activation : "tanh" (targets through atanh, clipped to +-target_clip)
        or "identity".
    readout : "pinv" (Moore-Penrose, the thesis) or "ridge" (ridge_lambda).
    dtype : "float64" or "float32".
    """

    n_inputs: int | None = None
    n_outputs: int | None = None
    n_reservoir: int = 200
    spectral_radius: float = 0.5
    connectivity: float | None = None
    input_scaling: float = 1.0
    bias: float = 1.0
    leak_rate: float = 1.0
    noise_level: float | None = 0.0
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
            (self.n_inputs is None or self.n_inputs >= 1,
             f"n_inputs must be >= 1, got {self.n_inputs}"),
            (self.n_outputs is None or self.n_outputs >= 1,
             f"n_outputs must be >= 1, got {self.n_outputs}"),
            (self.n_reservoir >= 1, f"reservoir size N must be >= 1, got {self.n_reservoir}"),
            (
                np.isfinite(self.spectral_radius) and self.spectral_radius >= 0,
                f"spectral radius must be a finite number >= 0, got {self.spectral_radius}",
            ),
            (
                self.connectivity is None or 0 < self.connectivity <= 1,
                f"connectivity must be in (0, 1], got {self.connectivity}",
            ),
            (self.input_scaling >= 0, f"input scaling must be >= 0, got {self.input_scaling}"),
            (0 < self.leak_rate <= 1, f"leak rate must be in (0, 1], got {self.leak_rate}"),
            (
                self.noise_level is None or (np.isfinite(self.noise_level)
                                             and self.noise_level >= 0),
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
    # Here, not at the top: the training config imports this module, and SciPy would
    # triple the start-up time of every `skinny` command that reads a config.
    import scipy.sparse
    import scipy.sparse.linalg

    try:
        vals = scipy.sparse.linalg.eigs(
            scipy.sparse.csr_array(w), k=6, which="LM", v0=np.ones(n), ncv=min(n - 1, 60),
            return_eigenvectors=False,
        )  # several eigenvalues and a wide Krylov space: k=1 can stop on a runner-up
        return float(np.max(np.abs(vals)))
    except scipy.sparse.linalg.ArpackNoConvergence:
        return float(np.max(np.abs(np.linalg.eigvals(w))))


def draw_weights(cfg: ESNConfig, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One run's weights from ``rng``: W (N, N), ``density`` of it nonzero, U[-0.5, 0.5]
    rescaled to ``spectral_radius``; W_in (N, n_in + 1) ~ U[-s, s], s = input_scaling;
    W_back (N, n_out) ~ U[-s, s], s = feedback_scaling (drawn, then zeroed without output
    feedback, so the draws do not depend on it)."""
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
