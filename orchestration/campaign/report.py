"""A campaign's table, statistics, pass rates, figures and progress.

Pass rates: for each requirement the scenario judges (each run's verdict, ``met``, ``not
met``, ``not evaluated``; :mod:`..mission.requirements`), the fraction of runs that meet
it, with the two-sided 95 % Clopper-Pearson (exact binomial) interval: lower = B(α/2; k,
n − k + 1), upper = B(1 − α/2; k + 1, n − k), B the beta quantile
(``scipy.special.betaincinv``).  It never undercovers, and with k = n it gives the lower
bound (α/2)^(1/n) engineers quote ("n passes out of n: p ≥ … at 97.5 % one-sided").
Every run counts in n: a run that stopped (``error``), was ``lost`` or could not be
evaluated meets nothing (each counted apart).
"""

from __future__ import annotations

import csv
import math
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

from ..output.recorder import atomically
from ..system.units import display_factor, pretty

PERCENTILES = (1, 5, 50, 95, 99)
STATUSES = ("ok", "failed", "error", "lost")


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    from scipy.special import betaincinv  # type: ignore[import-untyped]

    if n == 0:
        return (0.0, 1.0)
    alpha = 1 - confidence
    low = 0.0 if k == 0 else float(betaincinv(k, n - k + 1, alpha / 2))
    high = 1.0 if k == n else float(betaincinv(k + 1, n - k, 1 - alpha / 2))
    return low, high


def columns(plan, catalog: dict) -> list[tuple[str, str]]:
    """(name, kind) of the table's columns; kind: i (int), f (float), b (bool), s (str).
    ``catalog``: {"metrics": ..., "requirements": ...} (:func:`.engine.catalog`)."""
    cols = [("index", "i"), ("seed", "i"), ("grid", "i")]
    cols += [(name, plan.kinds[name]) for name in plan.columns]
    cols += [("status", "s"), ("message", "s")]
    cols += [(name, "f") for name in catalog.get("metrics", {})]
    for name, requirement in catalog.get("requirements", {}).items():
        if requirement.get("judged_over") != "campaign":  # else: "judged over the campaign"
            cols.append((f"met_{name}", "b"))
        cols.append((f"verdict_{name}", "s"))
    return cols + [("worker", "s"), ("seconds", "f"), ("cpu_seconds", "f")]


def warm_ups(records: dict) -> dict:
    """The workers' warm-ups (:mod:`.worker`; one per worker process, in the record of its
    first batch's first run): their wall and CPU seconds in all and per process, and the
    errors they raised.  A cost of the campaign, not of its runs' ``seconds``.  A warm-up
    whose batch was lost with its worker process is not counted: its record is lost too."""
    made = [r for _, r in sorted(records.items()) if "warm_up_seconds" in r]
    return {
        "processes": len(made),
        "seconds": sum((r["warm_up_seconds"] for r in made), 0.0),
        "cpu_seconds": sum((r.get("warm_up_cpu_seconds", 0.0) for r in made), 0.0),
        "workers": [
            {
                "worker": r.get("worker", ""),
                "pid": r.get("pid"),
                "seconds": r["warm_up_seconds"],
                "cpu_seconds": r.get("warm_up_cpu_seconds"),
                **({"error": r["warm_up_error"]} if "warm_up_error" in r else {}),
            }
            for r in made
        ],
    }


def _cell(record: dict, name: str, kind: str):
    if name in record.get("values", {}):
        return record["values"][name]
    verdicts = record.get("requirements", {})
    if name.startswith("met_") and kind == "b":
        return verdicts.get(name[4:]) == "met"
    if name.startswith("verdict_") and kind == "s":
        return verdicts.get(name[8:], "")
    if name in record.get("metrics", {}) and name not in ("index", "seed", "grid"):
        value = record["metrics"][name]["value"]
        return math.nan if value is None else value
    value = record.get(name)
    return (math.nan if kind == "f" else "") if value is None else value


def table(plan, records: dict, catalog: dict):
    """The runs as a NumPy structured array, in index order (a metric without a value:
    NaN; runs.csv writes it as an empty cell)."""
    cols = columns(plan, catalog)
    rows = [tuple(_cell(records[i], n, k) for n, k in cols) for i in sorted(records)]
    width = {
        n: max([1] + [len(str(r[j])) for r in rows]) for j, (n, k) in enumerate(cols) if k == "s"
    }
    dtype = [(n, {"i": "i8", "f": "f8", "b": "?"}.get(k) or f"U{width[n]}") for n, k in cols]
    return np.array(rows, dtype=dtype)


