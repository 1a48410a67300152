"""Earlier versions' flat training configs, read as today's composed one.

Before :class:`skinny_mj.config.TrainConfig` was composed of its parts' configs, its
``metrics.json``, config files and ``model.npz`` metadata held one flat dict of 43
fields (``"method": "new", "reservoir": 200, ...``). :data:`LEGACY_KEYS` says where each
field went; :func:`from_legacy` reads such a dict (``TrainConfig.from_dict`` calls it
when :func:`is_legacy`), so the files of earlier versions still run.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from skinny_mj import overrides
from skinny_mj.errors import SkinnyInputError

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
    "epochs": "rule.epochs", "gain_schedule": "rule.gain_schedule",
    "gain_factor": "rule.gain_factor", "gain_value": "rule.gain_value",
    "u_error_gain": "rule.u_error_gain", "readout_forgetting": "rule.forgetting",
    "cycles": "rule.cycles", "tt_input_noise": "rule.input_noise",
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
    """A flat file of an earlier version (plain field names such as ``method``)."""
    return any("." not in k and k not in ("actuation", "rule", "forward", "inputs")
               for k in d)


def from_legacy(d: Mapping[str, Any], base: Any) -> Any:
    """An earlier version's flat config ``d`` as today's ``base.override(...)`` (``base``:
    ``TrainConfig()``): each field moved to its dotted key; a setting the chosen types
    do not have is dropped when it has its old default (the old code ignored it), else
    refused as before."""
    unknown = sorted(set(d) - set(LEGACY_KEYS) - set(_LEGACY_CHOICES))
    if unknown:
        raise SkinnyInputError(f"unknown training config field(s) {unknown}")
    method = d.get("method", "new")
    changes: dict[str, Any] = {"rule": method}
    if method in ("new", "true-target") and "beta" in d:
        changes["rule.beta"] = d["beta"]
    if method == "true-target" and "tt_cycles" in d:
        changes["rule.cycles"] = d["tt_cycles"]
    if method in ("original", "new"):
        fit = "ridge-select" if d.get("ridge_select") else d.get("readout_fit", "cycle")
        changes["rule.fit"] = fit
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
    old_defaults = _LEGACY_DEFAULTS
    for name, value in d.items():
        if name in _LEGACY_CHOICES or (name == "cycles" and method == "true-target"):
            continue  # (FEL's cycles, which the true target ignored; its own: tt_cycles)
        key = LEGACY_KEYS[name]
        if key in available:
            changes[key] = value
        elif value != old_defaults.get(name, value):
            raise SkinnyInputError(f"field {name!r} ({key}) has no effect with "
                                   f"{_choice_text(probe)}, got {value!r}")
    return base.override(changes)


def _choice_text(cfg: Any) -> str:
    return f"rule={cfg.rule.kind}, actuation={cfg.actuation.kind}, forward={cfg.forward.kind}"


#: Earlier versions' defaults of the fields that moved onto a type.
_LEGACY_DEFAULTS = {
    "epochs": 10, "gain_schedule": "linear", "gain_factor": 0.9, "gain_value": 0.65,
    "u_error_gain": 1.0, "readout_forgetting": 0.8, "cycles": None, "tt_input_noise": 0.0,
    "feedback": "pd", "gravity_feedforward": False, "velocity_inputs": None,
    "feedback_omega": None, "feedback_zeta": 1.0, "test_payload_kg": 0.0,
    "test_mass_scale": 1.0, "forward_reservoir": 100, "forward_input": "sensed",
    "forward_sharing": None,
}
