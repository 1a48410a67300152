"""The dynamic study's candidate tables: each maps a row id (or a suffix) to the config
changes that row makes to its base, in the order the candidates were added (a row's place
fixes its seeds, so new candidates go last). :mod:`skinny_mj.experiments.dynamic.study`
builds the rows from them; the results are in docs/results/dynamic.md."""

from __future__ import annotations

#: The torque ``general`` preset's candidates (``--rows general``), each the 2D preset
#: before them (``2d-general-first``: 15 s of slow babbling) with one change
SLOW = "vmin=0.5,vmax=4"  # the first preset's babbling speeds (rad/s)
GENERAL_VARIANTS: dict[str, dict] = {
    "babble60": {"movement.trajectory": f"babble:seed=0,duration=60,{SLOW}"},
    "babble120": {"movement.trajectory": f"babble:seed=0,duration=120,{SLOW}"},
    "babble60+ymca": {"movement.trajectory": f"set:babble:seed=0,duration=60,{SLOW}+ymca"},
    "limits60": {"movement.trajectory": f"babble:seed=0,duration=60,{SLOW},limits=0.5,"
                                        "holds=0.2"},
    "n500": {"esn.n_reservoir": 500},
    "ridge1": {"esn.readout": "ridge", "esn.ridge_lambda": 1.0},
    "washout1": {"test.washout_cycles": 1},
    "scale4": {"movement.full_scale_factor": 4.0},
    "babble60-fast": {"movement.trajectory": "babble:seed=0,duration=60"},
    "babble60-fast+ymca": {"movement.trajectory": "set:babble:seed=0,duration=60+ymca"},
    "babble120+ymca": {"movement.trajectory": f"set:babble:seed=0,duration=120,{SLOW}+ymca"},
    "babble240+ymca": {"movement.trajectory": f"set:babble:seed=0,duration=240,{SLOW}+ymca"},
    "limits60+ymca": {"movement.trajectory": f"set:babble:seed=0,duration=60,{SLOW},"
                                             "limits=0.5,holds=0.2+ymca"},
    "limits120+ymca": {"movement.trajectory": f"set:babble:seed=0,duration=120,{SLOW},"
                                              "limits=0.5,holds=0.2+ymca"},
}


#: Later candidates, row id -> the first preset's changes, in the order they were added
#: (appended after the presets, so no earlier row's seeds move): on the 2D preset's
#: movement (60 s of slow babbling, then YMCA), and the 2D preset as it is on the 3D arm
#: (N = 200, 3 learning cycles)
PRESET_MOVE = {"movement.trajectory": f"set:babble:seed=0,duration=60,{SLOW}+ymca"}
GENERAL_LATE: dict[str, dict] = {
    "2d-general-babble60+ymca-n500": {**PRESET_MOVE, "esn.n_reservoir": 500},
    "2d-general-babble60+ymca-epochs30": {**PRESET_MOVE, "method.epochs": 30},
    "3d-general-babble60+ymca-n200": {**PRESET_MOVE, "plant.dof": 8},
    "2d-general-babble60+ymca-n100": {**PRESET_MOVE, "esn.n_reservoir": 100},
}
#: The 3D candidates (the 2D screen's best movements)
GENERAL_3D = ("babble60+ymca", "babble120+ymca")


