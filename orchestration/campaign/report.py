"""A campaign's table, statistics, pass rates, figures and progress.

Pass rates: for each requirement the scenario declares (``"requirement"``/``"met"`` on a
summary metric), the fraction of runs that meet it, with the two-sided 95 % Clopper-Pearson
(exact binomial) interval: lower = B(α/2; k, n − k + 1), upper = B(1 − α/2; k + 1, n − k),
B the beta quantile (scipy).  It never undercovers, and with k = n it gives the lower
bound (α/2)^(1/n) engineers quote ("n passes out of n: p ≥ … at 97.5 % one-sided").  Every
run counts in n: a run that stopped (``error``) or was ``lost`` meets nothing.
"""

from __future__ import annotations

import csv
import math
import sys
import time
from pathlib import Path

import numpy as np

from ...fmus.model_description import UNITS

PERCENTILES = (1, 5, 50, 95, 99)
STATUSES = ("ok", "failed", "error", "lost")


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    from scipy.stats import beta

    if n == 0:
        return (0.0, 1.0)
    alpha = 1 - confidence
    low = 0.0 if k == 0 else float(beta.ppf(alpha / 2, k, n - k + 1))
    high = 1.0 if k == n else float(beta.ppf(1 - alpha / 2, k + 1, n - k))
    return low, high


def columns(plan, metrics: dict) -> list[tuple[str, str]]:
    """(name, kind) of the table's columns; kind: i (int), f (float), b (bool), s (str)."""
    cols = [("index", "i"), ("seed", "i"), ("grid", "i")]
    cols += [(name, plan.kinds[name]) for name in plan.columns]
    cols += [("status", "s"), ("message", "s")]
    cols += [(name, "f") for name in metrics]
    cols += [(f"met_{name}", "b") for name, m in metrics.items() if "requirement" in m]
    return cols + [("worker", "s"), ("seconds", "f")]


def _cell(record: dict, name: str, kind: str):
    if name in record.get("values", {}):
        return record["values"][name]
    if name.startswith("met_") and kind == "b":
        return bool(record["metrics"].get(name[4:], {}).get("met", False))
    if name in record.get("metrics", {}) and name not in ("index", "seed", "grid"):
        value = record["metrics"][name]["value"]
        return math.nan if value is None else value
    value = record.get(name)
    return (math.nan if kind == "f" else "") if value is None else value


def table(plan, records: dict, metrics: dict):
    """The runs as a NumPy structured array, in index order."""
    cols = columns(plan, metrics)
    rows = [tuple(_cell(records[i], n, k) for n, k in cols) for i in sorted(records)]
    width = {
        n: max([1] + [len(str(r[j])) for r in rows]) for j, (n, k) in enumerate(cols) if k == "s"
    }
    dtype = [(n, {"i": "i8", "f": "f8", "b": "?"}.get(k) or f"U{width[n]}") for n, k in cols]
    return np.array(rows, dtype=dtype)


def write_table(array: np.ndarray, out: Path) -> list[Path]:
    """runs.csv (floats written exactly: repr round-trips), and runs.parquet with pyarrow."""
    path = out / "runs.csv"
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(array.dtype.names)
        for row in array.tolist():
            writer.writerow([repr(x) if isinstance(x, float) else x for x in row])
    written = [path]
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    pq.write_table(pa.table({n: array[n] for n in array.dtype.names}), out / "runs.parquet")
    return written + [out / "runs.parquet"]


def statistics(array: np.ndarray, metrics: dict) -> dict:
    """Per metric over the runs that reached it: count, mean, sd, min, max, percentiles."""
    stats = {}
    for name, meta in metrics.items():
        values = array[name][np.isfinite(array[name])]
        entry = {
            "unit": meta["unit"],
            "display_unit": meta.get("display_unit"),
            "description": meta.get("description"),
            "count": int(len(values)),
        }
        if len(values):
            entry.update(
                mean=float(values.mean()),
                sd=float(values.std(ddof=1)) if len(values) > 1 else 0.0,
                min=float(values.min()),
                max=float(values.max()),
                percentiles={str(p): float(np.percentile(values, p)) for p in PERCENTILES},
            )
        if "requirement" in meta:
            entry["requirement"] = meta["requirement"]
        stats[name] = entry
    return stats


def pass_rates(array: np.ndarray, metrics: dict, rows=None) -> dict:
    """Clopper-Pearson 95 % pass rate per requirement and for all of them together."""
    rows = np.ones(len(array), bool) if rows is None else rows
    names = [n for n, m in metrics.items() if "requirement" in m]
    rates = {}
    for name, met in [(n, array[f"met_{n}"][rows]) for n in names] + (
        [("all", np.all([array[f"met_{n}"][rows] for n in names], axis=0))]
        if len(names) > 1
        else []
    ):
        k, n = int(np.sum(met)), int(len(met))
        low, high = clopper_pearson(k, n)
        rates[name] = {
            "met": k,
            "runs": n,
            "rate": k / n if n else None,
            "ci95": [low, high],
            "method": "Clopper-Pearson",
        }
    return rates


