"""Assertions AOCS engineers write again and again, on :class:`Results` and summaries.

Each raises ``AssertionError`` with what failed, where (time) and by how much; values are
in the signal's unit (SI) unless ``deg=True`` (the bound then in degrees, for angles).
pytest shows the failing test's line and this message, not the code here
(``__tracebackhide__``).
A signal is a column (``SatelliteDynamics.w_BI_B[2]``) or a whole array by base name
(``AttitudeController.att_error``: every element must hold).
"""

from __future__ import annotations

import numpy as np

from ..system.units import join, pretty, to_degrees


def _signal(results, name, start, stop, deg):
    __tracebackhide__ = True
    t = results.time
    rows = np.ones(len(t), bool)
    if start is not None:
        rows &= t >= start - 1e-12
    if stop is not None:
        rows &= t <= stop + 1e-12
    if not rows.any():
        raise AssertionError(
            f"{name}: no communication point in [{start}, {stop}] s (the run "
            f"covers {t[0]:g} … {t[-1]:g} s)"
        )
    values = results.get(name, deg=deg).reshape(len(t), -1)[rows]
    unit = results.unit(name)
    return t[rows], values, pretty(to_degrees(unit)[1] if deg else unit)


def assert_within(
    results,
    name: str,
    low: float | None = None,
    high: float | None = None,
    *,
    start: float | None = None,
    stop: float | None = None,
    deg: bool = False,
) -> None:
    """Every element of ``name`` in [low, high] (either may be None) over [start, stop]."""
    __tracebackhide__ = True
    t, values, unit = _signal(results, name, start, stop, deg)
    for bound, bad, word in (
        (low, values < low if low is not None else None, "below"),
        (high, values > high if high is not None else None, "above"),
    ):
        if bad is not None and bad.any():
            k, j = np.argwhere(bad)[0]
            worst = values.min() if word == "below" else values.max()
            raise AssertionError(
                f"{name} is {word} {join(f'{bound:g}', unit)} at {bad.any(axis=1).sum()} of "
                f"{len(t)} points, first at t = {t[k]:g} s ({join(f'{values[k, j]:.6g}', unit)}"
                + (f", element {j + 1}" if values.shape[1] > 1 else "")
                + f"); worst {join(f'{worst:.6g}', unit)}"
            )


def assert_settles(results, name: str, bound: float, after: float, *, deg: bool = False) -> None:
    """|name| ≤ bound (every element) from t = ``after`` to the end: e.g. the pointing error
    below 0.01° after a 60-s settling time."""
    __tracebackhide__ = True
    t, values, unit = _signal(results, name, after, None, deg)
    magnitude = np.abs(values)
    if (magnitude > bound).any():
        last = t[(magnitude > bound).any(axis=1)][-1]
        raise AssertionError(
            f"{name} does not settle within {join(f'±{bound:g}', unit)} after t = {after:g} s: "
            f"max {join(f'{magnitude.max():.6g}', unit)}, last outside at t = {last:g} s"
        )


def assert_momentum_conserved(
    results, rtol: float = 1e-9, name: str = "SatelliteDynamics.H_I"
) -> None:
    """max |H(t) − H(0)| / |H(0)| ≤ rtol for the recorded inertial momentum ``name``."""
    __tracebackhide__ = True
    H = results.vector(name)
    drift = np.linalg.norm(H - H[0], axis=1) / max(np.linalg.norm(H[0]), 1e-300)
    if drift.max() > rtol:
        k = int(np.argmax(drift))
        raise AssertionError(
            f"{name} drifts by {drift.max():.3g} (relative) at "
            f"t = {results.time[k]:g} s, above {rtol:g}"
        )


def requirement_met(metric: dict) -> bool:
    """A summary metric's ``met`` flag, or else its value against its requirement: a bound
    (value ≤ bound), a band [low, high], or {"min"/"max": ...}."""
    if "met" in metric:
        return bool(metric["met"])
    requirement, value = metric["requirement"], metric["value"]
    if value is None:
        return False
    if isinstance(requirement, dict):
        low, high = requirement.get("min"), requirement.get("max")
    elif isinstance(requirement, (list, tuple)):
        low, high = requirement
    else:
        low, high = None, requirement
    return (low is None or value >= low) and (high is None or value <= high)


