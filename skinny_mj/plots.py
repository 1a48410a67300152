"""Figures as PNG files (matplotlib, Agg backend: no display needed).

Every function takes the output path first, writes atomically and returns the path.
The paper's values, where given, are drawn as black diamonds labelled "paper".
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_path

DPI = 120


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend (headless), imported on
    first use so that importing this module stays cheap."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path: str | Path,
                rect: tuple[float, float, float, float] | None = None) -> Path:
    """Write ``fig`` as a PNG atomically (temp file + rename), close it, return the path;
    ``rect``: the part of the figure the axes are laid out in (room for a figure legend)."""
    plt = pyplot()
    path = Path(path)
    try:
        fig.tight_layout(rect=rect)
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=DPI)
    finally:
        plt.close(fig)
    return path


def _mean_sd(values: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(E,) -> (values, None); (R, E) -> (mean over runs, sd over runs)."""
    values = np.asarray(values, dtype=float)
    if values.ndim == 1:
        return values, None
    if values.ndim == 2:
        return np.nanmean(values, axis=0), np.nanstd(values, axis=0)
    raise SkinnyInputError(f"a curve must be (E,) or (R, E), got shape {values.shape}")


def learning_curve_png(path: str | Path, curves: Mapping[str, np.ndarray], ylabel: str, *,
                       xlabel: str = "epoch", title: str = "", log_y: bool = False) -> Path:
    """Learning curves: name -> (E,) values or (R, E) runs (drawn as mean ± sd band)."""
    if not curves:
        raise SkinnyInputError("learning_curve_png needs at least one curve")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for name, values in curves.items():
        mean, sd = _mean_sd(values)
        _mean_band(ax, np.arange(1, len(mean) + 1), mean, sd, name)
    if log_y:
        ax.set_yscale("log")
    ax.set(xlabel=xlabel, ylabel=ylabel, title=title)
    ax.grid(alpha=0.3)
    ax.legend()
    return save_figure(fig, path)


def _mean_band(ax, x: np.ndarray, mean: np.ndarray, sd: np.ndarray | None, name: str) -> None:
    """A mean line with markers and, over several runs, a ± sd band in its colour."""
    (line,) = ax.plot(x, mean, marker="o", markersize=3, label=name)
    if sd is not None:
        ax.fill_between(x, mean - sd, mean + sd, color=line.get_color(), alpha=0.2)


def boxplot_png(path: str | Path, groups: Mapping[str, Sequence[float]], ylabel: str,
                reference: Mapping[str, float] | None = None, *, title: str = "") -> Path:
    """One box per group of run values; ``reference`` (the paper's means) as markers."""
    if not groups:
        raise SkinnyInputError("boxplot_png needs at least one group")
    plt = pyplot()
    names = list(groups)
    data = [np.asarray(groups[n], dtype=float) for n in names]
    data = [d[np.isfinite(d)] for d in data]
    fig, ax = plt.subplots(figsize=(max(4.0, 1.1 * len(names) + 2), 4.0))
    positions = np.arange(1, len(names) + 1)
    ax.boxplot([d if d.size else [np.nan] for d in data], positions=positions, widths=0.6)
    ax.set_xticks(positions, names, rotation=20 if len(names) > 4 else 0)
    if reference:
        xs = [p for p, n in zip(positions, names, strict=True) if n in reference]
        ys = [reference[n] for n in names if n in reference]
        ax.scatter(xs, ys, marker="D", color="black", zorder=3, label="paper")
        ax.legend()
    ax.set(ylabel=ylabel, title=title)
    ax.grid(axis="y", alpha=0.3)
    return save_figure(fig, path)


def line_sweep_png(path: str | Path, x: Sequence[float], ys: Mapping[str, np.ndarray],
                   xlabel: str, ylabel: str, *, title: str = "", log_x: bool = False) -> Path:
    """A parameter sweep: name -> (R, len(x)) run values, drawn as mean ± sd over runs."""
    if not ys:
        raise SkinnyInputError("line_sweep_png needs at least one series")
    x = np.asarray(x, dtype=float)
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for name, values in ys.items():
        values = np.atleast_2d(np.asarray(values, dtype=float))
        if values.shape[-1] != len(x):
            raise SkinnyInputError(
                f"series {name!r} has {values.shape[-1]} points, x has {len(x)}")
        _mean_band(ax, x, *_mean_sd(values), name)
    if log_x:
        ax.set_xscale("log")
    ax.set(xlabel=xlabel, ylabel=ylabel, title=title)
    ax.grid(alpha=0.3)
    ax.legend()
    return save_figure(fig, path)


def heatmap_png(path: str | Path, matrix: np.ndarray, row_labels: Sequence[str],
                col_labels: Sequence[str], title: str = "", *, fmt: str = "{:.3f}") -> Path:
    """A labelled heat map of ``matrix`` (n_rows, n_cols), values written in the cells."""
    matrix = np.asarray(matrix, dtype=float)
    if matrix.shape != (len(row_labels), len(col_labels)):
        raise SkinnyInputError(f"matrix shape {matrix.shape} does not match "
                               f"{len(row_labels)} row and {len(col_labels)} column labels")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(1.0 + 0.9 * len(col_labels), 1.0 + 0.5 * len(row_labels)))
    image = ax.imshow(matrix, cmap="viridis", aspect="auto")
    fig.colorbar(image, ax=ax)
    ax.set_xticks(range(len(col_labels)), col_labels, rotation=30, ha="right")
    ax.set_yticks(range(len(row_labels)), row_labels)
    if matrix.size <= 400:
        mid = np.nanmean(matrix) if np.isfinite(matrix).any() else 0.0
        for (i, j), v in np.ndenumerate(matrix):
            ax.text(j, i, fmt.format(v), ha="center", va="center", fontsize=7,
                    color="white" if v < mid else "black")
    ax.set_title(title)
    return save_figure(fig, path)