def write_table(array: np.ndarray, out: Path) -> list[Path]:
    """runs.csv (floats written exactly: repr round-trips; no value: an empty cell), and
    runs.parquet with pyarrow."""
    path = out / "runs.csv"
    with atomically(path) as temporary, temporary.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(array.dtype.names)
        for row in array.tolist():
            writer.writerow([_text(x) for x in row])
    written = [path]
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    with atomically(out / "runs.parquet") as temporary:
        pq.write_table(pa.table({n: array[n] for n in array.dtype.names}), temporary)
    return written + [out / "runs.parquet"]


def _text(x) -> object:
    if isinstance(x, float):
        return "" if math.isnan(x) else repr(x)
    return x


def statistics(array: np.ndarray, catalog: dict, records: dict | None = None) -> dict:
    """Per metric over the runs that have a value: count, mean, sd, min, max, percentiles;
    ``missing``: the runs without a value, and why (``reasons``: {reason: runs})."""
    stats = {}
    for name, meta in catalog.get("metrics", {}).items():
        values = array[name][np.isfinite(array[name])]
        entry = {
            "unit": meta["unit"],
            "display_unit": meta.get("display_unit"),
            "description": meta.get("description"),
            "count": int(len(values)),
            "missing": int(len(array) - len(values)),
        }
        reasons: dict[str, int] = {}
        for record in (records or {}).values():
            reason = record.get("metrics", {}).get(name, {}).get("reason")
            if reason is not None:
                key = _reason(reason)
                reasons[key] = reasons.get(key, 0) + 1
        if reasons:
            entry["reasons"] = reasons
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


def _reason(text: str) -> str:
    """A reason without its run's numbers, so that the runs' reasons group: 'not settled:
    |x| > 0.01 at the end of the run (t = 150 s)' -> 'not settled'."""
    return text.split(":")[0].strip() if ":" in text else text


def pass_rates(array: np.ndarray, catalog: dict, rows=None) -> dict:
    """Per requirement judged and for all of them together (``all``): the runs that met
    it, with the Clopper-Pearson 95 % interval; every run counts (one that stopped or was
    not evaluated meets nothing), and the runs not met, not evaluated and stopped are
    counted apart.  A requirement the variant does not judge has no pass rate, nor has
    one judged over the whole campaign (an ensemble statistic: campaign.json's
    ``ensemble``)."""
    rows = np.ones(len(array), bool) if rows is None else rows
    names = [
        n
        for n, r in catalog.get("requirements", {}).items()
        if "not_judged" not in r and r.get("judged_over") != "campaign"
    ]
    rates = {}
    for name, verdicts in [(n, array[f"verdict_{n}"][rows]) for n in names] + (
        [("all", _all(array[rows], names))] if len(names) > 1 else []
    ):
        k, n = int(np.sum(verdicts == "met")), int(len(verdicts))
        low, high = clopper_pearson(k, n)
        rates[name] = {
            "met": k,
            "not_met": int(np.sum(verdicts == "not met")),
            "not_evaluated": int(np.sum(verdicts == "not evaluated")),
            "stopped": int(np.sum(verdicts == "")),
            "runs": n,
            "rate": k / n if n else None,
            "ci95": [low, high],
            "method": "Clopper-Pearson",
        }
    return rates


def _all(array: np.ndarray, names: list[str]) -> np.ndarray:
    """Per run: "met" if every requirement is met, else the first other verdict."""
    verdicts = np.full(len(array), "met", dtype=object)
    for name in names:
        column = array[f"verdict_{name}"]
        verdicts = np.where((verdicts == "met") & (column != "met"), column, verdicts)
    return verdicts.astype(str)


def grid_pass_rates(plan, array: np.ndarray, catalog: dict) -> list[dict]:
    """For a sweep: each grid point's values and pass rates."""
    if not plan.grid_keys:
        return []
    return [
        {
            "values": {
                k: plan.choices[k][int(v)] if k in plan.choices else v
                for k, v in zip(plan.grid_keys, point)
            },
            "pass_rates": pass_rates(array, catalog, array["grid"] == g),
        }
        for g, point in enumerate(plan.grid)
    ]


