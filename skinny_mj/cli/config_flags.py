"""The command line's configuration flags, declared once.

:data:`TRAIN_FLAGS` maps each flag of ``skinny train`` to its dotted
:class:`~skinny_mj.training.config.TrainConfig` key and help, grouped by the part of the config
it sets; :func:`add_flags` puts them on a parser. A flag's value is read with the type
of its config field (:func:`skinny_mj.training.overrides.parse_value`), its help shows the
default of ``TrainConfig()``, and a flag not given is not in the parsed namespace
(``argparse.SUPPRESS``), so a default never overrides a preset or a config file.
``skinny train`` also takes any key as ``KEY=VALUE`` (``esn.spectral_radius=0.9
method=original``); :func:`changes` turns both into one dict of overrides.
"""

from __future__ import annotations

import argparse
import dataclasses
import typing
from collections.abc import Callable, Mapping, Sequence
from typing import Any, NamedTuple

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.body import DOF_ALIASES, body_name, body_names, body_of, by_dof
from skinny_mj.training import fits, overrides
from skinny_mj.training.config import (
    ACTUATIONS,
    DOF_KEY,
    FEEDBACKS,
    METHODS,
    RETARGETS,
    SIGNALS,
    TrainConfig,
)
from skinny_mj.training.fits import FITS

__all__ = ["Flag", "TRAIN_FLAGS", "TEST_FLAGS", "TRACK_FLAGS", "MOVEMENT_FLAGS", "add_flags",
           "given", "pairs", "check_no_conflict", "changes", "flag_names", "default_of",
           "add_body_flags", "chosen_body"]


class Flag(NamedTuple):
    """One command-line flag of a config key."""

    flag: str
    key: str
    help: str
    choices: Sequence[Any] | None = None
    switch: bool = False  # a flag without a value that sets the key to true
    valid: Callable[[str], object] | None = None  # refuses a bad value (open choices)
    default: str | None = None  # the default the help shows (None: the config's)
    metavar: str | None = None  # the value's name in the help (None: from its type)


#: The help of ``--body`` and ``--dof`` (``{bodies}``: the registered bodies' names).
BODY_HELP = ("the body, by name: {bodies} (a torque body trains with the torque "
             "actuation; docs/adding-a-body.md adds one)")
DOF_HELP = ("Skinny's body by its number of hinges: 4 = --body 2d, 8 = --body 3d (with a "
            "torque actuation, their torque twins)")


def _bodies_help(text: str) -> str:
    return text.replace("{bodies}", ", ".join(body_names()))


def _checked(valid: Callable[[str], object]) -> Callable[[str], str]:
    def parse(text: str) -> str:
        try:
            valid(text)
        except (SkinnyInputError, ValueError) as err:
            raise argparse.ArgumentTypeError(str(err).splitlines()[0]) from None
        return text
    return parse


MOVEMENT_FLAGS = [
    Flag("--trajectory", "movement.trajectory", "movement name (see `skinny trajectory "
         "list`) or a file: .npz/.csv trajectory, .amc (with --asf) or .bvh motion capture"),
    Flag("--asf", "movement.asf", "ASF skeleton for an .amc trajectory"),
    Flag("--speed", "movement.speed", "speed factor, e.g. 0.5 or 1.5"),
    Flag("--reps", "movement.reps", "repetitions of the movement"),
    Flag("--retarget", "movement.retarget", "motion capture: joint angles, or the "
         "subject's normalized segment vectors as desired positions", RETARGETS),
]
_BODY = [
    Flag("--body", "plant.body", BODY_HELP, valid=body_name, metavar="NAME"),
    Flag("--dof", DOF_KEY, DOF_HELP, tuple(DOF_ALIASES), default="the body's"),
    Flag("--signals", "plant.signals", "position signals the controller sees", SIGNALS),
]
_SENSOR_NOISE = Flag("--sensor-noise", "plant.sensor_noise", "SD of the sensed positions' noise")

