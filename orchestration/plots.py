"""Figures with matplotlib (non-interactive backend): line plots of recorded results."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def lines(path: Path, title: str, t, series: dict, ylabel: str) -> Path:
    """One axes: each named series against time."""
    return panels(path, title, [(t, series, ylabel)])


def panels(path: Path, title: str, rows) -> Path:
    """Stacked axes, one per (t, {label: values}, ylabel) row."""
    fig, axes = plt.subplots(len(rows), 1, figsize=(8, 3.2 * len(rows)), squeeze=False)
    for ax, (t, series, ylabel) in zip(axes[:, 0], rows):
        for label, values in series.items():
            ax.plot(t, values, label=label, linewidth=1.2)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if len(series) > 1:
            ax.legend(fontsize=8, ncol=min(len(series), 3))
    axes[-1, 0].set_xlabel("time [s]")
    axes[0, 0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