def group_pass_rates(array: np.ndarray, catalog: dict, key: str, edges=()) -> list[dict]:
    """The pass rates of the runs grouped by the dispersed column ``key`` (a fault's time,
    which unit fails, ...): one group per value, or with ``edges`` e₀ < e₁ < … one per
    interval [e_k, e_k+1), the values below e₀ and from the last edge on in groups of
    their own; an infinite value ("never") is always its own group.  Each group:
    {"group": its label, "runs": n, "pass_rates": as :func:`pass_rates`}."""
    if key not in (array.dtype.names or ()):
        raise ValueError(f"--group-by {key}: not a column of the campaign's table")
    column = array[key]
    if column.dtype.kind != "f":
        labels = column.astype(str)
    else:
        labels = np.array([_interval(x, edges) for x in column.tolist()], dtype=object)
    order = sorted(set(labels.tolist()), key=lambda label: _order(label, column, labels))
    return [
        {
            "group": label,
            "runs": int(np.sum(labels == label)),
            "pass_rates": pass_rates(array, catalog, labels == label),
        }
        for label in order
    ]


def _interval(x: float, edges) -> str:
    """The label of x's group: its value, 'inf', or its interval of ``edges``."""
    if math.isinf(x) or not edges:
        return "inf" if x == math.inf else "-inf" if x == -math.inf else f"{x:.6g}"
    if x < edges[0]:
        return f"< {edges[0]:g}"
    for low, high in zip(edges, edges[1:]):
        if x < high:
            return f"[{low:g}, {high:g})"
    return f">= {edges[-1]:g}"


def _order(label: str, column: np.ndarray, labels: np.ndarray):
    """Groups in the order of their smallest value (an infinite one last)."""
    return float(np.min(column[labels == label])) if column.dtype.kind == "f" else label


def display(meta: dict) -> tuple[float, str]:
    """(factor, unit as people write it) of a metric's display unit."""
    unit, shown = meta["unit"], meta.get("display_unit") or meta["unit"]
    factor = display_factor(unit, shown)
    return (1.0, pretty(unit)) if factor is None else (factor, pretty(shown))


def histograms(
    array: np.ndarray, catalog: dict, out: Path, nominal: dict | None = None
) -> list[Path]:
    """A histogram of each metric that varies over the runs, titled by its description,
    with its requirement's bounds, the paper's value and the nominal run's (``nominal``:
    {metric: SI value}); a constant metric has none: one value says it all.  The legend
    stands beside the axes, off the bars."""
    from ..output.plots import plt

    paths = []
    for name, meta in catalog.get("metrics", {}).items():
        values = array[name][np.isfinite(array[name])]
        if not len(values) or np.ptp(values) <= 1e-9 * max(np.abs(values).max(), 1e-300):
            continue
        scale, unit = display(meta)
        fig, ax = plt.subplots(figsize=(7.5, 3.6))
        ax.hist(
            values * scale,
            bins=min(50, max(5, int(np.sqrt(len(values))))),
            color="tab:blue",
            alpha=0.75,
            histtype="stepfilled",  # the bars' outline as one polygon: as drawn, no seams
        )
        for bound, value in meta.get("requirement", {}).items():
            ax.axvline(
                value * scale, color="tab:red", linestyle="--", label=f"requirement ({bound})"
            )
        if meta.get("paper") is not None:
            ax.axvline(meta["paper"] * scale, color="0.35", linestyle=":", label="paper")
        if (nominal or {}).get(name) is not None:
            ax.axvline(nominal[name] * scale, color="black", linewidth=1.2, label="nominal run")
        if ax.get_legend_handles_labels()[1]:
            ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        ax.set_xlabel(f"{name} [{unit}]" if unit else name)
        ax.set_ylabel("runs")
        missing = len(array) - len(values)
        ax.set_title(
            _described(meta)
            + f"{len(values)} runs"
            + (f" ({missing} without a value)" if missing else ""),
            fontsize=10,
        )
        paths.append(_save(fig, ax, out / f"hist_{name}.png"))
    return paths


def sweeps(plan, array: np.ndarray, catalog: dict, out: Path) -> list[Path]:
    """For a sweep: each metric against each swept parameter (every run a point, the
    median per grid value a line; one series per value of the other swept parameters),
    with its requirement's bounds."""
    from ..output.plots import plt

    paths = []
    for name, meta in catalog.get("metrics", {}).items():
        if not np.isfinite(array[name]).any():
            continue
        scale, unit = display(meta)
        for key in plan.grid_keys:
            others = [k for k in plan.grid_keys if k != key]
            fig, ax = plt.subplots(figsize=(7, 4))
            groups = sorted({tuple(row[k] for k in others) for row in array}, key=str)
            for group in groups:
                chosen = np.ones(len(array), bool)
                for k, v in zip(others, group):
                    chosen &= array[k] == v
                x, y = array[key][chosen], array[name][chosen] * scale
                label = ", ".join(f"{k} = {_shown(v)}" for k, v in zip(others, group))
                points = ax.plot(x, y, "o", markersize=3, alpha=0.5, label=label or None)[0]
                grid = sorted(set(x.tolist()))
                medians = [np.nanmedian(y[x == g]) for g in grid]
                ax.plot(grid, medians, "-", color=points.get_color(), linewidth=1.4)
            for bound, value in meta.get("requirement", {}).items():
                label = f"requirement ({bound})"
                ax.axhline(value * scale, color="tab:red", linestyle="--", label=label)
            if meta.get("paper") is not None:
                ax.axhline(meta["paper"] * scale, color="0.35", linestyle=":", label="paper")
            ax.set_xlabel(key)
            ax.set_ylabel(f"{name} [{unit}]" if unit else name)
            ax.set_title(_described(meta) + f"against {key}: {len(array)} runs", fontsize=10)
            if ax.get_legend_handles_labels()[1]:
                ax.legend(fontsize=8)
            paths.append(_save(fig, ax, out / f"sweep_{name}_{_file_name(key)}.png"))
    return paths


