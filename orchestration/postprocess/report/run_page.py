"""The report of one run (``agilesat report RUN_DIR``): what ran; its headline numbers
beside the paper's, with each requirement's verdict; the 3-D view; the signals the
scenario bounds, with the bands and limits and its pointing indices against their bounds;
then every recorded output, instance by instance (sections drawn when opened).  Angles in
degrees, every axis titled with the quantity (its model description) and unit; the
maneuver's phases shaded and named on every time axis."""

from __future__ import annotations

import math

import numpy as np

from ...output.summary import format_value, requirement_text
from ...system.units import pretty, to_degrees
from . import figures, scene
from .decimate import min_max
from .page import Page, esc, facts, static_table, verdict

#: the buckets a series of every output is thinned to (:mod:`.decimate`: 2 points each)
BUCKETS = 300


def build(run) -> Page:
    """The page of a :class:`..run_directory.RunDirectory`."""
    s = run.summary
    scenario = run.scenario
    title = f"agilesat run {run.label}"
    subtitle = scenario.title if scenario is not None else str(s.get("system", ""))
    page = Page(title, subtitle)
    settings = s.get("settings", {})
    page.add(
        facts(
            [
                ("status", s.get("status")),
                ("command", s.get("command")),
                ("date", s.get("date")),
                ("agilesat", s.get("version")),
                ("time", _span(settings)),
                ("algorithm", settings.get("algorithm")),
                ("rows", s.get("rows")),
                ("wall time", f"{s['wall_time']:.3g} s" if "wall_time" in s else None),
                (
                    "parameters set",
                    ", ".join(f"{k} = {v['value']}" for k, v in (s.get("parameters") or {}).items())
                    or None,
                ),
            ]
        )
    )
    _numbers(page, s)
    _requirements(page, s)
    if s.get("diagnostics"):
        page.heading("Diagnostics")
        page.add("<ul>" + "".join(f"<li>{esc(d)}</li>" for d in s["diagnostics"]) + "</ul>")
    results = run.results
    phases = _phases(run)
    if scene.available(results):
        page.heading("3-D view", "view")
        page.note(
            "Drag to turn a view, scroll to zoom; the slider and ▶ play move through the run. "
            "Frames: DESIGN.md §2 (q_BI maps I to B; E is I turned by the Earth angle)."
        )
        page.figure(scene.figure(results, run.parameter))
    _bounded(page, run, phases)
    _pointing(page, run, phases)
    _outputs(page, run, phases)
    written = s.get("figures") or []
    if written:
        page.heading("Figures written beside this page")
        page.add(
            "<p>"
            + " · ".join(
                f'<a href="{esc(name)}">{esc(name)}</a>'
                for name in (str(f).rsplit("/", 1)[-1] for f in written)
            )
            + "</p>"
        )
    return page


def _span(settings: dict) -> str | None:
    if "stop" not in settings:
        return None
    return f"{settings.get('start', 0):g} … {settings['stop']:g} s, step {settings.get('step'):g} s"


def _numbers(page: Page, s: dict) -> None:
    """The metrics (a scenario's) beside the paper's, or min/max/final of every output."""
    metrics = s.get("metrics") or {}
    if metrics:
        page.heading("Headline numbers", "numbers")
        rows = []
        for name, m in metrics.items():
            unit, shown = m["unit"], m.get("display_unit")
            value = "—" if m["value"] is None else format_value(m["value"], unit, shown)
            if m["value"] is None and m.get("reason"):
                value += f' <span class="note">({esc(m["reason"])})</span>'
            paper = format_value(m["paper"], unit, shown) if m.get("paper") is not None else ""
            required = requirement_text(m["requirement"], unit, shown) if "requirement" in m else ""
            rows.append(
                [
                    f"<code>{esc(name)}</code>",
                    esc(m.get("description") or ""),
                    value if m["value"] is None else esc(value),
                    esc(paper),
                    esc(required),
                    verdict(m.get("verdict")),
                ]
            )
        page.add(
            static_table(
                ["metric", "what", "ours", "paper", "required", "verdict"], rows, numeric=(2, 3)
            )
        )
    outputs = s.get("outputs") or {}
    if outputs:
        page.heading("Outputs: range and final value", "outputs-range")
        page.table(
            ["output", "min", "max", "final", "unit"],
            [
                [n, o["min"], o["max"], o["final"], pretty(o.get("unit"))]
                for n, o in outputs.items()
            ],
        )


