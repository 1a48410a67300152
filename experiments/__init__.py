"""One study per module, and per question beyond the thesis; each regenerates its table
and figures through the shared engine. A study module declares ``NAME`` and a
``STUDY`` (:class:`skinny_mj.engine.study.Study`: a base config, rows of overrides, the paper's
numbers), or follows the older module contract of :mod:`skinny_mj.engine.experiment`
(``NAME``, ``build``, ``report``). :mod:`skinny_mj.engine.registry` finds every module here that
sets ``NAME``: a new study is one new file.
"""

from __future__ import annotations

from typing import Any

from skinny_mj.engine import registry


def get(name: str) -> Any:
    """The study registered as ``name`` (:func:`skinny_mj.engine.registry.get`)."""
    return registry.get(name)


def describe(name: str) -> str:
    """First paragraph of a study's description (:func:`skinny_mj.engine.registry.describe`)."""
    return registry.describe(name)
