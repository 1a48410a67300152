"""The thesis toolbox's protocol options, as the training path applies them.

Each is a :class:`skinny_mj.training.config.TrainConfig` setting whose default is the thesis
code's behaviour bit for bit: ``test.noise`` (reservoir noise during the K = 0 test),
``method.u_error_gain`` (FEL: a scalar on the feedback controller's u_error, which the
thesis leaves unstated), ``method.u_error_damping`` (its damped-least-squares lambda near
a singular Jacobian) and ``method.input_noise`` (true target: noise on the
teacher-forced inputs).
"""

from __future__ import annotations

import numpy as np

from skinny_mj.controllers.feedback import FeedbackController

#: The feedback controller's default damped-least-squares lambda.
DAMPING = FeedbackController.damping


def tt_input_rng(seed: int) -> np.random.Generator:
    """The Generator of the true-target's teacher-forcing input noise for run ``seed``:
    the fourth child of ``SeedSequence(seed)`` (the first three are
    :func:`skinny_mj.training.loop.run_streams`'s, which stay as they were)."""
    return np.random.default_rng(np.random.SeedSequence(int(seed)).spawn(4)[3])


def feedback_of(u_error_gain: float, damping: float = DAMPING) -> FeedbackController | None:
    """The FEL feedback controller: None (fel's default one) unless ``u_error_gain``
    scales its u_error or ``damping`` is not the default lambda."""
    if u_error_gain == 1.0 and damping == DAMPING:
        return None
    return FeedbackController(gain=u_error_gain, damping=damping)
