"""The report of a campaign (``agilesat report CAMPAIGN_DIR``): what ran; each
requirement's pass rate with its 95 % Clopper-Pearson interval and the verdicts over the
whole campaign; every metric's statistics beside the paper's value and the nominal run's;
the histograms; the envelopes of the kept signals, with the spread between the runs on a
log scale of its own (a 1–99 % band a thousand times narrower than the signal is
invisible beside it); a sweep's pass rates per grid point; the table of every run,
sortable; the failed runs with the command that replays each.

Everything is read from the directory: campaign.json, metrics.json, runs.csv and
signals.npy (:mod:`..campaign`)."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from ...system.units import display_factor, pretty, to_degrees
from . import figures
from .decimate import indices
from .page import Page, esc, facts, static_table, verdict

#: the buckets an envelope is thinned to (2 points each)
BUCKETS = 600
#: data spanning more than this ratio get a log axis
DECADES = 100.0
PERCENTILES = (0, 1, 5, 50, 95, 99, 100)


def build(directory: Path) -> Page:
    directory = Path(directory)
    summary = json.loads((directory / "campaign.json").read_text(encoding="utf-8"))
    catalog_path = directory / "metrics.json"
    catalog = json.loads(catalog_path.read_text(encoding="utf-8")) if catalog_path.exists() else {}
    metrics = catalog.get("metrics", {})
    spec, runs = summary["spec"], summary["runs"]
    page = Page(
        f"agilesat campaign {spec['target']}",
        f"{runs['made']} of {runs['planned']} runs made: {runs['ok']} ok, "
        f"{runs['failed']} failed (diagnosed), {runs['error']} stopped, "
        f"{runs['lost']} lost",
    )
    settings = summary.get("settings", {})
    page.add(
        facts(
            [
                ("status", summary.get("status")),
                ("runs per grid point", spec.get("runs")),
                ("seed", spec.get("seed")),
                ("dispersions", "; ".join(spec.get("vary") or []) or None),
                (
                    "set",
                    ", ".join(f"{k} = {v}" for k, v in (spec.get("set") or {}).items()) or None,
                ),
                ("kept", ", ".join(spec.get("keep") or []) or None),
                (
                    "time",
                    f"{settings.get('start', 0):g} … {settings.get('stop', 0):g} s, step "
                    f"{settings.get('step', 0):g} s"
                    if settings
                    else None,
                ),
                ("agilesat", (summary.get("versions") or {}).get("agilesat")),
                ("nominal run", (summary.get("nominal") or {}).get("command")),
            ]
        )
    )
    _verdicts(page, summary)
    table = _read_table(directory / "runs.csv")
    _statistics(page, summary, metrics)
    _histograms(page, summary, metrics, table)
    _envelopes(page, directory, summary)
    _grid(page, summary)
    _runs(page, table, summary)
    _failures(page, summary)
    return page


def _display(meta: dict) -> tuple[float, str]:
    """(factor, unit as people write it) of a metric's display unit."""
    unit = meta.get("unit")
    shown = meta.get("display_unit") or unit
    factor = display_factor(unit, shown)
    return (1.0, pretty(unit)) if factor is None else (factor, pretty(shown))