def _described(meta: dict) -> str:
    """A metric's description as a title's first line(s), or nothing."""
    text = meta.get("description")
    return textwrap.fill(text, 80) + "\n" if text else ""


def _save(fig, ax, path: Path) -> Path:
    """A campaign figure written (grid, layout, the run figures' resolution; its title also
    in the PNG's "Title", for tools and tests that read files) and closed: laid out and
    drawn once (:mod:`.figure_save`)."""
    from ..output.plots import DPI, plt
    from .figure_save import save

    ax.grid(True, alpha=0.3)
    try:
        return save(fig, ax, path, DPI)
    finally:
        plt.close(fig)


def _shown(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def _file_name(name: str) -> str:
    return name.replace("[", "_").replace("]", "").replace(",", "_")


def envelopes(
    signals, names: list[str], units: dict, t: np.ndarray, out: Path, bounds=()
) -> list[Path]:
    """Percentile envelopes (1–99 %, 5–95 %, median) over time of each kept signal, with
    the scenario's bounds of it (:class:`..mission.scenario.SignalBound`): a requirement as
    a green band over its window, a limit as dashed red lines."""
    from ..output.plots import plt

    paths = []
    for j, name in enumerate(names):
        data = np.asarray(signals[:, j, :])
        data = data[np.isfinite(data).any(axis=1)]
        if not len(data):
            continue
        # the same percentiles; without a NaN (no run stopped early) in half the time
        quantiles = np.percentile if np.isfinite(data).all() else np.nanpercentile
        p = quantiles(data, PERCENTILES, axis=0)
        fig, ax = plt.subplots(figsize=(8, 3.6))
        ax.fill_between(t, p[0], p[4], color="tab:blue", alpha=0.2, label="1–99 %")
        ax.fill_between(t, p[1], p[3], color="tab:blue", alpha=0.4, label="5–95 %")
        ax.plot(t, p[2], color="tab:blue", linewidth=1.2, label="median")
        for bound in (b for b in bounds if b.applies_to(name)):
            _bound(ax, t, bound)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(f"{name} [{pretty(units.get(name)) or 'SI'}]")
        ax.set_title(f"{name}: {len(data)} runs", fontsize=10)
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside the data
        paths.append(_save(fig, ax, out / f"envelope_{_file_name(name)}.png"))
    return paths


def _bound(ax, t: np.ndarray, bound) -> None:
    """A signal bound on an envelope's axes, over its window of the time axis."""
    start = t[0] if bound.start is None else max(bound.start, t[0])
    stop = t[-1] if bound.stop is None else min(bound.stop, t[-1])
    if bound.limit or bound.low is None or bound.high is None:
        ys = [y for y in (bound.low, bound.high) if y is not None]
        ax.hlines(
            ys, start, stop, colors="tab:red", linestyles="--", linewidth=1, label=bound.label
        )
    else:
        ax.fill_between(
            [start, stop], bound.low, bound.high, color="tab:green", alpha=0.2, label=bound.label
        )


class Progress:
    """Runs done / failed, rate and ETA: a tqdm bar on a terminal, plain lines every
    ``period`` seconds otherwise (logs, CI).  ``before``: {status: count} of the ``done``
    runs an earlier session made (a resumed campaign counts its failures too)."""

    def __init__(
        self,
        total: int,
        done: int,
        enabled: bool = True,
        period: float = 10.0,
        stream=None,
        before: dict | None = None,
    ):
        self.stream = stream or sys.stderr
        self.total, self.done, self.todo = total, done, total - done
        self.counts = {s: (before or {}).get(s, 0) for s in STATUSES}
        self.made = 0  # by this session: the rate
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
        self.made += 1
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
        rate = self.made / elapsed if elapsed > 0 else 0.0
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