#: The recorded-like 3D YMCA's screen (``--rows rec-3d``): ``3d-rec-fel-arm`` with the
#: changes of each candidate, on that row's seeds (paired), in the order they were screened;
#: ``omega``: the inertia-scaled PD teacher's poles (the row's: 5 rad/s), ``inscale``: the
#: ESN's input scaling (1), ``scale``: the full-scale factor of the velocity inputs (2)
OMEGA = "actuation.omega"
_INSCALE, _SCALE, _CYCLES = "esn.input_scaling", "movement.full_scale_factor", "method.cycles"
_RIDGE = {"esn.readout": "ridge"}
REC_3D_SCREEN: dict[str, dict] = {
    "vscale-ymca": {"movement.max_speed_from": "ymca"}, "scale1": {_SCALE: 1.0},
    "forget0.9": {"method.fit.forgetting": 0.9}, "cycles10": {_CYCLES: 10},
    "n1000": {"esn.n_reservoir": 1000}, "inscale0.5": {_INSCALE: 0.5},
    "inscale2": {_INSCALE: 2.0}, "sr0.9": {"esn.spectral_radius": 0.9},
    "ridge1e-3": {**_RIDGE, "esn.ridge_lambda": 1e-3},
    "ridge1e-1": {**_RIDGE, "esn.ridge_lambda": 1e-1},
    "omega10": {OMEGA: 10.0}, "gff": {"actuation.gravity_feedforward": True},
    "omega15": {OMEGA: 15.0}, "omega10+scale1": {OMEGA: 10.0, _SCALE: 1.0},
    "scale0.5": {_SCALE: 0.5}, "omega10+inscale0.5": {OMEGA: 10.0, _INSCALE: 0.5},
    "omega20": {OMEGA: 20.0}, "omega15+scale1": {OMEGA: 15.0, _SCALE: 1.0},
    "scale1+inscale0.5": {_SCALE: 1.0, _INSCALE: 0.5},
    "omega10+cycles10": {OMEGA: 10.0, _CYCLES: 10},
    "omega25": {OMEGA: 25.0}, "omega20+inscale0.5": {OMEGA: 20.0, _INSCALE: 0.5},
    "omega30": {OMEGA: 30.0}, "omega20+cycles10": {OMEGA: 20.0, _CYCLES: 10},
    "omega20+scale1": {OMEGA: 20.0, _SCALE: 1.0},
    "omega15+inscale0.5": {OMEGA: 15.0, _INSCALE: 0.5},
    "omega10+inscale0.5+cycles10": {OMEGA: 10.0, _INSCALE: 0.5, _CYCLES: 10},
    "omega20+ridge1e-1": {OMEGA: 20.0, **_RIDGE, "esn.ridge_lambda": 1e-1},
    "omega20+forget0.9": {OMEGA: 20.0, "method.fit.forgetting": 0.9},
    "omega20+n1000": {OMEGA: 20.0, "esn.n_reservoir": 1000},
    "omega20+epochs30": {OMEGA: 20.0, "method.epochs": 30},
    "omega20+forget0.9+ridge1e-1": {OMEGA: 20.0, "method.fit.forgetting": 0.9, **_RIDGE,
                                    "esn.ridge_lambda": 1e-1},
    "omega20+forget0.95": {OMEGA: 20.0, "method.fit.forgetting": 0.95},
}
#: The screen's choice (the lowest mean position NRMSE over the row's first 3 seeds, see
#: docs/results/dynamic.md): the teacher's poles at 20 rad/s (omega dt = 0.4 at 50 Hz) and
#: the readout's statistics kept with forgetting 0.9 per learning cycle (the row's: 0.8)
REC_3D_CHOICE = "omega20+forget0.9"


#: Later 3D general candidates, row id -> the changes of ``3d-general-babble60+ymca`` (60 s
#: of slow babbling, then YMCA; the 3D arm rows' ESN, N = 500, 6 cycles), on its seeds: the
#: teacher's poles (and forgetting) the recorded-like 3D YMCA's screen chose, with that ESN
#: or the 2D preset's (N = 200, 3 cycles), then more epochs, more babbling, the poles
#: alone, N = 100
CHOSEN = REC_3D_SCREEN[REC_3D_CHOICE]
_N200 = {"esn.n_reservoir": 200, _CYCLES: 3}
GENERAL_3D_LATE: dict[str, dict] = {
    f"3d-general-babble60+ymca-{REC_3D_CHOICE}": CHOSEN,
    f"3d-general-babble60+ymca-{REC_3D_CHOICE}-n200": {**CHOSEN, **_N200},
    f"3d-general-babble60+ymca-{REC_3D_CHOICE}-n200-epochs30": {**CHOSEN, **_N200,
                                                                "method.epochs": 30},
    f"3d-general-babble120+ymca-{REC_3D_CHOICE}-n200": {**CHOSEN, **_N200,
                                                        **GENERAL_VARIANTS["babble120+ymca"]},
    "3d-general-babble60+ymca-omega20-n200": {OMEGA: 20.0, **_N200},
    f"3d-general-babble60+ymca-{REC_3D_CHOICE}-n100": {**CHOSEN, "esn.n_reservoir": 100,
                                                       _CYCLES: 3},
    f"3d-general-babble240+ymca-{REC_3D_CHOICE}-n200": {**CHOSEN, **_N200,
                                                        **GENERAL_VARIANTS["babble240+ymca"]},
}