def _verdicts(page: Page, summary: dict) -> None:
    statements = {n: r.get("statement", n) for n, r in (summary.get("requirements") or {}).items()}
    rates = summary.get("pass_rates") or {}
    if rates:
        page.heading("Pass rates", "pass-rates")
        rows = []
        for name, r in rates.items():
            low, high = r["ci95"]
            rows.append(
                [
                    esc("all requirements" if name == "all" else statements.get(name, name)),
                    f"{r['met']}/{r['runs']}",
                    "—" if r["rate"] is None else f"{100 * r['rate']:.2f} %",
                    f"{100 * low:.2f} – {100 * high:.2f} %",
                    str(r["not_met"]),
                    str(r["not_evaluated"]),
                    str(r["stopped"]),
                ]
            )
        page.add(
            static_table(
                [
                    "requirement",
                    "met",
                    "rate",
                    "95 % interval (Clopper-Pearson)",
                    "not met",
                    "not evaluated",
                    "stopped",
                ],
                rows,
                numeric=(1, 2, 3, 4, 5, 6),
            )
        )
        names = list(rates)
        rate = [100 * (rates[n]["rate"] or 0) for n in names]
        layout = figures.stacked(
            ["runs meeting each requirement [%], with the 95 % interval"],
            46 * len(names) + 60,
            shared=False,
        )
        layout["xaxis"].update(range=[0, 100.5], title={"text": "runs that met it [%]"})
        layout["yaxis"].update(automargin=True, autorange="reversed")
        layout["hovermode"] = "closest"
        labels = ["all requirements" if n == "all" else n for n in names]
        page.figure(
            {
                "data": [
                    {
                        "type": "bar",
                        "orientation": "h",
                        "x": rate,
                        "y": labels,
                        "marker": {
                            "color": [
                                "#2ca02c" if rates[n]["not_met"] == 0 else "#d62728" for n in names
                            ]
                        },
                        "error_x": {
                            "type": "data",
                            "symmetric": False,
                            "array": [100 * rates[n]["ci95"][1] - r for n, r in zip(names, rate)],
                            "arrayminus": [
                                r - 100 * rates[n]["ci95"][0] for n, r in zip(names, rate)
                            ],
                            "color": "#333",
                        },
                        "hovertemplate": "%{y}: %{x:.2f} %<extra></extra>",
                    }
                ],
                "layout": layout,
            }
        )
    ensemble = summary.get("ensemble") or {}
    if ensemble:
        page.heading("Judged over the whole campaign", "ensemble")
        page.add(
            static_table(
                ["requirement", "verdict", "what the campaign shows"],
                [
                    [
                        esc(r.get("statement", n)),
                        verdict(r.get("verdict")),
                        esc(r.get("text") or r.get("reason") or ""),
                    ]
                    for n, r in ensemble.items()
                ],
            )
        )
    judged = summary.get("not_judged") or {}
    if judged:
        page.add(
            "<p>Not judged: "
            + "; ".join(f"{esc(statements.get(n, n))} ({esc(why)})" for n, why in judged.items())
            + "</p>"
        )


def _statistics(page: Page, summary: dict, metrics: dict) -> None:
    stats = summary.get("statistics") or {}
    if not stats:
        return
    nominal = (summary.get("nominal") or {}).get("metrics", {})
    page.heading("Metrics over the runs", "statistics")
    rows = []
    for name, s in stats.items():
        meta = {**metrics.get(name, {}), **s}
        factor, unit = _display(meta)

        def shown(value, factor=factor):
            return "" if value is None else f"{value * factor:.5g}"

        p = s.get("percentiles") or {}
        requirement = meta.get("requirement")
        bound = ""
        if isinstance(requirement, dict):
            low, high = requirement.get("min"), requirement.get("max")
            bound = (
                f"[{shown(low)}, {shown(high)}]"
                if low is not None and high is not None
                else f"≤ {shown(high)}"
                if high is not None
                else f"≥ {shown(low)}"
            )
        rows.append(
            [
                f"<code>{esc(name)}</code>"
                + (
                    f'<br><span class="note">{esc(s["description"])}</span>'
                    if s.get("description")
                    else ""
                ),
                esc(unit),
                shown(s.get("mean")),
                shown(s.get("sd")),
                shown(p.get("1")),
                shown(p.get("50")),
                shown(p.get("99")),
                shown(s.get("min")),
                shown(s.get("max")),
                shown(meta.get("paper")),
                shown(nominal.get(name)),
                esc(bound),
                str(s.get("missing") or ""),
            ]
        )
    page.add(
        static_table(
            [
                "metric",
                "unit",
                "mean",
                "sd",
                "1 %",
                "median",
                "99 %",
                "min",
                "max",
                "paper",
                "nominal run",
                "required",
                "without a value",
            ],
            rows,
            numeric=tuple(range(2, 13)),
        )
    )


