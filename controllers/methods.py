"""The learning methods as types, each owning its schedule and its β.

- :class:`Original`: feedback-error learning's original method (β = 1, the readout fitted
  to y_ESN + u_error), one learning cycle an epoch unless ``cycles`` says more (paper A);
- :class:`New`: FEL's new method (paper E), the target blended
  β (y_ESN + u_error) + (1 − β) y_ESN over ``cycles`` learning cycles an epoch (None:
  paper E's Table 1 for its β);
- :class:`TrueTarget`: the true-target architecture (paper D), teacher-forced fits to the
  analytic commands, ``cycles`` of them blended with β (β = 1: one fit).

β is checked once, by :func:`check_beta` in the β types' ``__post_init__``. The feedback
gain K per epoch comes from one of :data:`GAIN_SCHEDULES`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from skinny_mj.controllers.feedback import fixed_gain, linear_gain, multiplicative_gain

__all__ = ["GAIN_SCHEDULES", "PAPER_CYCLES_FOR_BETA", "FELMethod", "Original", "New",
           "TrueTarget", "check_beta"]

#: K per epoch: linear 1 -> 0, multiplicative (paper C), fixed (paper A)
GAIN_SCHEDULES = ("linear", "multiplicative", "fixed")
#: Learning cycles per epoch the paper derived from its Figure 3 (paper E, Table 1).
PAPER_CYCLES_FOR_BETA = {0.3: 2, 0.1: 3, 0.05: 6}


def _number(value) -> bool:
    return isinstance(value, int | float) and math.isfinite(value)


def check_beta(beta: float) -> None:
    """The one check of a blend's β: in (0, 1]."""
    if not (_number(beta) and 0 < beta <= 1):
        raise ValueError(f"beta must be in (0, 1], got {beta}")


def check(checks: list[tuple[bool, str]], error: type[ValueError] = ValueError) -> None:
    """Raise ``error`` with the message of the first check that is False."""
    for ok, message in checks:
        if not ok:
            raise error(message)


@dataclass(frozen=True)
class FELMethod:
    """Feedback-error learning's schedule, shared by its two methods: ``epochs``, the gain
    schedule (K per epoch) and the learning cycles per epoch (``cycles``; None: the
    method's default, :attr:`learning_cycles`). A method adds its ``beta``."""

    epochs: int = 10
    gain_schedule: str = "linear"  # K per epoch: linear 1 -> 0, multiplicative, fixed
    gain_factor: float = 0.9  # multiplicative: K = factor ** epoch (paper C)
    gain_value: float = 0.65  # fixed: K (paper A)
    cycles: int | None = None

    def __post_init__(self) -> None:
        check([
            (isinstance(self.epochs, int) and self.epochs >= 1,
             f"epochs must be >= 1, got {self.epochs}"),
            (self.gain_schedule in GAIN_SCHEDULES,
             f"gain schedule must be one of {GAIN_SCHEDULES}, got {self.gain_schedule!r}"),
            (_number(self.gain_factor) and 0 < self.gain_factor <= 1,
             f"gain factor must be in (0, 1], got {self.gain_factor}"),
            (_number(self.gain_value) and self.gain_value >= 0,
             f"feedback gain must be >= 0, got {self.gain_value}"),
            (self.cycles is None or (isinstance(self.cycles, int) and self.cycles >= 1),
             f"cycles must be >= 1, got {self.cycles}"),
        ])

    def gains(self) -> np.ndarray:
        """Feedback gain K per epoch, (epochs,)."""
        if self.gain_schedule == "linear":
            return linear_gain(self.epochs)
        if self.gain_schedule == "multiplicative":
            return multiplicative_gain(self.epochs, self.gain_factor)
        return fixed_gain(self.epochs, self.gain_value)

    @property
    def learning_cycles(self) -> int:
        """Learning cycles per epoch: ``cycles``, or 1."""
        return 1 if self.cycles is None else self.cycles


@dataclass(frozen=True)
class Original(FELMethod):
    """FEL's original method: the readout fitted to y_ESN + u_error (β = 1)."""

    kind: str = "original"
    beta: ClassVar[float] = 1.0


@dataclass(frozen=True)
class New(FELMethod):
    """FEL's new method (paper E): the target blended with ``beta``."""

    kind: str = "new"
    beta: float = 0.1

    def __post_init__(self) -> None:
        super().__post_init__()
        check_beta(self.beta)

    @property
    def learning_cycles(self) -> int:
        """``cycles``; by default paper E's Table 1 where it has β, else enough cycles for
        (1 − β)^n to fall below 5 % over all epochs (which reproduces the table for
        β = 0.1 and 0.05)."""
        if self.cycles is not None:
            return self.cycles
        for beta, cycles in PAPER_CYCLES_FOR_BETA.items():
            if abs(self.beta - beta) < 1e-12:
                return cycles
        if self.beta >= 1:
            return 1
        total = math.ceil(math.log(0.05) / math.log(1.0 - self.beta))
        return max(1, math.ceil(total / self.epochs))


@dataclass(frozen=True)
class TrueTarget:
    """The true-target architecture (paper D): ``cycles`` teacher-forced fits blended
    with ``beta`` (β = 1: one fit); ``input_noise`` the SD of Gaussian noise added to the
    teacher-forced inputs (not the targets) in every training cycle, normalized signal
    units (0 = none, bit for bit)."""

    kind: str = "true-target"
    beta: float = 0.1
    cycles: int = 50
    input_noise: float = 0.0

    def __post_init__(self) -> None:
        check_beta(self.beta)
        check([
            (isinstance(self.cycles, int) and self.cycles >= 1,
             f"true-target cycles must be >= 1, got {self.cycles}"),
            (_number(self.input_noise) and self.input_noise >= 0,
             f"input noise must be >= 0, got {self.input_noise}"),
        ])

    @property
    def fitted_cycles(self) -> int:
        """Cycles fitted: one with β = 1 (the original method), else ``cycles``."""
        return 1 if self.beta >= 1 else self.cycles
