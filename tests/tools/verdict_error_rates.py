"""How often is a verdict wrong?  Synthetic campaigns of known distributions through the
verdict code agilesat uses (``agilesat.orchestration.pointing``: ``decide_counts``,
``decide``, ``PointingRequirement.judge``, ``next_look``), and the rates of false "met"
and false "not met" against the nominal risk α = 1 − confidence (docs/pointing.md).

    python tests/tools/verdict_error_rates.py           # the tables (markdown)
    python tests/tools/verdict_error_rates.py --check   # and exit 1 if a false rate exceeds
                                                         # α + 3 binomial standard errors

The truth of each campaign is known: at the worst time (ensemble) or over all (run, time)
pairs (mixed) the index exceeds the bound with probability p, and q = 1 − level is what the
requirement allows.  p = q/20 is compliant with margin, p = q is exactly at the bound (still
compliant, and the hardest case for both tests), p = 4 q violates.  A "met" is false when
p > q, a "not met" when p ≤ q; at the bound both happen at most α of the time.

- ensemble, fixed campaigns: every evaluated time at p, independent (the most chances of a
  false "not met"), or one time at p and the others never above (a single worst time: the
  most chances of a false "met");
- mixed: whole runs above or not (the runs' shares 0 or 1), or each run's times
  independent (shares Binomial(T, p)/T);
- temporal: each run's own time, no confidence: a run whose share of time above the bound
  exceeds q is a violation, shown; "met" says every run made meets it (when a share ρ of
  the realisations violate, a campaign of n runs says "met" with probability (1 − ρ)^n);
- until decided: the looks of ``agilesat campaign --until-decided`` (``next_look``) from a
  first look to a most, decided or not;
- whole error histories: AR(1) Gaussian errors (correlated in time) through
  ``PointingRequirement.judge``, as a campaign's directory is judged.

The ensemble verdict on runs above the bound or not depends on the count at the worst time
only (the evidences are monotonic in the count): the campaigns are drawn as counts, the
verdict of each worst count asked once (and checked on whole count vectors).  Seeded: the
same command prints the same tables.
"""

from __future__ import annotations

import argparse
import functools
import math
import sys
import time

import numpy as np
from scipy.special import ndtri  # type: ignore[import-untyped]

from agilesat.orchestration.pointing import (
    PointingRequirement,
    decide,
    decide_counts,
    next_look,
)

SEED = 20261207
LEVELS = ((0.9973, 0.95), (0.9, 0.9))  # (level, confidence)
TRUTHS = (("margin", 1 / 20), ("at the bound", 1.0), ("violating", 4.0))  # p / q
OUTCOMES = ("met", "not met", "undecided")
#: (times per run, how the runs' shares above the bound are drawn)
MIXED_MODELS = ((1, "whole runs"), (40, "times independent"), (4000, "times independent"))


@functools.cache
def _verdict_of_worst(worst: int, runs: int, times: int, level: float, confidence: float):
    """The verdict of a campaign whose most runs above the bound at one of ``times`` times
    is ``worst``."""
    counts = np.zeros(times)
    counts[0] = worst
    return decide_counts(counts, runs, level, confidence)


def _verdict(counts: np.ndarray, runs: int, level: float, confidence: float) -> str:
    return _verdict_of_worst(int(counts.max()), runs, len(counts), level, confidence).status


class Cell:
    """The outcomes of ``campaigns`` campaigns of one kind, and whether their false rates
    hold the bound."""

    def __init__(self, label: tuple, alpha: float, p_over_q: float, outcomes: list[str]):
        self.label, self.alpha, self.p_over_q = label, alpha, p_over_q
        self.count = len(outcomes)
        self.rates = {o: outcomes.count(o) / self.count for o in OUTCOMES}

    def false_rates(self) -> dict[str, float]:
        """{outcome: rate} of the outcomes that are false for this truth."""
        false = {}
        if self.p_over_q >= 1:
            false["met"] = self.rates["met"]
        if self.p_over_q <= 1:
            false["not met"] = self.rates["not met"]
        return false

    def allowed(self) -> float:
        return self.alpha + 3 * math.sqrt(self.alpha * (1 - self.alpha) / self.count)

    def failures(self) -> list[str]:
        return [
            f"{' '.join(map(str, self.label))}: false {o} {r:.4f} > {self.allowed():.4f}"
            for o, r in self.false_rates().items()
            if r > self.allowed()
        ]


