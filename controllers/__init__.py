"""Controllers: ESN internal models, feedback controller, feedback-error learning.

Pure NumPy/SciPy (never imports mujoco, dm_control or skinny_mj). Import the
submodules directly, e.g. ``from skinny_mj.controllers.esn import ESN, ESNConfig``.
"""
