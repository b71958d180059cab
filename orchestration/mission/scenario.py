"""A scenario: a :class:`~.system.System` with its metrics, requirements, variants and
figures, declared in a Python module that can live anywhere.

    SCENARIO = Scenario(
        "detumble", "Detumble, then point at the target", system,
        metrics=[settling_time(...), pointing_error(..., require=at_most(deg(0.1)))],
        variants={"slow": Variant("half the gain", parameters={"Damper.gain": 2.5})},
        figures=[figures],
    )

``agilesat run path/to/mission.py[:variant]`` (and ``info``, ``export``, ``campaign``)
take the module's ``SCENARIO`` (:mod:`.targets`), as they take the shipped ``scan_pitch``
(whose module is written the same way: copy it as a template).

A :class:`Variant` changes parameter values, and may change the system itself (add,
replace, remove components, rewire: its ``system`` function edits a copy), add metrics,
requirements and figures, and exempt requirements it is not meant to meet
(``not_judged``: they are reported "not judged", with the reason, and never fail it).

After a run, :meth:`Scenario.evaluate` gives the summary's ``metrics`` (value, unit,
display unit, description, the reference value, and its bound where it has one),
``requirements`` (each one's verdict, :mod:`.requirements`), ``diagnostics`` (the
requirements not met, then what the scenario's ``diagnose`` explains) and ``status``
("failed" when a requirement is not met or a diagnosis is given: ``agilesat run`` exits 3;
an undecided requirement fails nothing, and ``agilesat run`` exits 4).  A requirement
judged over a campaign (:func:`.requirements.judged_over_campaign`) is "judged over the
campaign" in a run: one verdict per requirement and scope.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ..output.results import ColumnError
from ..output.summary import format_value
from ..system.parameters import did_you_mean
from .metrics import Metric, NotEvaluable
from .requirements import (
    MET,
    NOT_EVALUATED,
    NOT_JUDGED,
    NOT_MET,
    OVER_CAMPAIGN,
    OVER_CAMPAIGN_REASON,
    Bound,
    Requirement,
    Verdict,
    judged_over_campaign,
)
from .system import System, _origin


@dataclass(frozen=True)
class Variant:
    """A variant of a scenario: ``parameters`` ({"A.p": value}, units allowed) on top of
    the system's, ``system`` a function that edits a copy of the system (``system.add``,
    ``connect(..., replace=True)``, ``remove``, ...), extra ``metrics``, ``requirements``
    and ``figures``, and ``not_judged``: the requirements (names) it is not meant to meet,
    a mapping to the reason or a sequence (the reason: the variant's description)."""

    description: str
    parameters: Mapping = field(default_factory=dict)
    system: Callable | None = None
    metrics: Sequence[Metric] = ()
    requirements: Sequence[Requirement] = ()
    figures: Sequence[Callable] = ()
    not_judged: Mapping | Sequence = ()
    line: int = field(init=False, default=0)

    def __post_init__(self):
        object.__setattr__(self, "line", _origin()[1])

    def exempt(self) -> dict[str, str]:
        """{requirement: why it is not judged}."""
        if isinstance(self.not_judged, Mapping):
            return dict(self.not_judged)
        return {name: self.description for name in self.not_judged}


_NOMINAL = Variant("the scenario as defined")


@dataclass(frozen=True)
class SignalBound:
    """A band low ≤ x ≤ high (either may be None) of a recorded signal over [start, stop]
    (None: the whole run), which campaign envelopes of the signal (``--keep``) draw: a
    requirement's band in green (``requirement`` names it: a variant that does not judge it
    draws none; the requirement may be on a statistic of the signal, e.g. its mean over the
    window, which the band bounds), or a device's ``limit`` as dashed red lines, the value
    of the system's ``parameter`` ("Component.name"): a campaign that sets or disperses
    that parameter draws none.  ``signal``: a variable (every element) or an element."""

    signal: str
    low: float | None
    high: float | None
    label: str
    start: float | None = None
    stop: float | None = None
    requirement: str | None = None
    limit: bool = False
    parameter: str | None = None

    def applies_to(self, column: str) -> bool:
        """Does it bound this recorded column ("A.x[2]")?"""
        return column == self.signal or column.partition("[")[0] == self.signal


class Scenario:
    """``name`` (an identifier), ``title``, the ``system``; ``metrics`` and ``requirements``
    (a metric's ``require=`` is one too); ``variants`` {name: :class:`Variant`};
    ``figures``: functions ``(results, out_dir) -> path or [paths]``; ``diagnose``:
    ``(results, metrics) -> [problems]``, the explanation of a run that did not fly as
    required (``metrics``: the summary's entries); ``systems_dir``: where ``agilesat
    generate`` writes its SSD (the shipped scenarios'; others render theirs on demand);
    ``bounds``: :class:`SignalBound` s a campaign's envelopes draw; ``phases``: the
    maneuver's phases ``(name, start, end)`` [s] that the report marks on its time axes."""

    def __init__(
        self,
        name: str,
        title: str,
        system: System,
        *,
        metrics: Sequence[Metric] = (),
        requirements: Sequence[Requirement] = (),
        variants: Mapping[str, Variant] | None = None,
        figures: Sequence[Callable] | Callable = (),
        diagnose: Callable | None = None,
        systems_dir=None,
        bounds: Sequence[SignalBound] = (),
        phases: Sequence[tuple[str, float, float]] = (),
    ):
        if not name.isidentifier():
            raise ValueError(f"scenario name {name!r} must be an identifier")
        if not isinstance(system, System):
            raise TypeError(f"scenario {name}: system must be a System, got {type(system)}")
        self.name, self.title, self.system = name, title, system
        self.metrics, self.requirements = list(metrics), list(requirements)
        self.variants = dict(variants or {})
        self.figures = [figures] if callable(figures) else list(figures)
        self.diagnose = diagnose
        self.bounds = list(bounds)
        self.phases = list(phases)
        self.systems_dir = None if systems_dir is None else Path(systems_dir)
        for variant in self.variants:
            if not variant.isidentifier():
                raise ValueError(f"scenario {name}: variant name {variant!r} is not an identifier")
        names = [m.name for m in self.metrics]
        twice = {n for n in names if names.count(n) > 1}
        if twice:
            raise ValueError(f"scenario {name}: metrics named twice: {sorted(twice)}")

    def __repr__(self):
        return f"<Scenario {self.name}: {self.title}; variants {list(self.variants)}>"

    # -- variants ---------------------------------------------------------------------
    def variant(self, name: str | None) -> Variant:
        """The variant ``name`` (None: the scenario as defined); a KeyError with the
        closest names for one it does not have."""
        if not name:
            return _NOMINAL
        if name not in self.variants:
            raise KeyError(
                f"scenario {self.name} has no variant {name!r}"
                + did_you_mean(name, self.variants)
                + f" (variants: {', '.join(self.variants) or 'none'})"
            )
        return self.variants[name]

    @functools.cache  # noqa: B019 - one system per scenario and variant
    def system_for(self, variant: str | None = None) -> System:
        """The system a variant runs: the scenario's, or a copy edited by the variant's
        ``system`` function, with the variant's parameter values."""
        v = self.variant(variant)
        if not variant:
            return self.system
        system = self.system.copy(f"{self.name}:{variant}")
        if v.system is not None:
            v.system(system)
        for key, value in v.parameters.items():
            system._set(key, value, v.line)
        return system

    def system_file(self, variant: str | None = None, build: bool = True):
        """The checked :class:`..system.ssp.SystemFile` of a variant (the FMUs built if
        ``build``)."""
        return self.system_for(variant).system_file(build)

    @property
    def ssd(self) -> Path | None:
        """The SSD file ``agilesat generate`` writes (shipped scenarios), else None."""
        return None if self.systems_dir is None else self.systems_dir / f"{self.name}.ssd"

    @property
    def components(self) -> tuple[str, ...]:
        return self.system.components

    @property
    def step(self):
        return self.system.step

    @property
    def stop(self):
        return self.system.stop

    # -- what a run is held to ------------------------------------------------------
    def metrics_for(self, variant: str | None = None) -> list[Metric]:
        return [*self.metrics, *self.variant(variant).metrics]

    def requirements_for(self, variant: str | None = None) -> list[Requirement]:
        """The scenario's and the variant's requirements, and each metric's bound."""
        bounds = []
        for m in self.metrics_for(variant):
            if m.require is None:
                continue
            if not isinstance(m.require, Bound):
                raise TypeError(
                    f"metric {m.name}: require= takes at_most(x), at_least(x) or within(a, b)"
                )
            bounds.append(m.require.on(m.name))
        found = [*bounds, *self.requirements, *self.variant(variant).requirements]
        names = [r.name for r in found]
        twice = {n for n in names if names.count(n) > 1}
        if twice:
            raise ValueError(f"scenario {self.name}: requirements named twice: {sorted(twice)}")
        unknown = set(self.variant(variant).exempt()) - set(names)
        if unknown:
            raise ValueError(
                f"scenario {self.name}:{variant}: not_judged names no requirement: "
                f"{sorted(unknown)} (requirements: {', '.join(names)})"
            )
        return found

    def evaluate(self, results, variant: str | None = None, partial: bool = False) -> dict:
        """The summary's ``metrics``, ``requirements``, ``diagnostics`` and ``status`` of a
        run of ``variant`` (see the module); ``partial``: the run recorded some outputs
        only (what needs another is not evaluated, and the diagnosis is left out)."""
        metrics = self.metrics_for(variant)
        values = {m.name: m.evaluate(results, partial) for m in metrics}
        errors = [v.reason for v in values.values() if v.failed]
        exempt = self.variant(variant).exempt()
        entries = {m.name: _entry(m, values[m.name]) for m in metrics}
        verdicts: dict[str, dict] = {}
        problems = []
        for r in self.requirements_for(variant):
            metric = getattr(r, "metric", None)
            unit = values[metric].unit if metric in values else None
            display = entries[metric]["display_unit"] if metric in entries else None
            statement = r.statement(unit, display) if isinstance(r, Bound) else r.statement()
            verdict = (
                Verdict(NOT_JUDGED, reason=exempt[r.name])
                if r.name in exempt
                else _judged(r, results, values, partial, errors)
            )
            if judged_over_campaign(r) and verdict.status not in (NOT_JUDGED, OVER_CAMPAIGN):
                # one verdict per requirement and scope: the campaign's
                text = f"{statement}: {OVER_CAMPAIGN}"
                verdict = Verdict(OVER_CAMPAIGN, verdict.value, OVER_CAMPAIGN_REASON, text)
            verdicts[r.name] = {
                "statement": statement,
                "verdict": verdict.status,
                "met": verdict.met,
                "value": verdict.value,
                **({"unit": unit, "display_unit": display} if unit else {}),
                **({"reason": verdict.reason} if verdict.reason else {}),
                **({"text": verdict.text} if verdict.text else {}),
                **({"details": verdict.details} if verdict.details else {}),
                **({"judged_over": "campaign"} if judged_over_campaign(r) else {}),
            }
            if metric in entries and isinstance(r, Bound):
                entries[metric]["requirement"] = r.limits(unit)
                entries[metric]["met"] = verdict.met
                entries[metric]["verdict"] = verdict.status
            if verdict.status == NOT_MET and verdict.text:
                problems.append(f"requirement {verdict.text}")
            elif verdict.status == NOT_MET:
                shown = (
                    format_value(verdict.value, unit, display)
                    if verdict.value is not None and unit
                    else repr(verdict.value)
                )
                problems.append(f"requirement {statement} not met: {shown}")
        if self.diagnose is not None and not partial:
            try:
                problems += list(self.diagnose(results, entries))
            except Exception as exc:  # noqa: BLE001 - the diagnosis's mistake: said
                errors.append(f"the diagnosis {defined_at(self.diagnose)} {_raised(exc)}")
        return {
            "metrics": entries,
            "requirements": verdicts,
            "diagnostics": problems,
            "status": "error" if errors else "failed" if problems else "ok",
            **({"errors": errors} if errors else {}),
        }

    def bounds_for(self, variant: str | None = None) -> list[SignalBound]:
        """The signal bounds a variant keeps: not those of requirements it does not judge."""
        exempt = self.variant(variant).exempt()
        return [b for b in self.bounds if b.requirement is None or b.requirement not in exempt]

    def figures_for(self, variant: str | None = None) -> list[Callable]:
        """The scenario's and the variant's figure functions."""
        return [*self.figures, *self.variant(variant).figures]

    def draw(self, results, out_dir, variant: str | None = None) -> list[Path]:
        """The scenario's and the variant's figures of a run, into ``out_dir``."""
        paths: list[Path] = []
        for figure in self.figures_for(variant):
            made = figure(results, Path(out_dir))
            paths += [Path(p) for p in (made if isinstance(made, (list, tuple)) else [made])]
        return paths


def _judged(requirement, results, values: dict, partial: bool, errors: list) -> Verdict:
    """The verdict of ``requirement``; not evaluated where it cannot be had, and where it
    raised (a mistake of the requirement's: said in ``errors`` too)."""
    try:
        return requirement.evaluate(results, values)
    except NotEvaluable as reason:
        return Verdict(NOT_EVALUATED, reason=str(reason))
    except ColumnError as missing:
        if partial:
            return Verdict(NOT_EVALUATED, reason=f"not recorded: {missing}")
        failure: Exception = missing
    except Exception as exc:  # noqa: BLE001 - said, the run kept
        failure = exc
    where = getattr(requirement, "origin", "")
    reason = f"requirement {requirement.name}{f' ({where})' if where else ''} {_raised(failure)}"
    errors.append(reason)
    return Verdict(NOT_EVALUATED, reason=reason)


def _raised(exc: Exception) -> str:
    return f"raised {type(exc).__name__}: {exc}"


def defined_at(function) -> str:
    """Where a function was defined, as "(file:line)" ("" if unknown)."""
    code = getattr(function, "__code__", None)
    return f"({code.co_filename}:{code.co_firstlineno})" if code is not None else ""


def _entry(metric: Metric, value) -> dict:
    return {
        "value": value.value,
        "unit": value.unit,
        "display_unit": metric.display_unit or value.unit,
        "description": metric.description,
        **({"reason": value.reason} if value.value is None else {}),
        **({"failed": True} if value.failed else {}),
        **({"paper": metric.paper} if metric.paper is not None else {}),
    }


__all__ = ["MET", "Scenario", "SignalBound", "Variant"]
