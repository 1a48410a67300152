"""What a robot's controllers know of its joints: encoder angles with noise, velocities
estimated from them, optionally a control step late.

:class:`JointSensing` turns the true joint state of R arms, once per control step, into
the sensed one:

- angles: q_s(t) = q(t) + n(t), n ~ N(0, ``encoder_noise_rad``^2) per joint and step,
  each run's draws from its own ``np.random.Generator``;
- velocities: the backward difference (q_s(t) - q_s(t-1)) / dt of the sensed angles
  (``velocity="finite-difference"``: the velocity of half a step ago, to first order),
  or the second-order one (1.5 q_s(t) - 2 q_s(t-1) + 0.5 q_s(t-2)) / dt
  (``"finite-difference-2"``: the velocity now, to second order, at 1.8x the noise);
  zero at the first step, where the arm starts at rest (the first difference at the
  second); optionally low-passed by a first-order filter of cut-off
  ``velocity_filter_hz``: v(t) = a v(t-1) + (1 - a) fd(t), a = exp(-2 pi f_c dt);
  ``velocity="observer"``: a state observer driven by the torque the motors were
  commanded (an alpha-beta filter with the controllers' model as its prediction; no
  low-pass): the loop hands it the model's prediction (q^-, v^-) of the step just taken,
  from the observer's last estimate (q^, v^) (:attr:`estimate`) under the torque applied
  in the step, and it corrects with the encoder's residual r = q_s(t) - q^-:
  q^ = q^- + alpha r, v^ = v^- + beta r / dt (``observer_gains`` = (alpha, beta)); the
  angles the controllers see stay the encoder's;
  ``velocity="oracle"`` reads the true joint velocities instead;
- delay: what the controllers see at step t is the sensed state of step t - ``delay_steps``
  (the first state repeated until the history fills).

Pure NumPy: the plant side hands the true angles and velocities as arrays.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

#: How the joint velocities are sensed.
VELOCITIES = ("finite-difference", "finite-difference-2", "observer", "oracle")


@dataclass
class JointSensing:
    """Encoders, a velocity estimate and a delay for R arms (see the module docstring).

    encoder_noise_rad : standard deviation of each encoder reading, rad.
    velocity : one of :data:`VELOCITIES`.
    velocity_filter_hz : cut-off of the velocity estimate's low-pass, Hz (None: none).
    delay_steps : control steps by which the sensed state lags the true one.
    dt : control step, s.
    rngs : one Generator per run (R).
    observer_gains : (alpha, beta) of the ``"observer"`` velocity's correction.
    """

    encoder_noise_rad: float
    velocity: str
    velocity_filter_hz: float | None
    delay_steps: int
    dt: float
    rngs: list = field(repr=False)
    observer_gains: tuple[float, float] = (1.0, 1.0)

    def __post_init__(self) -> None:
        if self.velocity not in VELOCITIES:
            raise ValueError(f"velocity must be one of {VELOCITIES}, got {self.velocity!r}")
        if not (np.isfinite(self.encoder_noise_rad) and self.encoder_noise_rad >= 0):
            raise ValueError(f"encoder noise must be >= 0 rad, got {self.encoder_noise_rad}")
        if self.delay_steps < 0 or self.dt <= 0:
            raise ValueError("need delay_steps >= 0 and dt > 0")
        alpha, beta = self.observer_gains
        if not (0 < alpha <= 1 and 0 < beta <= 2):
            raise ValueError(f"observer gains need 0 < alpha <= 1, 0 < beta <= 2, got "
                             f"{self.observer_gains}")
        fc = self.velocity_filter_hz
        if fc is not None and not (np.isfinite(fc) and fc > 0):
            raise ValueError(f"velocity filter cut-off must be > 0 Hz, got {fc}")
        if fc is not None and self.velocity == "observer":
            raise ValueError("the observer velocity takes no low-pass (its gains filter it)")
        self._a = 0.0 if fc is None else float(np.exp(-2.0 * np.pi * fc * self.dt))
        self._history: deque = deque(maxlen=self.delay_steps + 1)

    def _read(self, q_true: np.ndarray) -> np.ndarray:
        q = np.asarray(q_true, float)
        if self.encoder_noise_rad == 0:
            return q.copy()
        noise = np.stack([rng.standard_normal(q.shape[1]) for rng in self.rngs])
        return q + self.encoder_noise_rad * noise

    def reset(self, q_true: np.ndarray, qd_true: np.ndarray) -> None:
        """A new cycle at the true state (R, n) rad, rad/s (the arm at rest)."""
        self._q = self._read(q_true)
        self._qd = np.asarray(qd_true, float).copy() if self.velocity == "oracle" \
            else np.zeros_like(self._q)
        self._q_prev = None
        self._q_hat = self._q.copy()  # the observer's own angle estimate
        self._history.clear()
        for _ in range(self.delay_steps + 1):
            self._history.append((self._q, self._qd))

    @property
    def needs_prediction(self) -> bool:
        """Does :meth:`update` need the model's prediction of the step just taken?"""
        return self.velocity == "observer"

    @property
    def estimate(self) -> tuple[np.ndarray, np.ndarray]:
        """(q^, v^), each (R, n): the latest (undelayed) angle and velocity estimates, rad
        and rad/s, the state the model's next prediction starts from."""
        return self._q_hat, self._qd

    def update(self, q_true: np.ndarray, qd_true: np.ndarray,
               prediction: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        """The next control step's true state (R, n); ``prediction``: the model's (q^-,
        v^-) (R, n) each, rad and rad/s, of the step just taken from :attr:`estimate` (the
        ``"observer"`` velocity's input; ignored otherwise)."""
        q = self._read(q_true)
        if self.velocity == "oracle":
            qd = np.asarray(qd_true, float).copy()
        elif self.velocity == "observer":
            if prediction is None:
                raise ValueError("the observer velocity needs the model's prediction")
            alpha, beta = self.observer_gains
            q_pred, qd_pred = (np.asarray(x, float) for x in prediction)
            r = q - q_pred
            self._q_hat = q_pred + alpha * r
            qd = qd_pred + (beta / self.dt) * r
        else:
            qd = (q - self._q) / self.dt
            if self.velocity == "finite-difference-2" and self._q_prev is not None:
                qd = (1.5 * q - 2.0 * self._q + 0.5 * self._q_prev) / self.dt
            if self._a:
                qd = self._a * self._qd + (1.0 - self._a) * qd
        self._q_prev, self._q, self._qd = self._q, q, qd
        self._history.append((q, qd))

    @property
    def q(self) -> np.ndarray:
        """(R, n) the sensed joint angles the controllers see now, rad."""
        return self._history[0][0]

    @property
    def qd(self) -> np.ndarray:
        """(R, n) the sensed joint velocities the controllers see now, rad/s."""
        return self._history[0][1]