def _read_table(path: Path) -> tuple[list[str], list[list]]:
    """runs.csv as (columns, rows), numbers as numbers (an empty cell: None)."""
    if not path.exists():
        return [], []
    with path.open(newline="", encoding="utf-8") as stream:
        reader = csv.reader(stream)
        columns = next(reader, [])
        rows = [[_value(cell) for cell in row] for row in reader]
    return columns, rows


def _value(cell: str):
    if cell == "":
        return None
    try:
        number = float(cell)
    except ValueError:
        return cell
    return int(number) if number.is_integer() and "." not in cell and "e" not in cell else number


def _marks(meta: dict, nominal, factor: float) -> list:
    """[(value, colour, dash, label)] of a metric's requirement bounds, the paper's value and
    the nominal run's, in its display unit."""
    marks = [
        (value * factor, figures.LIMIT, "dash", f"requirement ({bound})")
        for bound, value in (meta.get("requirement") or {}).items()
    ]
    if meta.get("paper") is not None:
        marks.append((meta["paper"] * factor, "#595959", "dot", "paper"))
    if nominal is not None:
        marks.append((nominal * factor, "black", "solid", "nominal run"))
    return marks


def _log(values) -> bool:
    """Whether values spread over decades (all positive, largest/smallest > DECADES)."""
    values = np.asarray(values, float)
    values = values[np.isfinite(values)]
    return bool(len(values)) and values.min() > 0 and values.max() / values.min() > DECADES


def _histograms(page: Page, summary: dict, metrics: dict, table) -> None:
    """A step histogram of each metric that varies, with its requirement's bounds (red
    dashed), the paper's value (grey dotted) and the nominal run's (black); log bins and
    axis where the values span decades."""
    columns, rows = table
    nominal = (summary.get("nominal") or {}).get("metrics", {})
    panels = []
    for name, meta in metrics.items():
        if name not in columns:
            continue
        j = columns.index(name)
        values = np.array([r[j] for r in rows if isinstance(r[j], (int, float))], float)
        values = values[np.isfinite(values)]
        if len(values) < 2 or np.ptp(values) <= 1e-9 * max(np.abs(values).max(), 1e-300):
            continue
        factor, unit = _display(meta)
        panels.append((name, meta, values * factor, factor, unit))
    if not panels:
        return
    page.heading("Histograms", "histograms")
    titles = [
        f"{esc(meta.get('description') or name)} [{unit}]"
        if unit
        else esc(meta.get("description") or name)
        for name, meta, _, _, unit in panels
    ]
    layout = figures.stacked(titles, 250, shared=False, gap=86)
    layout["hovermode"] = "closest"
    data = []
    for k, (name, meta, values, factor, unit) in enumerate(panels, 1):
        x_axis, y_axis = figures.axes(k)
        marks = _marks(meta, nominal.get(name), factor)
        log = _log(np.r_[values, [m[0] for m in marks]])
        bins = min(60, max(8, int(math.sqrt(len(values)))))
        edges = (
            np.geomspace(values.min(), values.max(), bins + 1)
            if log
            else np.histogram_bin_edges(values, bins)
        )
        counts, edges = np.histogram(values, edges)
        data.append(
            {
                "type": "scatter",
                "mode": "lines",
                "x": figures.array(edges),
                "y": figures.array(np.r_[counts, counts[-1]]),
                "line": {"shape": "hv", "color": "#1f77b4", "width": 1.2},
                "fill": "tozeroy",
                "fillcolor": "rgba(31,119,180,0.35)",
                "name": name,
                "xaxis": x_axis,
                "yaxis": y_axis,
                "hovertemplate": "%{x:.5g}: %{y} runs<extra></extra>",
            }
        )
        layout[f"xaxis{'' if k == 1 else k}"].update(
            type="log" if log else "linear", title={"text": f"{name} [{unit}]" if unit else name}
        )
        layout[f"yaxis{'' if k == 1 else k}"]["title"] = {"text": "runs"}
        for value, colour, dash, _ in marks:
            layout["shapes"].append(
                {
                    "type": "line",
                    "xref": x_axis,
                    "yref": f"{y_axis} domain",
                    "x0": value,
                    "x1": value,
                    "y0": 0,
                    "y1": 1,
                    "line": {"color": colour, "dash": dash, "width": 1.5},
                }
            )
        if marks:
            layout["annotations"].append(
                figures.note(
                    " · ".join(
                        f'<span style="color:{c}">{esc(label)} {v:.5g}</span>'
                        for v, c, _, label in marks
                    ),
                    k,
                    "#333",
                )
            )
    layout["height"] += 30 * len(panels)  # each panel's own x title
    page.figure({"data": data, "layout": layout})


