"""The recorded outputs a scenario's metrics and requirements read, checked against its
system before anything runs (``agilesat info``, ``run``, ``campaign``, the pytest
plugin's ``agilesat_run``): :func:`check`.

What a metric or requirement reads is found by evaluating it once on a stand-in for a
run's results, :class:`Probe`: a few rows of every output of the system at its start
value, which notes every name asked for that is no output (and answers it with zeros, so
that the evaluation goes on to the names after it).  A metric or requirement that raises
on those values stops there: a name it reads only further on is checked when the run
evaluates it (a missing one then makes it "not evaluated", the run's records written).

A name that is no output is a problem naming the file and line where the metric or
requirement was written, what is wrong, and the closest outputs (:func:`closest`): by
spelling, and by meaning, the words of the name among those of each output's name and
description and the kind of unit they imply (a gimbal rate is ``CmgCluster.delta_dot``,
"gimbal rates", rad/s).  Every problem is reported together.
"""

from __future__ import annotations

import difflib
import re
import warnings

import numpy as np

from ..output.results import Results
from ..system.parameters import did_you_mean, variables
from ..system.ssp import SystemFileError
from .metrics import MetricValue

#: rows of the stand-in results
ROWS = 5
#: words that say nothing of what a variable is
_FILLER = {"a", "an", "and", "as", "at", "by", "in", "is", "of", "on", "the", "to", "rel"}
#: words that mean the same in a variable's name or description
_SAME = [{"rate", "velocity", "speed", "dot", "omega"}, {"body", "b"}, {"angle", "attitude"}]
#: words of a name that imply a kind of unit: what the unit of an output that is meant has
_UNIT_WORDS = {
    **dict.fromkeys(("rate", "speed", "velocity", "dot"), lambda unit: "/s" in unit),
    "angle": lambda unit: unit == "rad",
    "torque": lambda unit: unit == "N.m",
    "momentum": lambda unit: unit == "N.m.s",
}


class Probe(Results):
    """Stand-in results of a system (``described``: {component: its Description}) over
    [start, stop]: every output at its start value (0 where it has none).  ``asked``:
    the names read that are no output, in order."""

    def __init__(self, described: dict, start: float, stop: float | None):
        names, units, values = ["time"], {}, []
        for component, d in described.items():
            for name in d.outputs:
                variable = d.variables[name]
                names.append(f"{component}.{name}")
                if variable.type == "Real" and variable.unit:
                    units[names[-1]] = variable.unit
                values.append(_number(variable.start))
        end = stop if stop is not None and stop > start else start + 1.0
        t = np.linspace(start, end, ROWS)
        data = np.column_stack([t, np.tile(np.asarray(values, dtype=float), (ROWS, 1))])
        super().__init__(names, data, {"units": units, "start": start, "stop": end})
        self.asked: list[str] = []

    def __getitem__(self, name):
        if name in self:
            return super().__getitem__(name)
        self.asked.append(name)
        return np.zeros(len(self))

    def vector(self, name):
        if name in self._bases or name in self._index:
            return super().vector(name)
        self.asked.append(name)
        return np.zeros((len(self), 4 if name.rpartition(".")[2].startswith("q_") else 3))

    def columns(self, name):
        if name in self:
            return super().columns(name)
        self.asked.append(name)
        return []

    def unit(self, name):
        if name in self:
            return super().unit(name)
        self.asked.append(name)
        return None

    def derived(self, key, compute):
        """Computed again each time: every reader asks its own names."""
        return compute()


def _number(text) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return 1.0 if str(text).lower() == "true" else 0.0


def check(scenario, variant: str | None = None, build: bool = True) -> None:
    """Raise :class:`..system.ssp.SystemFileError` naming every name a metric or a
    requirement of ``variant`` reads that is no output of its system (module)."""
    found = problems(scenario, variant, build)
    if found:
        raise SystemFileError(
            f"scenario {scenario.name}{f':{variant}' if variant else ''}: {len(found)} "
            "metric or requirement input(s) that no component outputs:\n  " + "\n  ".join(found)
        )


