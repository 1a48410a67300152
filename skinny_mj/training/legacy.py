"""Earlier versions' flat training configs, read as today's composed one.

Before :class:`skinny_mj.training.config.TrainConfig` was composed of its parts' configs, its
``metrics.json``, config files and ``model.npz`` metadata held one flat dict of 43
fields (``"method": "new", "reservoir": 200, ...``). :data:`LEGACY_KEYS` says where each
field went; :func:`from_legacy` reads such a dict (``TrainConfig.from_dict`` calls it
when :func:`is_legacy`), so the files of earlier versions still run.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from skinny_mj.errors import SkinnyInputError
from skinny_mj.training import overrides

__all__ = ["LEGACY_KEYS", "is_legacy", "from_legacy"]

#: The flat field names of earlier versions' config files -> today's dotted keys.
#: ``method``, ``beta``, ``cycles``, ``readout_fit``, ``ridge_select`` and ``forward``
#: choose types and are read by :func:`from_legacy`.
LEGACY_KEYS = {
    "dof": "plant.dof", "signals": "plant.signals", "sensor_noise": "plant.sensor_noise",
    "delay": "plant.delay", "leading_arm": "plant.leading_arm", "plant": "plant.backend",
    "trajectory": "movement.trajectory", "asf": "movement.asf", "speed": "movement.speed",
    "reps": "movement.reps", "max_speed_from": "movement.max_speed_from",
    "full_scale_factor": "movement.full_scale_factor", "retarget": "movement.retarget",
    "reservoir": "esn.n_reservoir", "spectral_radius": "esn.spectral_radius",
    "noise": "esn.noise_level", "readout": "esn.readout", "ridge": "esn.ridge_lambda",
    "inputs": "inputs",
    "forward_reservoir": "forward.reservoir", "forward_input": "forward.input",
    "forward_sharing": "forward.sharing",
    "epochs": "method.epochs", "gain_schedule": "method.gain_schedule",
    "gain_factor": "method.gain_factor", "gain_value": "method.gain_value",
    "u_error_gain": "method.u_error_gain", "readout_forgetting": "method.forgetting",
    "cycles": "method.cycles", "tt_input_noise": "method.input_noise",
    "test_gain": "test.gain", "test_washout_cycles": "test.washout_cycles",
    "test_noise": "test.noise",
    "feedback": "actuation.feedback", "gravity_feedforward": "actuation.gravity_feedforward",
    "velocity_inputs": "actuation.velocity_inputs", "feedback_omega": "actuation.omega",
    "feedback_zeta": "actuation.zeta", "test_payload_kg": "actuation.test_payload_kg",
    "test_mass_scale": "actuation.test_mass_scale",
}
_LEGACY_CHOICES = ("method", "beta", "tt_cycles", "readout_fit", "ridge_select",
                   "actuation", "forward")


def is_legacy(d: Mapping[str, Any]) -> bool:
    """A flat file of an earlier version (plain field names such as ``reservoir``)."""
    return any("." not in k and k not in ("actuation", "method", "rule", "forward", "inputs")
               for k in d)


def from_legacy(d: Mapping[str, Any], base: Any) -> Any:
    """An earlier version's flat config ``d`` as today's ``base.override(...)`` (``base``:
    ``TrainConfig()``): each field moved to its dotted key; a setting the chosen types
    do not have is dropped, since the old code ignored it (e.g. ``epochs`` of a
    true-target run, ``forward_reservoir`` without a forward model)."""
    unknown = sorted(set(d) - set(LEGACY_KEYS) - set(_LEGACY_CHOICES))
    if unknown:
        raise SkinnyInputError(f"unknown training config field(s) {unknown}")
    method = d.get("method", "new")
    changes: dict[str, Any] = {"method": method}
    if method in ("new", "true-target") and "beta" in d:
        changes["method.beta"] = d["beta"]
    if method == "true-target" and "tt_cycles" in d:
        changes["method.cycles"] = d["tt_cycles"]
    if method in ("original", "new"):
        fit = "ridge-select" if d.get("ridge_select") else d.get("readout_fit", "cycle")
        changes["method.fit"] = fit
    if d.get("actuation") is not None:
        changes["actuation"] = d["actuation"]
    if d.get("forward") is not None:
        changes["forward"] = d["forward"]
    if d.get("velocity_inputs") is None or (not d["velocity_inputs"]
                                            and d.get("actuation") != "torque"):
        d = {k: v for k, v in d.items() if k != "velocity_inputs"}  # None: on for torque
    try:
        probe = base.override(changes, check=False)
    except SkinnyInputError as err:  # e.g. an unknown method
        raise SkinnyInputError(f"{err} (fields method, actuation, forward)") from None
    available = set(overrides.keys(probe))
    for name, value in d.items():
        if name in _LEGACY_CHOICES or (name == "cycles" and method == "true-target"):
            continue  # (FEL's cycles, which the true target ignored; its own: tt_cycles)
        if LEGACY_KEYS[name] in available or name == "dof":  # else the old code ignored
            # it: dropped (dof: plant.body by its number of hinges, a key of no field)
            changes[LEGACY_KEYS[name]] = value
    return base.override(changes)