def assert_requirements_met(summary: dict, *names: str, accept_undecided: bool = False) -> None:
    """The named requirements (default: every requirement judged) are met: each one's
    verdict (:mod:`..mission.requirements`) is "met".  ``summary``: a run's (summary.json;
    a requirement judged over a campaign is left out, or fails if named, saying so) or a
    campaign's (campaign.json: each requirement judged run by run met in every run, each
    judged over the campaign met).  Not met fails; undecided (a statistical requirement
    whose runs show neither compliance nor a violation) fails too unless
    ``accept_undecided``; not evaluated (a metric without a value) fails, saying why; a
    requirement the variant does not judge is left out, or fails if named.  A summary
    without verdicts: each metric with a requirement against it."""
    __tracebackhide__ = True
    if "ensemble" in summary and "pass_rates" in summary:
        verdicts = _campaign_verdicts(summary)
    elif "requirements" in summary:
        verdicts = summary["requirements"]
    else:
        return _metrics_meet(summary, names)
    unknown = [n for n in names if n not in verdicts]
    if unknown:
        raise AssertionError(
            f"no requirement {unknown} in the summary; requirements: {', '.join(verdicts)}"
        )
    skipped = ("not judged", "judged over the campaign")
    chosen = names or [n for n, r in verdicts.items() if r["verdict"] not in skipped]
    failed: dict[str, list[str]] = {}
    for name in chosen:
        r = verdicts[name]
        if r["verdict"] == "met" or (r["verdict"] == "undecided" and accept_undecided):
            continue
        shown = r.get("text") or f"{r['statement']}: {r['verdict']}"
        value = ""
        if r.get("value") is not None and r.get("unit"):
            from ..output.summary import format_value

            value = f" = {format_value(r['value'], r['unit'], r.get('display_unit'))}"
        reason = f" ({r['reason']})" if r.get("reason") and not r.get("text") else ""
        failed.setdefault(r["verdict"], []).append(f"{shown}{value}{reason}")
    if failed:
        hint = {"undecided": " (accept_undecided=True accepts it)"}
        raise AssertionError(
            "; ".join(
                f"requirement {verdict}{hint.get(verdict, '')}: {'; '.join(texts)}"
                for verdict, texts in failed.items()
            )
        )


def _campaign_verdicts(summary: dict) -> dict:
    """A campaign summary's requirements as verdicts: one judged run by run is met when
    every run meets it (else not met, or not evaluated where no run failed it); one judged
    over the campaign, its verdict."""
    statements = {n: r.get("statement", n) for n, r in summary.get("requirements", {}).items()}
    verdicts = {}
    for name, rate in summary["pass_rates"].items():
        if name == "all":
            continue
        every = rate["runs"] > 0 and rate["met"] == rate["runs"]
        verdict = "met" if every else "not met" if rate["not_met"] else "not evaluated"
        text = f"{statements.get(name, name)}: met in {rate['met']}/{rate['runs']} runs"
        verdicts[name] = {"verdict": verdict, "text": text}
    for name, why in summary.get("not_judged", {}).items():
        verdicts[name] = {
            "verdict": "not judged",
            "statement": statements.get(name, name),
            "reason": why,
        }
    for name, entry in summary["ensemble"].items():
        verdicts[name] = {**entry, "text": entry.get("text") or entry["statement"]}
    return verdicts


def _metrics_meet(summary: dict, names) -> None:
    __tracebackhide__ = True
    metrics = summary["metrics"]
    unknown = [n for n in names if n not in metrics]
    if unknown:
        raise AssertionError(f"no metric {unknown} in the summary; metrics: {', '.join(metrics)}")
    chosen = names or [n for n, m in metrics.items() if "requirement" in m]
    failed = [
        f"{n} = {metrics[n]['value']!r} {metrics[n]['unit']} (required "
        f"{metrics[n].get('requirement')!r})"
        for n in chosen
        if not requirement_met(metrics[n])
    ]
    if failed:
        raise AssertionError("requirement not met: " + "; ".join(failed))


def assert_pointing(
    source,
    index: str,
    *,
    bound: float,
    level: float = 0.9973,
    interpretation: str = "temporal",
    window: float | None = None,
    separation: float | None = None,
    t_in_window: str = "end",
    axis=None,
    boresight=None,
    confidence: float | None = None,
    attitude: str | None = None,
    reference: str | None = None,
    start: float | None = None,
    stop: float | None = None,
    accept_undecided: bool = False,
):
    """The ECSS pointing index ``index`` (APE … KRE, docs/pointing.md) of ``source`` is
    within ``bound`` (rad) at ``level`` under ``interpretation``: ``source`` is a run
    (:class:`.results.Results` or its directory) or a campaign (its
    :class:`..campaign.Campaign` or directory, the quaternions kept); the error is that of
    ``attitude`` against ``reference`` (:func:`.recorded.evaluate`: a knowledge index
    defaults to the estimate against the truth).  Fails when it is not met, when it is
    undecided (the runs show neither compliance nor a violation at the ``confidence``;
    unless ``accept_undecided``) and when it is not evaluated (a record too short), saying
    which and why; returns the :class:`..pointing.PointingResult`."""
    __tracebackhide__ = True
    from ..pointing import PointingRequirement
    from .recorded import evaluate

    requirement = PointingRequirement(
        index,
        bound,
        level,
        interpretation,
        window,
        separation,
        t_in_window,
        axis,
        boresight,
        confidence,
    )
    result = evaluate(
        source, requirement, attitude=attitude, reference=reference, start=start, stop=stop
    )
    if not result.met and not (result.status == "undecided" and accept_undecided):
        hint = " (accept_undecided=True accepts it)" if result.status == "undecided" else ""
        raise AssertionError(f"{result.status}{hint}: {result.line('deg')}")
    return result