def problems(scenario, variant: str | None = None, build: bool = True) -> list[str]:
    """The names the metrics and requirements of ``variant`` read that are no output of
    its system, each said with where it was written and the closest outputs."""
    system = scenario.system_for(variant)
    described = system.descriptions(build)
    probe = Probe(described, system.start, system.stop)
    metrics = scenario.metrics_for(variant)
    values = {m.name: MetricValue(None, m.unit or "1", "not run") for m in metrics}
    exempt = scenario.variant(variant).exempt()
    readers = [(f"metric {m.name}", m.origin, lambda m=m: m.compute(probe)) for m in metrics]
    readers += [
        (f"requirement {r.name}", getattr(r, "origin", ""), lambda r=r: r.evaluate(probe, values))
        for r in scenario.requirements_for(variant)
        if r.name not in exempt
    ]
    found: dict[str, None] = {}
    for what, origin, evaluate in readers:
        for name in _read(probe, evaluate):
            found.setdefault(_problem(what, origin, name, described))
    return list(found)


def _read(probe: Probe, evaluate) -> list[str]:
    """The names ``evaluate()`` asks of the probe that are no output."""
    probe.asked = []
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            evaluate()
        except Exception:  # noqa: BLE001, S110 - its values are stand-ins: only names count
            pass
    return list(dict.fromkeys(probe.asked))


def _problem(what: str, origin: str, name: str, described: dict) -> str:
    """One problem: where, what reads ``name``, why it is no output, the closest ones."""
    component, _, variable = str(name).partition(".")
    base = variable.partition("[")[0]
    where = f"{origin}: " if origin else ""
    close: list[str] = []
    if component not in described:
        close = closest(name, described)
        why = f"no component {component!r} in the system"
        why += "" if close else did_you_mean(component, described)
    elif not variable:
        why = "expected Component.output"
    else:
        d = described[component]
        table = variables(d)
        if base not in table:  # an element of it: said once, for the whole variable
            name = f"{component}.{base}"
            why = f"{component} ({d.path.name}) has no output {base!r}"
            close = closest(name, described)
        elif table[base].first.causality != "output":
            causality = table[base].first.causality
            why = f"{name} is not an output (its causality: {causality}): a run records outputs"
        else:
            elements = table[base].scalars
            why = (
                f"the elements of {component}.{base} are {elements[0].name} .. {elements[-1].name}"
            )
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    return f"{where}{what} reads {name}: {why}{hint}"


def _words(text: str) -> set[str]:
    """The words of a name or a description, lower case, a plural's -s dropped."""
    found = re.findall(r"[A-Z]?[a-z]+|[A-Z]+(?![a-z])", text or "")
    words = {w.lower() for w in found} - _FILLER
    return {w[:-1] if len(w) > 3 and w.endswith("s") and not w.endswith("ss") else w for w in words}


def _shared(wanted: set[str], have: set[str]) -> int:
    """How many of the ``wanted`` words ``have`` holds: the word, one that means the same
    (:data:`_SAME`), or one that starts with it, of four letters or more ("accel" and
    "acceleration")."""
    return sum(
        any(
            w == h
            or any({w, h} <= same for same in _SAME)
            or min(len(w), len(h)) >= 4
            and (h.startswith(w) or w.startswith(h))
            for h in have
        )
        for w in wanted
    )


def closest(name: str, described: dict, n: int = 3) -> list[str]:
    """The outputs of the system closest to ``name`` ("Component.variable"), by spelling
    and by meaning (module), each with its description and unit: at most ``n``."""
    component, _, variable = str(name).partition(".")
    base = variable.partition("[")[0]
    wanted = _words(base)
    scored = []
    for c, d in described.items():
        for output, v in variables(d).items():
            if v.first.causality != "output":
                continue
            unit = v.first.unit or ""
            spelling = difflib.SequenceMatcher(None, base.lower(), output.lower()).ratio()
            meaning = _shared(wanted, _words(output) | _words(v.first.description)) / max(
                len(wanted), 1
            )
            implied = [test(unit) for word, test in _UNIT_WORDS.items() if word in wanted]
            if meaning and implied:
                meaning += 0.2 if all(implied) else -0.2
            if max(spelling, meaning) < 0.6:
                continue
            same = difflib.SequenceMatcher(None, component, c).ratio()
            said = ", ".join(filter(None, (v.first.description, unit if unit != "1" else "")))
            scored.append((max(spelling, meaning) + 0.3 * same, f"{c}.{output} ({said})"))
    return [text for _, text in sorted(scored, key=lambda s: -s[0])[:n]]
