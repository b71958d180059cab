"""Figures with matplotlib (non-interactive backend): line plots of recorded results."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def lines(path: Path, title: str, t, series: dict, ylabel: str,
          xlabel: str = "time [s]") -> Path:
    """One axes: each named series against time (or ``xlabel``)."""
    return panels(path, title, [(t, series, ylabel)], xlabel)


def panels(path: Path, title: str, rows, xlabel: str = "time [s]") -> Path:
    """Stacked axes, one per (t, {label: values}, ylabel) row."""
    fig, axes = plt.subplots(len(rows), 1, figsize=(8, 3.2 * len(rows)), squeeze=False)
    for ax, (t, series, ylabel) in zip(axes[:, 0], rows):
        for label, values in series.items():
            ax.plot(t, values, label=label, linewidth=1.2)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if len(series) > 1:
            ax.legend(fontsize=8, ncol=min(len(series), 3))
    return _save(fig, axes, path, title, xlabel)


def requirement(path: Path, title: str, x, rows, met, xlabel: str) -> Path:
    """Metrics against a design variable (log x), each with its requirement line; points
    that meet every requirement filled, the others open."""
    fig, axes = plt.subplots(len(rows), 1, figsize=(8, 3.2 * len(rows)), squeeze=False)
    for ax, (label, values, limit) in zip(axes[:, 0], rows):
        ax.plot(x, values, color="0.6", linewidth=1)
        for xi, v, ok in zip(x, values, met):
            ax.plot(xi, v, "o", color="tab:green" if ok else "tab:red",
                    fillstyle="full" if ok else "none")
        ax.axhline(limit, color="tab:blue", linestyle="--", label="requirement")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    return _save(fig, axes, path, title, xlabel)


def _save(fig, axes, path: Path, title: str, xlabel: str) -> Path:
    """Label the stacked axes, write the figure, free it."""
    axes[-1, 0].set_xlabel(xlabel)
    axes[0, 0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
