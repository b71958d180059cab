"""A run's own numerical error, on request (``agilesat run … --error-estimate``).

The run is repeated at half its step and at a quarter (in this process, nothing written),
and each metric's error at the run's step H is estimated by Richardson extrapolation::

    e(H) ≈ (m(H) − m(H/2)) · 2^p / (2^p − 1),   p = log2 |m(H) − m(H/2)| / |m(H/2) − m(H/4)|

with p the order observed from the three runs; where it cannot be observed (the two
differences zero, or the finer one not smaller, or p outside [0.5, 6]: a metric that moves
by whole steps, as a settling time does) the order is taken as 1 and said, which
overstates a second-order error.  It is the error of the step: the coupling of the
continuous FMUs and, for components without their own step, their sample period too (the
controllers' design, not the method: docs/coupling.md separates the two).  A requirement
whose margin (the metric's distance to its bound) is smaller than the metric's estimate is
not decided by this run, and said so.
"""

from __future__ import annotations

import math

#: the orders accepted as observed; outside them the order is taken as ASSUMED_ORDER
ORDERS, ASSUMED_ORDER = (0.5, 6.0), 1.0


def richardson(coarse: float, middle: float, fine: float) -> tuple[float, float, bool]:
    """(the error estimate of ``coarse``, the order used, whether it was observed)."""
    d1, d2 = coarse - middle, middle - fine
    if d1 == 0.0 and d2 == 0.0:
        return 0.0, math.inf, True
    order, observed = ASSUMED_ORDER, False
    if d2 != 0.0 and abs(d1) > abs(d2):
        p = math.log2(abs(d1) / abs(d2))
        if ORDERS[0] <= p <= ORDERS[1]:
            order, observed = p, True
    return d1 * 2**order / (2**order - 1), order, observed


def estimate(summary: dict, rerun) -> dict:
    """The summary's ``numerical_error``: ``rerun(step)`` runs the same target at another
    step and returns its summary."""
    step = summary["settings"]["step"]
    runs = [summary] + [rerun(step / k) for k in (2, 4)]
    metrics, requirements = {}, {}
    for name, given in summary.get("metrics", {}).items():
        entry = {**runs[1]["metrics"].get(name, {}), **given}  # units, bounds: any run's
        values = [run["metrics"].get(name, {}).get("value") for run in runs]
        if any(not isinstance(v, (int, float)) for v in values):
            metrics[name] = {"values": values, "estimate": None}
            continue
        error, order, observed = richardson(*values)
        metrics[name] = {
            "values": values,
            "estimate": error,
            "order": order if math.isfinite(order) else None,
            "order_observed": observed,
            "unit": entry.get("unit"),
            "display_unit": entry.get("display_unit"),
        }
        limits = entry.get("requirement")
        if limits and isinstance(entry.get("value"), (int, float)):
            value = entry["value"]
            margin = min(value - limits.get("min", -math.inf), limits.get("max", math.inf) - value)
            requirements[name] = {
                "margin": margin,
                "estimate": abs(error),
                "decided": abs(margin) > abs(error),
            }
    return {
        "steps": [step, step / 2, step / 4],
        "metrics": metrics,
        "requirements": requirements,
    }


def sample(records: list[dict], step: float, rerun) -> dict:
    """A campaign's ``numerical_error`` from a sample of its runs (``records``: journal
    records, their ``values`` and metric values at ``step``): each run's estimate
    (``rerun(values, step)`` runs it again), and per metric the largest over the sample;
    per requirement the runs it leaves undecided."""
    found = [
        estimate(
            {"settings": {"step": step}, "metrics": record["metrics"]},
            lambda h, values=record["values"]: rerun(values, h),
        )
        for record in records
    ]
    metrics = {}
    for name in found[0]["metrics"] if found else ():
        each = [f["metrics"][name] for f in found if f["metrics"][name]["estimate"] is not None]
        largest = max(each, key=lambda m: abs(m["estimate"]), default=None)
        metrics[name] = {
            "estimate": None if largest is None else abs(largest["estimate"]),
            "runs": len(each),
            "orders_observed": sum(bool(m.get("order_observed")) for m in each),
            "unit": largest and largest["unit"],
            "display_unit": largest and largest["display_unit"],
        }
    undecided = {}
    for f, record in zip(found, records):
        for name, r in f["requirements"].items():
            undecided.setdefault(name, [])
            if not r["decided"]:
                undecided[name].append(record["index"])
    return {
        "steps": [step, step / 2, step / 4],
        "sample": [record["index"] for record in records],
        "metrics": metrics,
        "undecided": undecided,
    }


def sample_lines(found: dict) -> list[str]:
    """A campaign's sampled estimate as ``agilesat campaign`` prints it."""
    from .output.summary import format_value

    runs = ", ".join(map(str, found["sample"]))
    out = [f"numerical error on {len(found['sample'])} runs ({runs}), the largest of each:"]
    for name, m in found["metrics"].items():
        if m["estimate"] is not None:
            shown = format_value(m["estimate"], m["unit"], m["display_unit"])
            out.append(
                f"  {name}: ± {shown} ({m['orders_observed']} of {m['runs']} orders observed)"
            )
    for name, indices in found["undecided"].items():
        if indices:
            out.append(
                f"  requirement on {name}: runs {', '.join(map(str, indices))} are within "
                "its numerical error of the bound: not decided by those runs"
            )
    return out


def lines(found: dict) -> list[str]:
    """The estimate as ``agilesat run`` prints it."""
    from .output.summary import format_value

    steps = ", ".join(f"{h:g}" for h in found["steps"])
    out = [f"numerical error (Richardson over the steps {steps} s):"]
    for name, m in found["metrics"].items():
        if m["estimate"] is None:
            out.append(f"  {name}: no estimate (no value at every step)")
            continue
        shown = format_value(abs(m["estimate"]), m["unit"], m["display_unit"])
        order = (
            "converged to its digits"
            if m["order"] is None
            else f"order {m['order']:.2f} observed"
            if m["order_observed"]
            else f"order {ASSUMED_ORDER:g} assumed"
        )
        out.append(f"  {name}: ± {shown} ({order})")
    for name, r in found["requirements"].items():
        m = found["metrics"][name]
        margin = format_value(abs(r["margin"]), m["unit"], m["display_unit"])
        if not r["decided"]:
            out.append(
                f"  requirement on {name}: its margin {margin} is within the numerical "
                "error: this run does not decide it"
            )
    return out