def grid_pass_rates(plan, array: np.ndarray, metrics: dict) -> list[dict]:
    """For a sweep: each grid point's values and pass rates."""
    if not plan.grid_keys:
        return []
    return [
        {
            "values": {
                k: plan.choices[k][int(v)] if k in plan.choices else v
                for k, v in zip(plan.grid_keys, point)
            },
            "pass_rates": pass_rates(array, metrics, array["grid"] == g),
        }
        for g, point in enumerate(plan.grid)
    ]


def display(meta: dict) -> tuple[float, str]:
    unit = meta.get("display_unit") or meta["unit"]
    return UNITS.get(meta["unit"], ({}, {}))[1].get(meta.get("display_unit"), 1.0), unit


def histograms(array: np.ndarray, metrics: dict, out: Path) -> list[Path]:
    from ..output.plots import plt

    paths = []
    for name, meta in metrics.items():
        values = array[name][np.isfinite(array[name])]
        if not len(values):
            continue
        scale, unit = display(meta)
        fig, ax = plt.subplots(figsize=(6, 3.6))
        spread = np.ptp(values) > 1e-9 * max(np.abs(values).max(), 1e-300)
        ax.hist(
            values * scale,
            bins=min(50, max(5, int(np.sqrt(len(values))))) if spread else 1,
            color="tab:blue",
            alpha=0.75,
        )
        for bound, value in meta.get("requirement", {}).items():
            ax.axvline(
                value * scale, color="tab:red", linestyle="--", label=f"requirement ({bound})"
            )
        if "requirement" in meta:
            ax.legend(fontsize=8)
        ax.set_xlabel(f"{name} [{unit}]")
        ax.set_ylabel("runs")
        ax.set_title(f"{name}: {len(values)} runs", fontsize=10)
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        path = out / f"hist_{name}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def envelopes(signals, names: list[str], units: dict, t: np.ndarray, out: Path) -> list[Path]:
    """Percentile envelopes (1–99 %, 5–95 %, median) over time of each kept signal."""
    from ..output.plots import plt

    paths = []
    for j, name in enumerate(names):
        data = np.asarray(signals[:, j, :])
        data = data[np.isfinite(data).any(axis=1)]
        if not len(data):
            continue
        p = np.nanpercentile(data, PERCENTILES, axis=0)
        fig, ax = plt.subplots(figsize=(8, 3.6))
        ax.fill_between(t, p[0], p[4], color="tab:blue", alpha=0.2, label="1–99 %")
        ax.fill_between(t, p[1], p[3], color="tab:blue", alpha=0.4, label="5–95 %")
        ax.plot(t, p[2], color="tab:blue", linewidth=1.2, label="median")
        ax.set_xlabel("time [s]")
        ax.set_ylabel(f"{name} [{units.get(name, 'SI')}]")
        ax.set_title(f"{name}: {len(data)} runs", fontsize=10)
        ax.legend(fontsize=8)
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        path = out / f"envelope_{name.replace('[', '_').replace(']', '').replace(',', '_')}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


class Progress:
    """Runs done / failed, rate and ETA: a tqdm bar on a terminal, plain lines every
    ``period`` seconds otherwise (logs, CI)."""

    def __init__(
        self, total: int, done: int, enabled: bool = True, period: float = 10.0, stream=None
    ):
        self.stream = stream or sys.stderr
        self.total, self.done, self.todo = total, done, total - done
        self.counts = dict.fromkeys(STATUSES, 0)
        self.began = self.last = time.monotonic()
        self.period, self.enabled = period, enabled
        self.bar = None
        if enabled and getattr(self.stream, "isatty", lambda: False)():
            from tqdm import tqdm

            self.bar = tqdm(
                total=total, initial=done, unit="run", file=self.stream, dynamic_ncols=True
            )

    def update(self, status: str) -> None:
        self.counts[status] = self.counts.get(status, 0) + 1
        self.done += 1
        if self.bar is not None:
            self.bar.set_postfix_str(self._outcomes(), refresh=False)
            self.bar.update(1)
        elif self.enabled and (
            time.monotonic() - self.last >= self.period or self.done == self.total
        ):
            self.last = time.monotonic()
            print(self.line(), file=self.stream, flush=True)

    def _outcomes(self) -> str:
        return (
            ", ".join(f"{v} {k}" for k, v in self.counts.items() if v and k != "ok")
            or "none failed"
        )

    def line(self) -> str:
        elapsed = time.monotonic() - self.began
        made = sum(self.counts.values())
        rate = made / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else math.inf
        return (
            f"campaign: {self.done}/{self.total} runs done ({self._outcomes()}), "
            f"{rate:.2f} runs/s, ETA {_duration(eta)}"
        )

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _duration(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "unknown"
    if seconds < 120:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.0f} min" if seconds < 7200 else f"{seconds / 3600:.1f} h"