def ensemble_fixed(rng, campaigns: int) -> list[Cell]:
    cells = []
    for level, confidence in LEVELS:
        q = 1 - level
        for runs in (60, 1109, 4000):
            for times, where in ((40, "every time"), (4000, "every time"), (4000, "one time")):
                for name, ratio in TRUTHS:
                    if where == "every time":
                        counts = rng.binomial(runs, ratio * q, size=(campaigns, times))
                    else:
                        counts = np.zeros((campaigns, times), dtype=int)
                        counts[:, 0] = rng.binomial(runs, ratio * q, size=campaigns)
                    outcomes = [_verdict(c, runs, level, confidence) for c in counts]
                    for c in counts[:20]:  # the shortcut is the verdict of the whole vector
                        assert decide_counts(c, runs, level, confidence).status == _verdict(
                            c, runs, level, confidence
                        )
                    label = (f"{level:g}/{confidence:g}", runs, times, where, name)
                    cells.append(Cell(label, 1 - confidence, ratio, outcomes))
    return cells


def mixed_fixed(rng, campaigns: int) -> list[Cell]:
    cells = []
    for level, confidence in LEVELS:
        q = 1 - level
        for runs in (60, 1109):
            for times, model in MIXED_MODELS:
                for name, ratio in TRUTHS:
                    p = ratio * q
                    outcomes = []
                    for _ in range(campaigns):
                        if model == "whole runs":
                            x = rng.random(runs) < p
                        else:
                            x = rng.binomial(times, p, size=runs) / times
                        outcomes.append(decide(x, level, confidence).status)
                    label = (f"{level:g}/{confidence:g}", runs, times, model, name)
                    cells.append(Cell(label, 1 - confidence, ratio, outcomes))
    return cells


def temporal(rng, campaigns: int) -> list[tuple]:
    """(level, runs, truth, rates) of temporal requirements judged by
    ``PointingRequirement.judge`` on runs whose share of time above the bound is known: at
    most q (every realisation complies), or 4 q for a share ρ of them."""
    rows = []
    times, bound = 400, 1.0
    t = np.arange(times) * 0.1
    for level in (0.99, 0.9):
        q = 1 - level
        requirement = PointingRequirement("APE", bound, level, "temporal")
        for runs in (60,):
            for truth, share_ok, violating in (
                ("every run at q/2", q / 2, 0.0),
                ("every run at q", q, 0.0),
                ("1 % of runs at 4 q", q, 0.01),
                ("10 % of runs at 4 q", q, 0.1),
            ):
                outcomes = []
                for _ in range(campaigns):
                    bad = rng.random(runs) < violating
                    above = np.where(bad, round(4 * q * times), round(share_ok * times))
                    m = np.where(np.arange(times) < above[:, None], 2 * bound, bound / 2)
                    outcomes.append(requirement.judge(t, m).status)
                rates = {o: outcomes.count(o) / campaigns for o in OUTCOMES}
                rows.append((f"{level:g}", runs, truth, violating, rates))
    return rows


def until_decided(rng, campaigns: int) -> list[tuple]:
    """(cell, mean runs, most runs) of campaigns run until decided."""
    rows = []
    for (level, confidence), first, most in (((0.9973, 0.95), 60, 4000), ((0.9, 0.9), 20, 1000)):
        q = 1 - level
        for times, where in ((400, "every time"), (400, "one time")):
            for name, ratio in TRUTHS:
                p = ratio * q
                outcomes, used = [], []
                for _ in range(campaigns):
                    runs, counts = 0, np.zeros(times, dtype=int)
                    target = first
                    while True:
                        new = target - runs
                        if where == "every time":
                            counts += rng.binomial(new, p, size=times)
                        else:
                            counts[0] += rng.binomial(new, p)
                        runs = target
                        verdict = _verdict_of_worst(
                            int(counts.max()), runs, times, level, confidence
                        )
                        if verdict.status != "undecided" or runs >= most:
                            break
                        target = next_look(runs, [verdict.runs_to_decide()], most)
                    outcomes.append(verdict.status)
                    used.append(runs)
                label = (f"{level:g}/{confidence:g}", f"{first}–{most}", times, where, name)
                cell = Cell(label, 1 - confidence, ratio, outcomes)
                rows.append((cell, float(np.mean(used)), int(np.max(used))))
    return rows


