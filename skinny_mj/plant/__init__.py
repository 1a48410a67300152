"""The plant: Skinny's body, its MuJoCo model and physics, the dm_control
task, the plant adapters the controllers talk to, dynamics, changes of the body, the
bimanual plant, the ideal controller, pictures."""