def _requirements(page: Page, s: dict) -> None:
    requirements = s.get("requirements") or {}
    if not requirements:
        return
    page.heading("Requirements", "requirements")
    rows = []
    for name, r in requirements.items():
        said = r.get("text") or r.get("reason") or ""
        rows.append(
            [
                f"<code>{esc(name)}</code>",
                esc(r.get("statement", "")),
                verdict(r.get("verdict")),
                esc(said),
            ]
        )
    page.add(static_table(["requirement", "statement", "verdict", "what the run shows"], rows))


def _phases(run) -> list:
    """[(name, start, end)] of the scenario's maneuver (``Scenario.phases``), else of a
    recorded ``phase`` output (its runs of one value), else none."""
    declared = getattr(run.scenario, "phases", None) or ()
    if declared:
        return list(declared)
    results = run.results
    for name in results.names[1:]:
        if name.endswith(".phase"):
            values, t = results[name], results.time
            edges = np.flatnonzero(np.diff(values)) + 1
            starts, ends = np.r_[0, edges], np.r_[edges, len(t) - 1]
            return [(f"phase {values[a]:g}", t[a], t[b]) for a, b in zip(starts, ends)]
    return []


def _label(run, variable: str) -> tuple[str, float, str]:
    """(the quantity as its model description says, the factor to display, unit) of a
    recorded variable (base name): angles in degrees."""
    results = run.results
    column = results.columns(variable)[0]
    unit = results.units.get(column)
    factor, shown = to_degrees(unit)
    described = run.description(column) or variable.split(".", 1)[-1]
    return described, factor, pretty(shown if factor != 1.0 else unit)


def _elements(results, variable: str) -> list[tuple[str, np.ndarray]]:
    """(label, values) of each element of a variable: x, y, z of a 3-vector; w, x, y, z of
    a quaternion (scalar first); the index otherwise."""
    columns = results.columns(variable)
    base = variable.split(".")[-1]
    names = (
        ("w", "x", "y", "z")
        if len(columns) == 4 and base.startswith("q_")
        else (("x", "y", "z") if len(columns) == 3 else None)
    )
    return [
        (names[j] if names else (column[len(variable) :] or base), results[column])
        for j, column in enumerate(columns)
    ]


def series_figure(
    run, variables, phases, marks=None, buckets: int = BUCKETS, height_per: int = 210
) -> dict:
    """Stacked panels sharing time, one per variable (its elements as lines, decimated
    with the extremes kept), titled "<quantity> [<unit>]"; ``marks``: {variable:
    [mark(layout, k, factor)]}."""
    results = run.results
    t = results.time
    labels = [_label(run, v) for v in variables]
    layout = figures.stacked([f"{esc(d)} [{u}]" if u else esc(d) for d, _, u in labels], height_per)
    data = []
    for k, (variable, (_, factor, unit)) in enumerate(zip(variables, labels), 1):
        x_axis, y_axis = figures.axes(k)
        for j, (element, values) in enumerate(_elements(results, variable)):
            x, y = min_max(t, np.asarray(values, float) * factor, buckets)
            data.append(
                figures.line(
                    x,
                    y,
                    f"{variable} {element}",
                    figures.COLOURS[j % len(figures.COLOURS)],
                    xaxis=x_axis,
                    yaxis=y_axis,
                    hovertemplate=f"{esc(element)} %{{y:.6g}} {unit}<extra></extra>",
                )
            )
        for mark in (marks or {}).get(variable, ()):
            mark(layout, k, factor)
    figures.phases(layout, phases, float(t[-1]))
    return {"data": data, "layout": layout}


