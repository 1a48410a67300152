"""Dotted-key overrides of a nested frozen-dataclass configuration.

A configuration is a frozen dataclass whose fields are scalars or other frozen
dataclasses (its components). A component field may be a *choice of types* (a union,
e.g. ``Velocity | Torque``): each member has a ``kind`` field naming it, and setting
the field to a kind switches the type (``actuation=torque``), keeping the values of
the settings the old and the new type inherit from a common base (and starting an
unrelated type from its defaults). One mechanism then serves the command
line, config files and studies::

    override(cfg, {"esn.spectral_radius": 0.9, "method": "original", "method.epochs": 2})
    flatten(cfg)  # {"plant.dof": 4, ..., "method": "new", "method.beta": 0.1, ...}
    parse_value(cfg, "esn.n_reservoir", "400")  # 400 (the field's type)

A choice may also be a *registry* (a dataclass base with ``REGISTRY`` and the class
methods ``choose(name)`` -> the member type and ``names()``): its members are those
registered when the key is set (``method.fit=NAME``, :mod:`skinny_mj.training.fits`), and
the chosen member's fields are keys too (``method.fit.forgetting``). A type's ``ALIASES``
(old name -> (the key it names now, relative; the type checking a value the chosen
member has no field for)) keep an old key: it sets its new key, or, when the chosen type
has no such setting, is checked and ignored (``method.forgetting``). A type's
``RENAMED`` (old field name -> new field name) keeps the old name of a renamed field and
every key under it (``rule.epochs`` -> ``method.epochs``): :func:`canonical` gives a key's
current name and logs one warning line per old key and process.

A key naming a type's field applies after the key that chooses the type, whatever the
order given. An unknown key, a field the chosen type does not have, or a value of the
wrong type is a :class:`SkinnyInputError` naming the key.
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import logging
import math
import types
import typing
from collections.abc import Mapping
from typing import Any

from skinny_mj.errors import SkinnyInputError

__all__ = ["override", "flatten", "parse_value", "keys", "field_type", "node", "canonical",
           "renamed", "KIND"]

_log = logging.getLogger(__name__)

#: The field that names a union member's type.
KIND = "kind"
#: The old keys warned about in this process (each once).
_WARNED: set[str] = set()


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _members(annotation: Any) -> tuple[type, ...]:
    """The dataclass members of a (union) annotation; () for a scalar."""
    args = typing.get_args(annotation) if isinstance(annotation, types.UnionType) \
        or typing.get_origin(annotation) is typing.Union else (annotation,)
    return tuple(a for a in args if dataclasses.is_dataclass(a))


def _kinds(cls: type) -> tuple[str, ...]:
    """The kind names a union member answers to: its ``KINDS`` or its ``kind`` default."""
    return tuple(getattr(cls, "KINDS", ())) or (
        next(f.default for f in dataclasses.fields(cls) if f.name == KIND),)


def _registry(annotation: Any) -> bool:
    """Is ``annotation`` a choice of types kept in a registry (module docstring)?"""
    return isinstance(annotation, type) and bool(getattr(annotation, "REGISTRY", False))


def _member_of(annotation: Any, kind: str, key: str) -> type:
    if _registry(annotation):
        return annotation.choose(kind)  # (its own refusal of an unknown name)
    members = _members(annotation)
    for cls in members:
        if kind in _kinds(cls):
            return cls
    known = [k for cls in members for k in _kinds(cls)]
    raise SkinnyInputError(f"{key} must be one of {known}, got {kind!r}")


def _is_union(annotation: Any) -> bool:
    if _registry(annotation):
        return True
    members = _members(annotation)
    return bool(members) and all(_has(m, KIND) for m in members) \
        and (len(members) > 1 or hasattr(members[0], "KINDS"))


def _fields(obj: Any) -> list[str]:
    """The settings of a config object or class (its kind and class constants aside)."""
    return [f.name for f in dataclasses.fields(obj) if f.name != KIND]


def _has(obj: Any, name: str) -> bool:
    return dataclasses.is_dataclass(obj) and name in {f.name for f in dataclasses.fields(obj)}


def flatten(cfg: Any, prefix: str = "") -> dict[str, Any]:
    """Every leaf as ``{"a.b": value}``; a union field as its kind (``"method": "new"``)
    followed by the chosen type's fields. JSON-ready (tuples become lists)."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(cfg):
        value, key = getattr(cfg, f.name), prefix + f.name
        if f.name == KIND:
            continue
        if dataclasses.is_dataclass(value):
            if _has(value, KIND) and _is_union(_hints(type(cfg))[f.name]):
                out[key] = getattr(value, KIND)
            out.update(flatten(value, key + "."))
        else:
            out[key] = list(value) if isinstance(value, tuple) else value
    return out


