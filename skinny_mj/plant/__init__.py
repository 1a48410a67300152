"""The plant: Skinny's body, its MuJoCo model and physics, the dm_control
task, the plant adapters the controllers talk to, dynamics, changes of the body, the
bimanual plant, the ideal controller, pictures."""

from skinny_mj.plant import headless

headless.install()  # no display, no MUJOCO_GL: dm_control skips GLFW without a warning
