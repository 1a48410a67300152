"""Paper C on the 3D body (experiments/paper_c_3d.py) and the shared full scale it uses."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.experiments.paper_c import study as paper_c

from skinny_mj.engine import registry
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.parts import full_scale_speeds, load_trajectory


def test_shared_full_scale_is_the_fastest_joints_for_every_joint():
    own = TrainConfig().override({"plant.dof": 8, "plant.signals": "joint"})
    per_joint = full_scale_speeds(own, load_trajectory(own)[0])
    shared = own.override({"movement.full_scale": "shared"})
    speeds = full_scale_speeds(shared, load_trajectory(shared)[0])
    assert per_joint.min() < per_joint.max() / 5  # the 3D joints' scales differ widely
    np.testing.assert_array_equal(speeds, np.full(8, per_joint.max()))
    with pytest.raises(SkinnyInputError, match="full scale must be one of"):
        own.override({"movement.full_scale": "per-arm"})


def test_paper_c_3d_is_paper_c_on_the_3d_body_with_one_full_scale_and_200_units():
    study = registry.get("paper-c-3d")
    exp, two_d = study.build(), paper_c.STUDY.build()
    assert exp.name == "paper-c-3d" and [r.id for r in exp.rows] == \
        [r.id for r in two_d.rows] and exp.runs == two_d.runs
    config = study.config("ymca")
    assert (config.plant.dof, config.plant.signals, config.movement.full_scale,
            config.esn.n_reservoir) == (8, "joint", "shared", 200)
    assert config.override({"plant.dof": 4, "movement.full_scale": "per-joint",
                            "esn.n_reservoir": 1000}) == \
        paper_c.STUDY.config("ymca")  # nothing else differs from paper C
    moved = study.build(quick=True, movement="md_03.amc")  # paper C's real movement
    assert moved.rows[-1].id == paper_c.REAL_ID
    assert moved.config(paper_c.REAL_ID).plant.dof == 8
    for option, value in (("body", 4), ("signals", "cartesian")):
        with pytest.raises(SkinnyInputError, match=f"takes no --{option}"):
            study.build(**{option: value})