def _envelopes(page: Page, directory: Path, summary: dict) -> None:
    """Each kept signal over the runs that reached the end: min–max, 1–99 %, 5–95 % and
    the median against time, the scenario's bounds of it; below, the spread between runs
    (99 % − 1 %, 95 % − 5 %) on a log axis."""
    kept = summary.get("kept")
    path = directory / "signals.npy"
    if not kept or not path.exists():
        return
    from ...output.kept_signals import reached_the_end

    keep = summary["spec"].get("keep") or []
    names = [s for s in kept["signals"] if any(s == k or s.startswith(k + "[") for k in keep)]
    if not names:
        return
    signals = np.load(path, mmap_mode="r")[: summary["runs"]["planned"]]
    complete = reached_the_end(signals)
    if not complete.any():
        return
    t = kept["start"] + kept["step"] * np.arange(kept["points"])
    variable, bounds = _context(summary)
    page.heading("Envelopes of the kept signals", "envelopes")
    page.note(
        f"{int(complete.sum())} runs that reached the end (of {len(signals)}); each "
        f"curve thinned to at most {2 * BUCKETS + 2} points keeping each bucket's "
        "extremes."
    )
    for name in names:
        j = kept["signals"].index(name)
        values = np.asarray(signals[complete, j, :], float)
        page.figure(_envelope(name, t, values, variable(name), bounds))


def _context(summary: dict):
    """(the model variable of a column, or None; the scenario's signal bounds) of the
    campaign's target, where this installation can resolve it."""
    from ..run_directory import variables_of

    try:
        from ...mission.targets import resolve

        target = resolve(summary["spec"]["target"])
        system = target.system_file(build=False)
    except (KeyError, ValueError, OSError, ImportError):
        return (lambda column: None), []
    scenario = target.scenario
    bounds = [] if scenario is None else scenario.bounds_for(target.variant)
    changed = {key.partition("[")[0] for key in summary["spec"].get("set") or {}}
    changed |= {
        text.partition("=")[0].partition("[")[0] for text in summary["spec"].get("vary") or []
    }
    return variables_of(system), [b for b in bounds if b.parameter not in changed]


