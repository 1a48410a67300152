"""A saved inverse model (``model.npz`` of ``skinny train``, or a shipped model's name)
read for ``skinny test``: a file that is not one, or whose metadata, configuration and
weights disagree, is one :class:`~skinny_mj.errors.SkinnyInputError` naming the file."""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.controllers.esn import ESN, read_metadata
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.parts import network_sizes
from skinny_mj.training.presets import SHIPPED_NAMES, model_path

#: What reading a damaged .npz raises (zip errors, an empty file, a bad JSON config).
_UNREADABLE = (OSError, ValueError, KeyError, TypeError, EOFError, NotImplementedError,
               zipfile.BadZipFile)


def read_model(model: str | Path) -> tuple[Path, ESN, dict[str, Any]]:
    """``(path, network, metadata)`` of a saved model; the metadata's ``body`` (a name;
    an earlier model's ``dof`` and ``actuation`` name Skinny's) and ``signals`` name a body
    and a signal set, ``dof`` is the body's number of hinges, ``max_speed_rad_s`` is
    (dof,) finite speeds > 0 rad/s (as a float array)."""
    path = model_path(model)  # a shipped model's name, or a file
    if path.is_dir():
        raise SkinnyInputError("a folder, not a model file", path=path)
    if not path.is_file():
        raise SkinnyInputError("no such model file (shipped models: "
                               f"{', '.join(SHIPPED_NAMES)})",
                               path=path)
    if not zipfile.is_zipfile(path):  # else numpy's "pickled data ... allow_pickle" advice
        raise SkinnyInputError("not a model written by `skinny train` (not an .npz archive)",
                               path=path)
    try:
        meta = read_metadata(path)
        _check_weights(path)
        esn = ESN.load(path)
    except SkinnyInputError:
        raise
    except _UNREADABLE as err:
        text = " ".join(str(err).split()) or type(err).__name__
        if "allow_pickle" in text:  # numpy's advice to load it unsafely: not ours to give
            text = "it holds pickled Python objects, which are not loaded: they can run code"
        raise SkinnyInputError(f"not a model written by `skinny train` ({text})",
                               path=path) from None
    if not isinstance(meta, dict) or not {"signals", "max_speed_rad_s"} <= meta.keys() \
            or not {"body", "dof"} & meta.keys():
        raise SkinnyInputError("model has no Skinny metadata (body, signals, max speed)",
                               path=path)
    try:
        name = body.body_name(meta["body"]) if "body" in meta else body.by_dof(
            meta["dof"], meta.get("actuation", "velocity"))
        dof = body.body_of(name).dof
        signals = body.check_signals(meta["signals"])
    except SkinnyInputError as err:
        raise SkinnyInputError(f"model metadata: {err}", path=path) from None
    try:
        speed = np.asarray(meta["max_speed_rad_s"], dtype=float)
    except (TypeError, ValueError):
        speed = np.zeros(0)
    if speed.shape != (dof,) or not np.all(np.isfinite(speed) & (speed > 0)):
        raise SkinnyInputError(f"model metadata: max_speed_rad_s must be {dof} finite speeds "
                               f"> 0 rad/s, got {meta['max_speed_rad_s']!r}", path=path)
    return path, esn, {**meta, "body": name, "dof": dof, "signals": signals,
                       "max_speed_rad_s": speed}


#: The arrays of the network's weights in a model file (its state x, y is reset by a test).
_WEIGHTS = ("W", "W_in", "W_back", "W_out")


def _check_weights(path: Path) -> None:
    """Refuse weights no training writes: complex (float() would drop the imaginary part,
    warning) or NaN or infinite (the first command would be NaN, the plant unstable)."""
    with np.load(path, allow_pickle=False) as data:
        for name in _WEIGHTS:
            w = data[name]
            if not np.issubdtype(w.dtype, np.floating):
                raise SkinnyInputError(f"the weights {name} are {w.dtype}, not real numbers "
                                       "(an edited file?)", path=path)
            if not np.all(np.isfinite(w)):
                where = tuple(int(i) for i in np.argwhere(~np.isfinite(w))[0])
                raise SkinnyInputError(f"the weights {name} hold {w[where]} at {where}: not a "
                                       "model a training wrote (an edited file?)", path=path)


def check_model(esn: ESN, config: TrainConfig, path: Path) -> None:
    """Refuse a network that cannot run as ``config`` (its metadata's plant and training
    configuration) says: one trained beside a forward model (the file holds the inverse
    network only), one whose inputs and outputs are not the plant's, or whose weights
    disagree with its own configuration (a model of another body, or an edited file)."""
    if config.forward.kind != "none":
        raise SkinnyInputError(f"the model was trained with a forward model (forward="
                               f"{config.forward.kind}), which the file does not hold: "
                               "`skinny test` runs a network trained without one", path=path)
    _, n_out, n_in = network_sizes(config)
    cfg = esn.cfg
    if (cfg.n_inputs, cfg.n_outputs) != (n_in, n_out):
        raise SkinnyInputError(f"the network has {cfg.n_inputs} inputs and {cfg.n_outputs} "
                               f"outputs; its metadata's plant needs {n_in} and {n_out} "
                               "(a model of another body, or an edited file)", path=path)
    n = esn.W.shape[-1]
    k = esn.W_in.shape[-1]
    shapes = {"W": (esn.W.shape[-2:], (n, n)), "W_out": (esn.W_out.shape[-2:], (n_out, n + k)),
              "W_back": (esn.W_back.shape[-2:], (n, n_out)), "W_in": (esn.W_in.shape[-2:], (n, k))}
    wrong = [f"{name} {got}, expected {want}" for name, (got, want) in shapes.items()
             if tuple(got) != want]
    if wrong or k not in (n_in, n_in + 1):
        raise SkinnyInputError(f"the network's weights disagree with its configuration: "
                               f"{'; '.join(wrong) or f'W_in has {k} columns for {n_in} inputs'}",
                               path=path)