#: ``skinny train``'s flags by group (the part of the config they set).
TRAIN_FLAGS: dict[str, list[Flag]] = {
    "plant": [*_BODY, _SENSOR_NOISE],
    "actuation": [
        Flag("--actuation", "actuation", "velocity servo (the thesis's) or the torque body "
             "with mass and gravity (ESN inverse dynamics, PD teacher)", ACTUATIONS),
        Flag("--feedback", "actuation.feedback", "torque: FEL's teacher, the PD scaled by "
             "the torque limits ('pd') or placed in the arm's own inertia-scaled coordinates "
             "('inertia-pd', a torque body's default without --preset); the others run "
             "alone (--method none)", FEEDBACKS),
        Flag("--gravity-feedforward", "actuation.gravity_feedforward", "torque: add the "
             "gravity (bias) torque to the command, not learned", switch=True),
    ],
    "movement": MOVEMENT_FLAGS,
    "esn": [
        Flag("--reservoir", "esn.n_reservoir", "reservoir size N"),
        Flag("--spectral-radius", "esn.spectral_radius", "spectral radius of the reservoir"),
        Flag("--noise", "esn.noise_level", "reservoir noise level ν (none: the method's)"),
        Flag("--readout", "esn.readout", "readout fit", ("pinv", "ridge")),
        Flag("--ridge", "esn.ridge_lambda", "λ for --readout ridge"),
    ],
    "learning method": [
        Flag("--method", "method", "the learning method: feedback-error learning (original or "
             "new β), the true-target architecture, or none (the feedback controller alone, "
             "test.gain > 0)", METHODS),
        Flag("--epochs", "method.epochs", "FEL epochs"),
        Flag("--beta", "method.beta", "β of the new method and of the true target, in (0, 1]"),
        Flag("--cycles", "method.cycles", "learning cycles per epoch (FEL; none: from β), or "
             "the true target's cycles"),
        Flag("--u-error-gain", "method.u_error_gain", "FEL: scalar on u_error"),
        Flag("--readout-fit", "method.fit", "FEL's learning rule: the readout fitted on each "
             "cycle alone, with λ chosen on a validation cycle (ridge-select, velocity "
             "body), or remembering "
             "earlier cycles: the normal equations with forgetting, or RLS (torque body); "
             f"one of {', '.join(FITS)} or a fit another package registered",
             valid=fits.check),
        Flag("--readout-forgetting", "method.forgetting", "weight of earlier cycles per "
             "learning cycle, in [0, 1] (--readout-fit forgetting or rls)"),
        Flag("--tt-input-noise", "method.input_noise", "SD of noise on the true target's "
             "teacher-forced inputs"),
    ],
    "test": [
        Flag("--test-noise", "test.noise", "reservoir noise on during the test (the "
             "thesis's toolbox)", switch=True),
    ],
}
#: ``skinny test``'s and ``skinny track``'s: the movement, and the sensors' noise.
TEST_FLAGS: dict[str, list[Flag]] = {"movement": MOVEMENT_FLAGS, "plant": [_SENSOR_NOISE]}
TRACK_FLAGS: dict[str, list[Flag]] = {"plant": [*_BODY, _SENSOR_NOISE],
                                      "movement": MOVEMENT_FLAGS}


def _owner(key: str, cfg: TrainConfig) -> Any:
    """The config object holding ``key``'s leaf in ``cfg``, or a default one of the type
    that has it (``method.input_noise``: a default :class:`TrueTarget`)."""
    owner, _, name = key.rpartition(".")
    node = getattr(cfg, owner) if owner else cfg
    if hasattr(node, name):
        return node
    for member in typing.get_args(typing.get_type_hints(type(cfg)).get(owner, type(None))):
        if dataclasses.is_dataclass(member) and name in {f.name for f in
                                                          dataclasses.fields(member)}:
            return member()
    raise SkinnyInputError(f"unknown config key {key!r}")


def default_of(key: str, cfg: TrainConfig | None = None) -> Any:
    """The default of ``key`` in ``cfg`` (default ``TrainConfig()``); a key of a type
    not chosen there (``method.input_noise``) gives that type's default."""
    cfg = TrainConfig() if cfg is None else cfg
    if _is_choice(cfg, key):
        return getattr(overrides.node(cfg, key), overrides.KIND)  # a type's name
    return getattr(_owner(key, cfg), key.rpartition(".")[2])


def _metavar(key: str) -> str:
    """N (whole number), X (number) or TEXT, from the field's type."""
    if "." not in key:
        return "TEXT"
    try:
        hint = overrides.field_type(TrainConfig(), key)  # (an old key: its new key's)
    except SkinnyInputError:  # a key of a type not chosen by default
        hint = typing.get_type_hints(type(_owner(key, TrainConfig())))[key.rpartition(".")[2]]
    allowed = typing.get_args(hint) or (hint,)
    return "N" if int in allowed else "X" if float in allowed else "TEXT"


def _shown(value: Any) -> str:
    return "none" if value is None else str(value).lower() if isinstance(value, bool) \
        else str(value)


def add_flags(parser: argparse.ArgumentParser, groups: Mapping[str, list[Flag]]) -> None:
    """``groups``' flags on ``parser``, one argument group each; each flag's dest is its
    dotted key and only a flag given reaches the namespace (as text; a switch as True)."""
    for title, flags in groups.items():
        group = parser.add_argument_group(title)
        for f in flags:
            shown = f.default if f.default is not None else _shown(default_of(f.key))
            text = f"{_bodies_help(f.help)} (default: {shown})"
            if f.switch:
                group.add_argument(f.flag, dest=f.key, action="store_true",
                                   default=argparse.SUPPRESS, help=text)
            else:
                group.add_argument(f.flag, dest=f.key, default=argparse.SUPPRESS, help=text,
                                   choices=None if f.choices is None
                                   else [str(c) for c in f.choices],
                                   type=None if f.valid is None else _checked(f.valid),
                                   metavar=None if f.choices is not None
                                   else f.metavar or _metavar(f.key))


