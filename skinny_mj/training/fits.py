"""FEL's readout fits by name: the value of the key ``method.fit`` -> how a training builds
its learning rule (:class:`skinny_mj.controllers.learning.LearningRule`).

The package's own: ``cycle`` (each learning cycle alone, the thesis's pinv or ridge fit),
``ridge-select`` (λ chosen per fit on a validation cycle; the velocity body),
``forgetting`` and ``rls`` (remembering earlier cycles; the torque body; their setting
``method.fit.forgetting``, :class:`ForgettingSettings`). A fit's hyper-parameters are its
own :class:`FitSettings` dataclass, registered with it: the chosen fit's settings are
the configuration's ``method.fit``, each field a key ``method.fit.<param>``. A new rule is
one file (its settings, its :class:`~skinny_mj.controllers.learning.LearningRule`) plus one
:func:`register_fit` line (its builder, or the builder's name ``"module:function"``,
imported when a training makes its rule: the torque fits' builder lives in
:mod:`skinny_mj.training.torque`, which imports the configuration, which imports this
registry); then
``TrainConfig().override({"method.fit": NAME})``, ``skinny train method.fit=NAME`` and
``skinny sweep method.fit=cycle,NAME`` choose it (see the docs page "Adding a learning
rule"). :func:`register_fit` changes one Python process; for the command line and a
sweep's worker processes, another package publishes its :class:`Fit` through the
entry-point group :data:`FIT_GROUP` (the :class:`Fit` :func:`register_fit` returns), read
the first time a name is not known.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from skinny_mj import plugins
from skinny_mj.controllers.ridge_select import RidgeSelector
from skinny_mj.errors import SkinnyInputError

__all__ = ["Fit", "FitSettings", "ForgettingSettings", "FITS", "FIT_GROUP", "register_fit",
           "make_rule", "known", "check", "refusal"]

#: Entry-point group through which another package adds a fit (name = the fit's name,
#: value = a :class:`Fit`).
FIT_GROUP = "skinny_mj.fits"

#: ``make(cfg, esn, steps)`` -> the rule for one training (None: the loop's default,
#: each cycle alone); ``cfg``: its :class:`skinny_mj.training.config.TrainConfig`,
#: ``steps``: the samples of one learning cycle.
Make = Callable[[Any, Any, int], Any]


@dataclass(frozen=True)
class FitSettings:
    """A fit's settings, the value of ``method.fit``: ``kind`` is the fit's name (the key
    ``method.fit=NAME`` chooses it); a fit with hyper-parameters subclasses this frozen
    dataclass with one defaulted field per parameter, each then a key
    ``method.fit.<param>`` (``skinny sweep method.fit.forgetting=0.8,0.9``). Its
    ``__post_init__`` checks them (a ``ValueError`` names the setting)."""

    kind: str = "cycle"

    #: the registry answers for the subclasses (:mod:`skinny_mj.training.overrides`:
    #: a choice of types whose members are registered at run time)
    REGISTRY: ClassVar[bool] = True

    @classmethod
    def choose(cls, name: str) -> type:
        """The settings type of the registered fit ``name`` (else the refusal)."""
        return FITS[check(name)].settings

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(FITS)

    def __post_init__(self) -> None:
        check(self.kind)


@dataclass(frozen=True)
class ForgettingSettings(FitSettings):
    """The remembering fits' (``forgetting``, ``rls``) setting."""

    kind: str = "forgetting"
    forgetting: float = 0.8  # old cycles' weight per learning cycle, in [0, 1]

    def __post_init__(self) -> None:
        super().__post_init__()
        if isinstance(self.forgetting, bool) or not 0 <= self.forgetting <= 1:
            raise SkinnyInputError(f"forgetting must be in [0, 1], got {self.forgetting}")


@dataclass(frozen=True)
class Fit:
    """A readout fit: how to build it (a :data:`Make`, or its name ``"module:function"``),
    the bodies (actuation kinds) it runs on, and the type of its settings (a
    :class:`FitSettings`, its fields the fit's hyper-parameters with their defaults)."""

    make: Make | str
    bodies: tuple[str, ...] = ("velocity", "torque")
    settings: type[FitSettings] = FitSettings


def _cycle(cfg: Any, esn: Any, steps: int) -> None:
    return None


def _ridge_select(cfg: Any, esn: Any, steps: int) -> Any:
    return RidgeSelector(esn, cfg.method.epochs)


FITS: dict[str, Fit] = {
    "cycle": Fit(_cycle),
    "ridge-select": Fit(_ridge_select, ("velocity",)),
    "forgetting": Fit("skinny_mj.training.torque:readout_fitter", ("torque",),
                      ForgettingSettings),
    "rls": Fit("skinny_mj.training.torque:readout_fitter", ("torque",), ForgettingSettings),
}


def register_fit(name: str, make: Make | str, *, bodies: tuple[str, ...] = ("velocity", "torque"),
                 settings: type[FitSettings] = FitSettings, replace: bool = False) -> Fit:
    """Make ``name`` a value of ``method.fit``: ``make(cfg, esn, steps)`` builds its rule
    (``make`` may be its name, ``"module:function"``), reading its hyper-parameters from
    ``cfg.method.fit`` (a ``settings``: a :class:`FitSettings` subclass whose fields are
    the keys ``method.fit.<param>``). A name already taken is refused unless ``replace``.
    Returns the registered :class:`Fit`, which a package publishes under ``name`` in
    :data:`FIT_GROUP` for other processes (the command line, a sweep's workers)."""
    if not name or not isinstance(name, str):
        raise SkinnyInputError(f"a fit's name is a non-empty string, got {name!r}")
    if name in FITS and not replace:
        raise SkinnyInputError(f"fit {name!r} is registered already (replace=True to "
                               "change it)")
    if not (isinstance(settings, type) and issubclass(settings, FitSettings)):
        raise SkinnyInputError(f"a fit's settings are a FitSettings subclass, got {settings!r}")
    FITS[name] = Fit(make, tuple(bodies), settings)
    return FITS[name]


def make_rule(cfg: Any, esn: Any, steps: int) -> Any:
    """The learning rule of ``cfg``'s FEL training (None: the default per-cycle fit)."""
    make = FITS[cfg.method.fit.kind].make  # (the module's FITS, as registered)
    if isinstance(make, str):
        module, _, name = make.partition(":")
        make = getattr(importlib.import_module(module), name)
    return make(cfg, esn, steps)


def refusal(name: str) -> str:
    """The one line that refuses ``name`` as a value of ``method.fit``."""
    return f"fit must be one of {tuple(FITS)}, got {name!r}"


def check(name: str) -> str:
    """``name`` if it is a registered fit (:func:`known`), else a :class:`SkinnyInputError`."""
    if not known(name):
        raise SkinnyInputError(refusal(name))
    return name


def known(name: str) -> bool:
    """Is ``name`` a registered fit? An unknown name first reads :data:`FIT_GROUP`."""
    if name not in FITS:
        for found, fit in plugins.load_group(FIT_GROUP, Fit, "skinny_mj.training.fits.Fit"):
            FITS.setdefault(found, fit)
    return name in FITS
