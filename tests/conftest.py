"""Test-wide settings: no pixels, one BLAS thread (the suite runs on 2 cores)."""

import os

os.environ.setdefault("MUJOCO_GL", "disabled")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