def given(args: argparse.Namespace, groups: Mapping[str, list[Flag]]) -> dict[str, Any]:
    """The config keys of ``groups`` given on the command line (key -> text or True)."""
    values = vars(args)
    return {f.key: values[f.key] for fs in groups.values() for f in fs if f.key in values}


def pairs(items: Sequence[str]) -> dict[str, str]:
    """``["esn.spectral_radius=0.9", ...]`` as a dict; a word without ``=``, or a key given
    twice with different values, is refused."""
    out: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise SkinnyInputError(f"expected KEY=VALUE (e.g. esn.spectral_radius=0.9), "
                                   f"got {item!r}")
        key = key.strip()
        if key in out and out[key] != value:
            raise SkinnyInputError(f"{key}={out[key]} and {key}={value} contradict each "
                                   "other: give the key once")
        out[key] = value
    return out


def check_no_conflict(flags: Mapping[str, Any], keyed: Mapping[str, str],
                      names: Mapping[str, str]) -> None:
    """Refuse a config key set both by a flag (``flags``: key -> text, ``names``: key ->
    flag) and by a ``KEY=VALUE`` override (``keyed``) to another value, naming both."""
    for key in flags.keys() & keyed.keys():
        flag, value = names.get(key, key), flags[key]
        if str(value).strip() != str(keyed[key]).strip():
            shown = flag if value is True else f"{flag} {value}"
            raise SkinnyInputError(f"{shown} and {key}={keyed[key]} set the same key to "
                                   "different values: give one")


def changes(base: TrainConfig, texts: Mapping[str, Any],
            names: Mapping[str, str] | None = None) -> dict[str, Any]:
    """``texts`` (key -> command-line text, or an already typed value) as typed
    overrides of ``base``: the keys choosing a type first, then each other key read
    with the type its field has once those types are chosen, and checked by its part.
    A refusal names the key's flag from ``names`` (key -> flag), or the key."""
    choices = {k: v for k, v in texts.items() if _is_choice(base, k)}
    chosen = _refusing(lambda: base.override(choices, check=False), names,
                       next(iter(choices), ""))
    out = {}
    for key, value in texts.items():
        def typed(key=key, value=value):
            if key == DOF_KEY:  # plant.body's number of hinges (4, 8), not a field
                by_dof(value)
                return int(value)
            typed = overrides.parse_value(chosen, key, value) if isinstance(value, str) \
                else value
            chosen.override({key: typed}, check=False)  # its part's own checks
            return typed
        out[key] = _refusing(typed, names, key)
    return out


def _refusing(make, names: Mapping[str, str] | None, key: str):
    """``make()``; its refusal names ``key``'s flag (``--reservoir (esn.n_reservoir):
    ...``) when it came from one."""
    try:
        return make()
    except SkinnyInputError as err:
        flag = (names or {}).get(key)
        if flag is None:
            raise
        owner = key.rpartition(".")[0]
        text = str(err).removeprefix(f"{owner}: ") if owner else str(err)
        raise SkinnyInputError(f"{flag} ({key}): {text}") from None


def flag_names(groups: Mapping[str, list[Flag]]) -> dict[str, str]:
    """Key -> flag of ``groups``."""
    return {f.key: f.flag for fs in groups.values() for f in fs}


def _is_choice(cfg: TrainConfig, key: str) -> bool:
    """Does ``key`` choose a type (``method``, ``actuation``, ``forward``, ``method.fit``)?"""
    return dataclasses.is_dataclass(overrides.node(cfg, key))


def add_body_flags(parser: argparse.ArgumentParser, default: str) -> None:
    """``--body NAME`` and its alias ``--dof 4|8`` on a command that is not a training
    (``default``: what the help says the default is); :func:`chosen_body` reads them."""
    parser.add_argument("--body", type=_checked(body_name), default=argparse.SUPPRESS,
                        metavar="NAME", help=f"{_bodies_help(BODY_HELP)} (default: {default})")
    parser.add_argument("--dof", type=int, choices=tuple(DOF_ALIASES), default=argparse.SUPPRESS,
                        help=f"{DOF_HELP} (default: {default})")


def chosen_body(args: argparse.Namespace, default: str | None = "2d") -> str | int | None:
    """The body :func:`add_body_flags`' flags chose: ``--body``'s name, or ``--dof``'s
    number of hinges (``default`` when neither is given: a name, or None); both given and
    naming different bodies is a :class:`SkinnyInputError`."""
    name, dof = getattr(args, "body", None), getattr(args, "dof", None)
    if name is not None and dof is not None:
        if by_dof(dof, body_of(name).actuation) != name:
            raise SkinnyInputError(f"--dof {dof} is the {by_dof(dof)} body and --body {name} "
                                   "another: give one of them")
        return name
    return name if name is not None else dof if dof is not None else default
