"""Pattern generation with output feedback, without a plant: the ordinary teacher-forced
fit, paper E's new β method, and FORCE (online RLS), then a free run.

An ESN with output feedback (``ESNConfig.output_feedback``) is driven by an input
sequence u (R, T, n_in) (zeros for a pure generator: the bias drives it) and a teacher
d (R, T, n_out):

- :func:`fit_ordinary`: one teacher-forced pass (step t sees d(t-1) fed back), states
  after ``washout`` regressed on d (Jaeger 2001);
- :func:`fit_beta`: ``cycles`` passes, each from a reset, fitting the blend
  y_used = β d + (1 − β) y_ESN, as :mod:`skinny_mj.controllers.true_target` does with the true
  commands. ``feedback="teacher"``: the fed-back value is d (then, without reservoir
  noise, the states repeat each cycle and the readout after n cycles is exactly
  (1 − (1 − β)^n) times the ordinary one: the blend only shrinks it);
  ``feedback="blend"``: the fed-back value is the same blend of d and the network's own
  last output, so the network's own output enters its training as in FEL;
- :func:`fit_force`: teacher forcing through the washout, then the network's own
  output fed back while RLS (:class:`skinny_mj.controllers.readout.RLS`) pulls it to d every step
  and the updated output is what is fed back (Sussillo & Abbott 2009);
- :func:`free_run`: the network alone, its own output fed back.
"""

from __future__ import annotations

import numpy as np
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.learning import beta_target
from skinny_mj.controllers.methods import check_beta
from skinny_mj.controllers.readout import RLS

FEEDBACKS = ("teacher", "blend")


def figure_eight(n_steps: int, period: int = 100, amplitude: float = 0.5) -> np.ndarray:
    """Jaeger's figure-eight (a 1:2 Lissajous curve), (T, 2): amplitude x (sin w t,
    sin 2 w t), w = 2 pi / period steps."""
    t = np.arange(n_steps) * (2 * np.pi / period)
    return amplitude * np.stack([np.sin(t), np.sin(2 * t)], axis=1)


def fit_ordinary(esn: ESN, inputs: np.ndarray, teacher: np.ndarray, washout: int,
                 noise: bool = True) -> None:
    """One teacher-forced pass from a reset; readout fitted on the states after
    ``washout``. inputs (R, T, n_in), teacher (R, T, n_out)."""
    esn.reset()
    _, states = esn.run(inputs, noise=noise, teacher=teacher, washout=washout)
    esn.fit(states, teacher[:, washout:])


def fit_beta(esn: ESN, inputs: np.ndarray, teacher: np.ndarray, washout: int, beta: float,
             cycles: int, feedback: str = "teacher", noise: bool = True,
             min_improvement: float | None = None) -> np.ndarray:
    """The new β method: ``cycles`` passes (each from a reset) fitting y_used = β d +
    (1 − β) y_ESN. Returns the NRMSE (R, cycles) of each pass's outputs against d.

    ``min_improvement``: a convergence criterion instead of the fixed count (``cycles``
    is then the cap). A run stops, keeping its readout, at the first pass whose output
    NRMSE is not at least this fraction below the previous pass's (the last refit no
    longer helped); its later entries in the curve are NaN. With a perfect teacher the
    error falls by about β per pass until it reaches the noise floor, so the run stops
    there instead of with (1 − β)^cycles of the readout still missing."""
    if feedback not in FEEDBACKS:
        raise ValueError(f"feedback must be one of {FEEDBACKS}, got {feedback!r}")
    check_beta(beta)
    if cycles < 1:
        raise ValueError(f"cycles must be >= 1, got {cycles}")
    if min_improvement is not None and not 0 < min_improvement < 1:
        raise ValueError(f"min_improvement must be in (0, 1), got {min_improvement}")
    curve = np.full((esn.n_runs, cycles), np.nan)
    active = np.ones(esn.n_runs, bool)
    d = teacher[:, washout:]
    for i in range(cycles):
        esn.reset()
        if feedback == "teacher":
            y_esn, states = esn.run(inputs, noise=noise, teacher=teacher, washout=washout)
        else:
            y_esn, states = _run_blended(esn, inputs, teacher, beta, noise)
            y_esn, states = y_esn[:, washout:], states[:, washout:]
        err = np.sqrt(np.mean((y_esn - d) ** 2, axis=(1, 2)) / d.var(axis=(1, 2)))
        if min_improvement is not None and i > 0:
            active &= err < (1.0 - min_improvement) * curve[:, i - 1]
        if not active.any():
            break
        curve[active, i] = err[active]
        esn.fit(states, beta_target(d, y_esn, beta), runs=active)
    return curve