def _band(bound, verdicts: dict):
    """A scenario's :class:`..mission.scenario.SignalBound` as a mark of its panel: a
    requirement's band in green (its verdict in the label), a limit as dashed red lines."""

    def mark(layout, k, factor):
        said = verdicts.get(bound.requirement, {}).get("verdict") if bound.requirement else None
        label = esc(bound.label + (f": {said}" if said else ""))
        if bound.limit or bound.low is None or bound.high is None:
            for y in (bound.low, bound.high):
                if y is not None:
                    layout["shapes"].append(
                        figures.hline(y * factor, k, figures.LIMIT, x0=bound.start, x1=bound.stop)
                    )
            layout["annotations"].append(figures.note(label, k, figures.LIMIT))
            return
        layout["shapes"].append(
            figures.hband(bound.low * factor, bound.high * factor, k, x0=bound.start, x1=bound.stop)
        )
        layout["annotations"].append(figures.note(label, k, "#17612f", top=False))

    return mark


def _bounded(page: Page, run, phases) -> None:
    """The signals the scenario bounds (its ``bounds``), with the bands and limits."""
    scenario = run.scenario
    if scenario is None:
        return
    results = run.results
    marks: dict[str, list] = {}
    for bound in scenario.bounds_for(run.variant):
        if bound.signal in results:
            marks.setdefault(bound.signal, []).append(
                _band(bound, run.summary.get("requirements") or {})
            )
    if not marks:
        return
    page.heading("Signals and their bounds", "bounds")
    page.figure(series_figure(run, list(marks), phases, marks, buckets=1000, height_per=280))


def _pointing(page: Page, run, phases) -> None:
    """Each pointing requirement the run's variant judges: its index against time, the
    bound, the statistic compared and the verdict."""
    scenario = run.scenario
    if scenario is None:
        return
    from ...mission.pointing_figures import shown as judged

    results = run.results
    verdicts = run.summary.get("requirements") or {}
    shown = []
    for r, result, t, m in judged(scenario, run.variant, results):
        deg = 180 / math.pi
        bound, stat = r.requirement.bound * deg, result.statistic  # type: ignore[attr-defined]
        said = verdicts.get(r.name, {}).get("verdict", result.status)
        layout = figures.stacked(
            [f"{esc(r.name)}: {esc(r.statement())} — {esc(said)}"], 300, shared=False
        )
        layout["yaxis"]["title"] = {"text": f"{r.requirement.index} [°]"}  # type: ignore[attr-defined]
        x, y = min_max(t, m[0] * deg, 1000)
        if np.nanmax(y) < bound / 20:  # the bound far above the data: both shown
            layout["yaxis"]["type"] = "log"
        layout["shapes"] += [
            figures.hline(bound, 1, figures.LIMIT),
            figures.hline(stat.value * deg, 1, "black", "dashdot"),
        ]
        layout["annotations"] += [
            figures.note(f"requirement {bound:.4g}°", 1, figures.LIMIT),
            figures.note(
                f"{100 * stat.level:g} % ({stat.interpretation}): {stat.value * deg:.4g}°",
                1,
                "black",
                top=False,
            ),
        ]
        figures.phases(layout, phases, float(results.time[-1]))
        shown.append(
            {
                "data": [figures.line(x, y, r.requirement.label())],  # type: ignore[attr-defined]
                "layout": layout,
            }
        )
    if shown:
        page.heading("Pointing requirements (ECSS-E-ST-60-10C)", "pointing")
        for figure in shown:
            page.figure(figure)


def _outputs(page: Page, run, phases) -> None:
    """Every recorded output, one closed section per instance, drawn when opened."""
    results = run.results
    by_instance: dict[str, list[str]] = {}
    for name in results.names[1:]:
        variables = by_instance.setdefault(name.split(".")[0], [])
        base = name.rsplit("[", 1)[0]
        if base not in variables:
            variables.append(base)
    page.heading("Every output", "outputs")
    page.note(
        f"{len(results)} samples per output, thinned for display to at most "
        f"{2 * BUCKETS + 2} keeping each bucket's smallest and largest value."
    )
    for instance, variables in by_instance.items():
        page.add(f"<details><summary>{esc(instance)} ({len(variables)} outputs)</summary>")
        page.figure(series_figure(run, variables, phases))
        page.add("</details>")