def histories(rng, campaigns: int) -> list[Cell]:
    """Ensemble and mixed requirements judged on whole AR(1) Gaussian error histories
    (unit variance, correlation 0.9 from one sample to the next): |e| exceeds B with
    probability 2 Φ(−B) at every time."""
    cells = []
    level, confidence, runs, samples = 0.9, 0.9, 200, 400
    rho = 0.9
    t = np.arange(samples) * 0.1
    for interpretation in ("ensemble", "mixed"):
        for name, ratio in TRUTHS:
            bound = -ndtri(ratio * (1 - level) / 2)
            requirement = PointingRequirement(
                "APE", bound, level, interpretation, confidence=confidence
            )
            outcomes = []
            for _ in range(campaigns):
                e = np.empty((runs, samples))
                e[:, 0] = rng.normal(size=runs)
                noise = rng.normal(size=(runs, samples)) * math.sqrt(1 - rho**2)
                for k in range(1, samples):
                    e[:, k] = rho * e[:, k - 1] + noise[:, k]
                outcomes.append(requirement.judge(t, np.abs(e)).status)
            label = (f"{level:g}/{confidence:g}", runs, samples, interpretation, name)
            cells.append(Cell(label, 1 - confidence, ratio, outcomes))
    return cells


def _rates(cell: Cell) -> str:
    return " / ".join(f"{cell.rates[o]:.3f}" for o in OUTCOMES)


def table(title: str, header: list[str], cells: list[Cell], extra=None) -> list[str]:
    """One row per campaign kind (the label but the truth), the truths side by side."""
    lines = [f"{title}", "", "| " + " | ".join(header + [n for n, _ in TRUTHS]) + " |"]
    lines.append("|" + "---|" * (len(header) + len(TRUTHS)))
    for start in range(0, len(cells), len(TRUTHS)):
        group = cells[start : start + len(TRUTHS)]
        first = [str(x) for x in group[0].label[:-1]]
        more = [] if extra is None else extra(start // len(TRUTHS))
        lines.append("| " + " | ".join(first + more + [_rates(c) for c in group]) + " |")
    return lines + [""]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--campaigns", type=int, default=1000, help="per kind (default 1000)")
    parser.add_argument("--check", action="store_true", help="exit 1 if a false rate is high")
    args = parser.parse_args(argv)
    began = time.monotonic()
    rng = np.random.default_rng(SEED)
    k = args.campaigns
    fixed = ensemble_fixed(rng, k)
    mixed = mixed_fixed(rng, k // 2)
    sequential = until_decided(rng, k // 4)
    whole = histories(rng, k // 10)
    tempo = temporal(rng, k // 10)
    lines = [
        "Rates of met / not met / undecided for each truth (p/q: 1/20 compliant with "
        f"margin, 1 at the bound, 4 violating); {k} campaigns per kind "
        f"({k // 2} mixed, {k // 4} until decided, {k // 10} whole histories and temporal).",
        "",
    ]
    lines += table(
        "Ensemble, campaigns of a fixed size:",
        ["level/confidence", "runs", "times", "above the bound"],
        fixed,
    )
    lines += table(
        "Mixed, campaigns of a fixed size:",
        ["level/confidence", "runs", "times", "the runs' shares"],
        mixed,
    )
    cells = [row[0] for row in sequential]
    spent = [row[1:] for row in sequential]
    lines += table(
        "Ensemble, until decided (`--until-decided`: first look – most runs; the runs "
        "made, mean (most), per truth):",
        ["level/confidence", "runs", "times", "above the bound", "runs made"],
        cells,
        lambda g: [
            " / ".join(f"{m:.0f} ({x})" for m, x in spent[g * len(TRUTHS) : (g + 1) * len(TRUTHS)])
        ],
    )
    lines += table(
        "Whole AR(1) error histories (correlated in time) through PointingRequirement.judge:",
        ["level/confidence", "runs", "times", "interpretation"],
        whole,
    )
    lines += ["Temporal (no confidence: each run on its own time):", ""]
    lines += ["| level | runs | truth | met | not met |", "|---|---|---|---|---|"]
    failures = [f for c in fixed + mixed + cells + whole for f in c.failures()]
    for level, runs, truth, violating, rates in tempo:
        lines.append(
            f"| {level} | {runs} | {truth} | {rates['met']:.3f} | {rates['not met']:.3f} |"
        )
        if not violating and rates["not met"]:
            failures.append(f"temporal {level} {truth}: not met {rates['not met']}")
    print("\n".join(lines))
    print(f"({time.monotonic() - began:.0f} s)", file=sys.stderr)
    if args.check:
        for failure in failures:
            print(f"FALSE RATE TOO HIGH: {failure}", file=sys.stderr)
        return 1 if failures else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