def _run_blended(esn: ESN, inputs: np.ndarray, teacher: np.ndarray, beta: float,
                 noise: bool) -> tuple[np.ndarray, np.ndarray]:
    """A pass whose fed-back value is β d(t-1) + (1 − β) y(t-1) (y: own output)."""
    n_steps = inputs.shape[1]
    ys = np.empty((esn.n_runs, n_steps, esn.cfg.n_outputs))
    xs = np.empty((esn.n_runs, n_steps, esn.cfg.n_extended))
    for t in range(n_steps):
        fb = None if t == 0 else beta_target(teacher[:, t - 1], ys[:, t - 1], beta)
        ys[:, t] = esn.step(inputs[:, t], noise=noise, feedback=fb)
        xs[:, t] = esn.extended
    return ys, xs


def fit_force(esn: ESN, inputs: np.ndarray, teacher: np.ndarray, washout: int,
              ridge_lambda: float = 1.0, forgetting: float = 1.0,
              noise: bool = True) -> np.ndarray:
    """FORCE: teacher forcing for ``washout`` steps, then own output fed back and one
    RLS step per time step toward d (identity readout only). Returns the a-priori
    error's NRMSE per run (R,) over the learning steps."""
    if esn.cfg.readout_activation != "identity":
        raise ValueError("fit_force needs an identity readout")
    esn.reset()
    esn.run(inputs[:, :washout], noise=noise, teacher=teacher[:, :washout])
    rls = RLS(esn.W_out, ridge_lambda, forgetting)
    sq = np.zeros(esn.n_runs)
    for t in range(washout, inputs.shape[1]):
        esn.step(inputs[:, t], noise=noise)
        err = rls.update(esn.extended, teacher[:, t])
        sq += np.sum(err**2, axis=1)
        esn.y = esn.readout(esn.extended[:, None])[:, 0]  # the updated output is fed back
    d = teacher[:, washout:]
    return np.sqrt(sq / d[0].size / d.var(axis=(1, 2)))


def free_run(esn: ESN, inputs: np.ndarray) -> np.ndarray:
    """The network alone for inputs (R, H, n_in), own output fed back: (R, H, n_out).
    Starts from the current state and last output (e.g. after a teacher-forced pass)."""
    return np.stack([esn.step(inputs[:, t], noise=False) for t in range(inputs.shape[1])],
                    axis=1)


def horizon(free: np.ndarray, target: np.ndarray, threshold: float = 0.1,
            scale: float | None = None) -> np.ndarray:
    """Free-run steps (R,) before the normalized error ||y(t) − d(t)|| / (sqrt(n_out)
    std(d)) first exceeds ``threshold`` (H if never; non-finite counts as exceeded).
    free, target (R, H, n_out); ``scale``: std(d) (default: the target's, per run)."""
    std = target.std(axis=(1, 2)) if scale is None else np.full(free.shape[0], scale)
    err = np.sqrt(np.mean((free - target) ** 2, axis=2)) / std[:, None]
    bad = ~(err <= threshold)
    return np.where(bad.any(axis=1), bad.argmax(axis=1), free.shape[1])