def keys(cfg: Any) -> list[str]:
    """Every key :func:`override` takes on ``cfg`` as it is (the chosen types' fields)."""
    return list(flatten(cfg))


def _switch(old: Any, cls: type, kind: str) -> Any:
    """A ``cls`` of ``kind`` keeping the values of the settings ``old``'s type and ``cls``
    have from a common base (FEL's two methods share their schedule; a forward model
    switching its kind keeps its size); unrelated types start from their defaults."""
    common = [b for b in type(old).__mro__ if b is not object and dataclasses.is_dataclass(b)
              and issubclass(cls, b)]
    shared = {n: getattr(old, n) for n in _fields(common[0]) if n != KIND} if common else {}
    return cls(**shared, kind=kind)


def _unknown(key: str, owner: Any, root: Any) -> SkinnyInputError:
    """The error of ``key``, not a setting of ``owner`` (the config object holding it,
    or None when the key's path leaves the config)."""
    known = keys(root)
    close = difflib.get_close_matches(key, known, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    path = key.rpartition(".")[0]
    if owner is not None and _has(owner, KIND) and path:
        return SkinnyInputError(
            f"{key!r} is not a setting of {path}={getattr(owner, KIND)} (its settings: "
            f"{', '.join(_fields(owner)) or 'none'})")
    return SkinnyInputError(f"unknown config key {key!r}{hint}")


def canonical(cfg: Any, key: str) -> str:
    """``key`` under its current name: each part a type on its path renamed (its
    ``RENAMED``: old field name -> new) replaced by the new name; an old key is logged
    once per process (``rule.epochs is now method.epochs``)."""
    parts, obj = key.split("."), cfg
    for i, part in enumerate(parts):
        new = getattr(type(obj), "RENAMED", {}).get(part)
        if new is not None and not _has(obj, part):
            parts[i] = new
        obj = getattr(obj, parts[i], None) if _has(obj, parts[i]) else None
    now = ".".join(parts)
    if now != key and key not in _WARNED:
        _WARNED.add(key)
        _log.warning("%s is now %s", key, now)
    return now


def renamed(cfg: Any, changes: Mapping[str, Any]) -> dict[str, Any]:
    """``changes`` with every key under its current name (:func:`canonical`); an old and
    a new key setting one setting to different values are refused."""
    out: dict[str, Any] = {}
    given: dict[str, str] = {}  # current key -> the key it was given as
    for key, value in changes.items():
        now = canonical(cfg, key)
        if now in out and out[now] != value:
            raise SkinnyInputError(f"{given[now]}={out[now]} and {key}={value} set the same "
                                   f"key, {now}: give it once")
        out[now], given[now] = value, key
    return out


def node(cfg: Any, dotted: str) -> Any:
    """The value at the dotted key on ``cfg`` (a component or a leaf), or None when
    ``cfg`` as it is has no such key."""
    for part in canonical(cfg, dotted).split("."):
        if not _has(cfg, part):
            return None
        cfg = getattr(cfg, part)
    return cfg


_node = node


def _apply(node: Any, changes: Mapping[str, Any], prefix: str, root: Any) -> Any:
    """``node`` (at ``prefix``) with its relative dotted ``changes`` set: per field, a
    type chosen first, then its own settings; then ``node`` rebuilt once, so its checks
    see all the changes together (``method=none`` with ``test.gain=1``)."""
    groups: dict[str, dict[str, Any]] = {}
    aliases = getattr(type(node), "ALIASES", {})
    legacy: dict[tuple[str, str], str] = {}  # (field, its key) set by an old key
    for key, value in changes.items():
        name, _, rest = key.partition(".")
        if name in aliases and not rest and not _has(node, name):
            name, _, rest = aliases[name][0].partition(".")
            legacy[name, rest] = key
        groups.setdefault(name, {})[rest] = value
    new = {}
    for name, sub in groups.items():
        key = prefix + name
        if not _has(node, name) or name == KIND:
            raise _unknown(key + next((f".{r}" for r in sub if r), ""), node, root)
        annotation, current = _hints(type(node))[name], getattr(node, name)
        if "" in sub:
            current = _value(current, annotation, sub.pop(""), key)
        for rest in [r for r in sub if (name, r) in legacy and not _has(current, r)]:
            _unused_alias(aliases[legacy[name, rest]][1], rest, sub.pop(rest),
                          prefix + legacy[name, rest])
        if sub:
            if not dataclasses.is_dataclass(current):
                raise _unknown(f"{key}.{next(iter(sub))}", None, root)
            current = _apply(current, sub, key + ".", root)
        new[name] = current
    try:
        return dataclasses.replace(node, **new)
    except SkinnyInputError as err:
        owner = prefix[:-1]
        raise SkinnyInputError(f"{owner}: {err}" if owner else str(err)) from None
    except (TypeError, ValueError) as err:  # a component's own check (e.g. ESNConfig's)
        raise SkinnyInputError(f"{prefix[:-1] or 'config'}: {err}") from None


def _unused_alias(cls: type, name: str, value: Any, key: str) -> None:
    """Check ``value`` of the old key ``key`` as ``cls``'s setting ``name`` would be,
    then drop it: the chosen type has no use for it (as before it moved)."""
    value = _checked(value, _hints(cls)[name], key)
    try:
        cls(**{name: value})
    except (TypeError, ValueError) as err:
        raise SkinnyInputError(f"{key}: {err}") from None


def _value(current: Any, annotation: Any, value: Any, key: str) -> Any:
    """The new value of the field ``key`` (``current`` now) set to ``value``: a type
    chosen by its kind name, or a scalar checked against its annotation."""
    if _is_union(annotation):
        if not isinstance(value, str):
            raise SkinnyInputError(f"{key} is a choice of types: give its name as a string, "
                                   f"got {value!r}")
        cls = _member_of(annotation, value, key)
        return current if type(current) is cls and getattr(current, KIND) == value \
            else _switch(current, cls, value)
    if _members(annotation):
        raise SkinnyInputError(f"{key} is a group of settings ({', '.join(_fields(current))}): "
                               f"set them as {key}.NAME=VALUE")
    return _checked(value, annotation, key)


def _checked(value: Any, annotation: Any, key: str) -> Any:
    """``value`` if it fits ``annotation`` (a JSON list becomes a tuple; an int is a
    float; a bool is neither)."""
    allowed = typing.get_args(annotation) if typing.get_args(annotation) else (annotation,)
    if isinstance(value, list) and any(typing.get_origin(a) is tuple for a in allowed):
        return tuple(value)
    for kind in allowed:
        kind = typing.get_origin(kind) or kind
        if kind is type(None) and value is None:
            return value
        if kind is bool and isinstance(value, bool):
            return value
        if isinstance(value, bool):
            continue
        if kind is float and isinstance(value, int | float):
            return float(value) if isinstance(value, int) else value
        if kind in (int, str, tuple) and isinstance(value, kind):
            return value
        if kind is Any:
            return value
    raise SkinnyInputError(f"{key} must be {_describe(annotation)}, got {value!r}")


def _describe(annotation: Any) -> str:
    names = {int: "a whole number", float: "a number", str: "a string", bool: "true or false",
             type(None): "none"}
    allowed = typing.get_args(annotation) or (annotation,)
    return " or ".join(names.get(a, getattr(a, "__name__", str(a))) for a in allowed)


def override(cfg: Any, changes: Mapping[str, Any]) -> Any:
    """``cfg`` with the dotted keys of ``changes`` set (a type-choosing key before its
    fields; an old key under its current name, :func:`renamed`), validated again by the
    dataclasses' own checks, once with all the changes."""
    return _apply(cfg, renamed(cfg, changes), "", cfg) if changes else cfg


def field_type(cfg: Any, key: str) -> Any:
    """The annotation of the leaf ``key`` on ``cfg`` (a union field: ``str``)."""
    key = canonical(cfg, key)
    *owner, name = key.split(".")
    node = _node(cfg, ".".join(owner)) if owner else cfg
    alias = getattr(type(node), "ALIASES", {}).get(name) if node is not None else None
    if alias is not None and not _has(node, name):  # an old key: its new key's type
        target = ".".join([*owner, alias[0]])
        if _node(cfg, target.rpartition(".")[0]) is not None and \
                _has(_node(cfg, target.rpartition(".")[0]), target.rpartition(".")[2]):
            return field_type(cfg, target)
        return _hints(alias[1])[alias[0].rpartition(".")[2]]
    if node is None or not _has(node, name) or name == KIND:
        raise _unknown(key, node, cfg)
    annotation = _hints(type(node))[name]
    if _is_union(annotation):
        return str
    if _members(annotation):
        raise SkinnyInputError(f"{key} is a group of settings: set {key}.NAME=VALUE")
    return annotation


_TRUE, _FALSE, _NONE = ("true", "yes", "on", "1"), ("false", "no", "off", "0"), ("none", "null")


def parse_value(cfg: Any, key: str, text: str) -> Any:
    """``text`` (from a command line) as the type of ``key``'s field on ``cfg``."""
    annotation = field_type(cfg, key)
    allowed = typing.get_args(annotation) or (annotation,)
    low = text.strip().lower()
    if type(None) in allowed and low in _NONE:
        return None
    for kind in allowed:
        try:
            if kind is bool and low in _TRUE + _FALSE:
                return low in _TRUE
            if kind is int:
                return int(text)
            if kind is float:
                value = float(text)
                if not math.isfinite(value):
                    raise ValueError
                return value
            if kind is str:
                return text
        except ValueError:
            continue
    raise SkinnyInputError(f"{key} must be {_describe(annotation)}, got {text!r}")
