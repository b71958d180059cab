"""Plotly figures as plain JSON-ready dicts (``{"data": [...], "layout": {...}, "frames":
[...]}``, plotly.js's own schema): built without plotly.py's validating objects, which
take seconds per figure of many shapes, and with every array as a typed array
(:func:`array`: base64 float32, a third of the text of its numbers), which plotly.js
reads as it is."""

from __future__ import annotations

import base64
import json
import math

import numpy as np

#: series colours: matplotlib's tab10 without its red, which marks limits
COLOURS = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
)
LIMIT = "#d62728"
BAND = "rgba(44,160,44,0.20)"
MARGIN = {"l": 70, "r": 24, "t": 56, "b": 46}


def array(values) -> dict:
    """A typed array of plotly.js (float32, base64): NaN stays NaN (a gap in a line)."""
    data = np.ascontiguousarray(np.asarray(values, dtype="<f4"))
    return {"dtype": "f4", "bdata": base64.b64encode(data.tobytes()).decode("ascii")}


def line(x, y, name: str, colour: str | None = None, width: float = 1.5, **more) -> dict:
    trace = {
        "type": "scatter",
        "mode": "lines",
        "x": array(x),
        "y": array(y),
        "name": name,
        "line": {"width": width, **({"color": colour} if colour else {})},
    }
    trace.update(more)
    return trace


def stacked(titles, height_per: int = 220, shared: bool = True, gap: float = 46.0) -> dict:
    """The layout of ``len(titles)`` stacked panels (x axes matched when ``shared``), each
    titled (a quantity with its unit); panel k uses axes ``x{k}``/``y{k}`` (k from 1, "x"
    for the first)."""
    n = len(titles)
    height = MARGIN["t"] + MARGIN["b"] + n * height_per
    layout: dict = {
        "height": height,
        "margin": dict(MARGIN),
        "showlegend": False,
        "hovermode": "x unified",
        "annotations": [],
        "shapes": [],
    }
    span = height - MARGIN["t"] - MARGIN["b"]
    step = 1.0 / n
    pad = min(gap / span, 0.3 * step)
    for k, title in enumerate(titles, 1):
        top = 1 - (k - 1) * step
        bottom = 1 - k * step + pad
        suffix = "" if k == 1 else str(k)
        layout[f"xaxis{suffix}"] = {
            "anchor": f"y{suffix}",
            "domain": [0, 1],
            **({"matches": "x"} if shared and k > 1 else {}),
            "showticklabels": not shared or k == n,
        }
        layout[f"yaxis{suffix}"] = {
            "anchor": f"x{suffix}",
            "domain": [bottom, top - 0.02 * step],
            "exponentformat": "power",
        }
        layout["annotations"].append(
            {
                "text": title,
                "xref": "paper",
                "yref": "paper",
                "x": 0,
                "y": top,
                "xanchor": "left",
                "yanchor": "bottom",
                "showarrow": False,
                "font": {"size": 13},
            }
        )
    last = "" if n == 1 else str(n)
    layout[f"xaxis{last}"]["title"] = {"text": "time [s]"}
    return layout


def axes(k: int) -> tuple[str, str]:
    """The trace axes ("x", "y") of panel k (from 1)."""
    return ("x", "y") if k == 1 else (f"x{k}", f"y{k}")


def hline(y: float, k: int, colour: str, dash: str = "dash", x0=None, x1=None) -> dict:
    """A horizontal line on panel k (over [x0, x1], or its whole width)."""
    x, ya = axes(k)
    whole = x0 is None or x1 is None
    return {
        "type": "line",
        "xref": f"{x} domain" if whole else x,
        "yref": ya,
        "x0": 0 if whole else x0,
        "x1": 1 if whole else x1,
        "y0": y,
        "y1": y,
        "line": {"color": colour, "dash": dash, "width": 1.3},
    }


def hband(low: float, high: float, k: int, colour: str = BAND, x0=None, x1=None) -> dict:
    x, ya = axes(k)
    whole = x0 is None or x1 is None
    return {
        "type": "rect",
        "xref": f"{x} domain" if whole else x,
        "yref": ya,
        "x0": 0 if whole else x0,
        "x1": 1 if whole else x1,
        "y0": low,
        "y1": high,
        "fillcolor": colour,
        "line": {"width": 1, "color": "rgba(44,160,44,0.85)"},  # seen where it is thin
        "layer": "below",
    }


def note(text: str, k: int, colour: str, top: bool = True) -> dict:
    """A small label in panel k's upper (or lower) left corner."""
    x, y = axes(k)
    return {
        "text": text,
        "xref": f"{x} domain",
        "yref": f"{y} domain",
        "x": 0.01,
        "y": 0.98 if top else 0.02,
        "xanchor": "left",
        "yanchor": "top" if top else "bottom",
        "showarrow": False,
        "font": {"size": 10, "color": colour},
        "bgcolor": "rgba(255,255,255,0.7)",
    }


def phases(layout: dict, phases, t_end: float) -> None:
    """A maneuver's phases [(name, start, end)] across every panel of a stacked layout
    (x matched): alternating shades, dotted boundaries, each named at the top."""
    if phases:
        layout["margin"]["t"] += 18
        layout["height"] += 18
    for k, (name, start, end) in enumerate(phases):
        end = min(end, t_end)
        if not start < end:
            continue
        layout["shapes"].append(
            {
                "type": "rect",
                "xref": "x",
                "yref": "paper",
                "x0": start,
                "x1": end,
                "y0": 0,
                "y1": 1,
                "layer": "below",
                "line": {"width": 0},
                "fillcolor": "rgba(120,140,170,0.09)" if k % 2 == 0 else "rgba(0,0,0,0)",
            }
        )
        if k:
            layout["shapes"].append(
                {
                    "type": "line",
                    "xref": "x",
                    "yref": "paper",
                    "x0": start,
                    "x1": start,
                    "y0": 0,
                    "y1": 1,
                    "layer": "below",
                    "line": {"color": "#9aa5b8", "width": 1, "dash": "dot"},
                }
            )
        layout["annotations"].append(
            {
                "text": name,
                "xref": "x",
                "yref": "paper",
                "x": (start + end) / 2,
                "y": 1.0,
                "yanchor": "bottom",
                "yshift": 18,  # above the top panel's title
                "showarrow": False,
                "font": {"size": 10, "color": "#59647a"},
            }
        )


def to_json(figure: dict) -> str:
    """The figure as JSON (NumPy scalars as numbers, non-finite numbers as null)."""
    return json.dumps(_clean(figure), separators=(",", ":"), ensure_ascii=False)


def _clean(value):
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_clean(v) for v in value.tolist()]
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value