def _envelope(name: str, t, values, variable, bounds) -> dict:
    unit = getattr(variable, "unit", None)
    factor, shown_unit = 1.0, pretty(unit)
    degrees, in_degrees = to_degrees(unit)
    if degrees != 1.0:
        factor, shown_unit = degrees, pretty(in_degrees)
    p = np.percentile(values * factor, PERCENTILES, axis=0)
    keep = indices(p.T, BUCKETS)
    x, p = t[keep], p[:, keep]
    described = getattr(variable, "description", None) or name
    spread = np.vstack([p[5] - p[1], p[4] - p[2]])
    log = bool((spread > 0).any())
    layout = figures.stacked(
        [
            f"{esc(name)}: {esc(described)} [{shown_unit}]",
            f"spread between the runs [{shown_unit}]" + (", log scale" if log else ""),
        ],
        250,
    )
    layout["showlegend"] = True
    layout["legend"] = {
        "orientation": "h",
        "y": 1.0,
        "yanchor": "bottom",
        "x": 1,
        "xanchor": "right",
        "font": {"size": 11},
    }
    blue = "31,119,180"
    data = [
        figures.line(
            x,
            p[0],
            "min, max",
            f"rgba({blue},0.5)",
            0.8,
            legendgroup="extremes",
            line={"dash": "dot", "color": f"rgba({blue},0.6)", "width": 0.8},
        ),
        figures.line(
            x,
            p[6],
            "max",
            None,
            0.8,
            showlegend=False,
            legendgroup="extremes",
            line={"dash": "dot", "color": f"rgba({blue},0.6)", "width": 0.8},
        ),
        figures.line(x, p[1], "1 %", None, 0, showlegend=False, line={"width": 0}),
        figures.line(
            x,
            p[5],
            "1–99 %",
            None,
            0,
            fill="tonexty",
            fillcolor=f"rgba({blue},0.22)",
            line={"width": 0},
        ),
        figures.line(x, p[2], "5 %", None, 0, showlegend=False, line={"width": 0}),
        figures.line(
            x,
            p[4],
            "5–95 %",
            None,
            0,
            fill="tonexty",
            fillcolor=f"rgba({blue},0.45)",
            line={"width": 0},
        ),
        figures.line(x, p[3], "median", f"rgb({blue})", 1.4),
        figures.line(x, spread[0], "99 % − 1 %", "#ff7f0e", 1.4, xaxis="x2", yaxis="y2"),
        figures.line(x, spread[1], "95 % − 5 %", "#2ca02c", 1.4, xaxis="x2", yaxis="y2"),
    ]
    for trace in data[:7]:
        trace["hovertemplate"] = "%{y:.6g}<extra>" + trace["name"] + "</extra>"
    if log:
        layout["yaxis2"]["type"] = "log"
    for bound in (b for b in bounds if b.applies_to(name)):
        if bound.limit or bound.low is None or bound.high is None:
            for y in (bound.low, bound.high):
                if y is not None:
                    layout["shapes"].append(
                        figures.hline(y * factor, 1, figures.LIMIT, x0=bound.start, x1=bound.stop)
                    )
            layout["annotations"].append(figures.note(esc(bound.label), 1, figures.LIMIT))
        else:
            layout["shapes"].append(
                figures.hband(
                    bound.low * factor, bound.high * factor, 1, x0=bound.start, x1=bound.stop
                )
            )
            layout["annotations"].append(figures.note(esc(bound.label), 1, "#17612f", False))
    return {"data": data, "layout": layout}


def _grid(page: Page, summary: dict) -> None:
    points = summary.get("grid_pass_rates") or []
    if not points:
        return
    page.heading("Sweep: pass rates per grid point", "grid")
    keys = list(points[0]["values"])
    rows = []
    for point in points:
        rates = point["pass_rates"]
        met = rates.get("all") or next(iter(rates.values()), None)
        rows.append(
            [
                *point["values"].values(),
                met["met"] if met else None,
                met["runs"] if met else None,
                met["rate"] if met else None,
            ]
        )
    page.table([*keys, "met", "runs", "rate"], rows)


def _runs(page: Page, table, summary: dict) -> None:
    columns, rows = table
    if not rows:
        return
    page.heading("Every run", "runs")
    page.note(
        "Click a column's header to sort by it. runs.csv holds the same, every float "
        "exactly; a run replays with the command in campaign.json's 'replay'."
    )
    verdicts = [j for j, c in enumerate(columns) if c.startswith("verdict_") or c == "status"]
    page.table(columns, rows, verdicts=verdicts)


def _failures(page: Page, summary: dict) -> None:
    failures = summary.get("failures") or []
    if not failures:
        return
    page.heading("Runs that failed, and how to replay each", "failures")
    page.table(
        ["run", "status", "message", "replay"],
        [[f["index"], f["status"], f["message"], f["replay"]] for f in failures],
        verdicts=[1],
    )
