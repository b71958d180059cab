"""A campaign's plan: the specification checked against the system, and the parameter
values of every run.

Run index i (0 ≤ i < runs × grid points) is grid point ``i % G`` and replicate ``i // G``
(G: the number of grid points, 1 without grids), so extending ``--runs`` keeps every run
already made.  Run i's values are the system's (the target's, a variant's values in it),
``--set``'s, and the grid point's values and the draws of :meth:`Dispersion.draw` for
index i on top.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from ..cosim.options import ALGORITHM, STEP, STOP, RunOptions, flag, setting
from ..mission import reads
from ..mission.requirements import judged_over_campaign
from ..mission.targets import resolve
from ..system.description import Description
from ..system.parameters import (
    ArrayVariable,
    choice_names,
    choice_value,
    did_you_mean,
    typed_parameters,
    variables,
)
from . import dispersion as dispersions


@dataclass
class Spec:
    """What the user asked for (``campaign.json``'s ``spec``; a resumed campaign must match
    it in everything but ``runs``): ``agilesat campaign``'s options, each with its flag
    (:func:`..cosim.options.flag`)."""

    target: str
    runs: int = flag("--runs", default=1, type=int, help="runs per grid point (default 1)")
    seed: int = flag("--seed", default=0, type=int, help="campaign seed (default 0)")
    vary: list[str] = flag(  # "A.x=DIST", as written
        "--vary",
        action="append",
        metavar="INSTANCE.VAR=DIST",
        help="disperse a parameter (DIST above); repeat for more",
    )
    files: list[str] = flag(  # dispersion files they came from
        "--dispersions",
        action="append",
        metavar="FILE",
        help='TOML/JSON file with a [vary] table of "Instance.var" = "DIST"',
    )
    set: dict = flag(  # "A.x" -> value (as for `run --set`)
        "--set",
        action="append",
        type=setting,
        metavar="INSTANCE.VAR=VALUE",
        help="a parameter value of every run (as `agilesat run --set`)",
    )
    keep: list[str] = flag(  # signals to keep per run
        "--keep",
        action="append",
        metavar="SIGNAL",
        help="keep this output per run (signals.npy, envelope figure); a whole "
        "vector (SatelliteDynamics.w_BO_B) or one element",
    )
    step: float | None = flag("--step", **STEP)
    stop: float | None = flag("--stop", **STOP)
    algorithm: str | None = flag("--algorithm", **ALGORITHM)

    def __post_init__(self):
        self.vary, self.keep = list(self.vary or ()), list(self.keep or ())
        self.files = [str(f) for f in self.files or ()]
        self.set = dict(self.set or {})  # the command line gives (key, value) pairs

    def to_dict(self) -> dict:
        return asdict(self)

    def differences(self, other: Spec) -> list[str]:
        a, b = self.to_dict(), other.to_dict()
        return [
            f"{k}: {a[k]!r} here, {b[k]!r} in the campaign"
            for k in a
            if k != "runs" and a[k] != b[k]
        ]


def over_campaign(scenario, variant) -> list:
    """The requirements of ``scenario``'s ``variant`` judged over the whole campaign (an
    ensemble or mixed statistic; a Pointing requirement whose statistic is temporal is
    judged run by run) that the variant judges; none without a scenario."""
    if scenario is None:
        return []
    exempt = scenario.variant(variant).exempt()
    return [
        r
        for r in scenario.requirements_for(variant)
        if judged_over_campaign(r) and r.name not in exempt
    ]


class Plan:
    def __init__(self, spec: Spec):
        if spec.runs < 1:
            raise ValueError(f"--runs must be at least 1, got {spec.runs}")
        if not 0 <= spec.seed < 2**63:
            raise ValueError(f"--seed must be a non-negative integer, got {spec.seed}")
        self.spec = spec
        found = resolve(spec.target)
        self.scenario, self.variant = found.scenario, found.variant
        #: the target as the workers take it (a mission file by its absolute path)
        self.target = _absolute(spec.target) if found.scenario is not None else spec.target
        #: campaign.json's ``target``: found again from any folder (``agilesat pointing``)
        self.target_record = found.record()
        self.system = found.system_file(build=True)  # the FMUs built once, here
        if found.scenario is not None:  # what its metrics and requirements read: outputs
            reads.check(found.scenario, found.variant)
        self.step = spec.step or self.system.step_size
        self.stop = self.system.stop_time if spec.stop is None else spec.stop
        self.start = self.system.start_time
        if not (self.step and self.stop and self.stop > self.start):
            raise ValueError(f"{self.system.path}: give --step and --stop (the system sets none)")
        self.points = int(round((self.stop - self.start) / self.step)) + 1
        self.fmus = {c.name: Path(c.source).stem for c in self.system.components}
        #: what each component's model description says (any FMU, ours or not), and its
        #: variables by whole name (shapes, types, starts, named choices)
        self.described = {c.name: Description(c.name, c.source) for c in self.system.components}
        self.tables = {name: variables(d) for name, d in self.described.items()}
        self.values = {f"{p.component}.{p.name}": p.value for p in self.system.parameters}
        self.values.update(spec.set)
        typed_parameters(self.described, spec.set)  # a bad value: here, not in every run
        self.dispersions = [dispersions.parse(text) for text in spec.vary]
        keys = [d.key for d in self.dispersions]
        twice = sorted({k for k in keys if keys.count(k) > 1})
        if twice:
            raise ValueError(f"dispersed twice: {', '.join(twice)}")
        self.choices = {}  # key -> the names of a named-choice parameter's values 0, 1, ...
        self.integers = set()  # keys of Integer parameters
        self.nominal = {}
        for k, d in enumerate(self.dispersions):
            self.dispersions[k], self.nominal[d.key] = self._check(d)
        self.columns = [
            name
            for d in self.dispersions
            for name in _scalar_names(d.key, self.nominal[d.key].shape)
        ]
        #: the table's type of each dispersed column: i (Integer), s (a choice's name), f
        self.kinds = {
            name: "s" if d.key in self.choices else "i" if d.key in self.integers else "f"
            for d in self.dispersions
            for name in _scalar_names(d.key, self.nominal[d.key].shape)
        }
        overlap = set(self.columns) & set(spec.set)
        if overlap:
            raise ValueError(f"both --set and dispersed: {', '.join(sorted(overlap))}")
        grids = [d for d in self.dispersions if d.is_grid]
        self.grid_keys = [d.key for d in grids]
        total = spec.runs * math.prod(d.points for d in grids)
        if total > dispersions.MAX_RUNS:
            raise ValueError(
                f"{spec.runs} run(s) × {' × '.join(str(d.points) for d in grids) or 1} grid "
                f"points = {total} runs, more than the {dispersions.MAX_RUNS} a campaign may "
                "have (its journal and table are held in memory): split it"
            )
        self.grid = list(itertools.product(*(d.grid() for d in grids))) or [()]
        self.units = {}  # of the kept signals, as their model descriptions say
        #: the signals kept of every run: those asked for (``kept``), then those the
        #: requirements judged over the campaign need
        self.kept = [name for key in spec.keep for name in self._signal(key)]
        self.signals = list(self.kept)
        #: the requirements judged over the whole campaign (an ensemble or mixed
        #: statistic; a Pointing requirement whose statistic is temporal is judged run by
        #: run: ``over_campaign`` false), and the columns of every run they need, kept
        #: with the others
        self.ensemble = over_campaign(self.scenario, self.variant)
        for requirement in self.ensemble:
            self.signals += [c for c in requirement.signals if c not in self.signals]

    @property
    def total(self) -> int:
        return self.spec.runs * len(self.grid)

    def run_values(self, index: int) -> dict:
        """The dispersed scalar values of run ``index`` ({"A.x[1]": float, ...})."""
        grid = dict(zip(self.grid_keys, self.grid[index % len(self.grid)]))
        result = {}
        for d in self.dispersions:
            nominal = self.nominal[d.key]
            value = (
                d.apply(grid[d.key], nominal)
                if d.is_grid
                else d.draw(self.spec.seed, index, nominal)
            )
            for name, x in zip(_scalar_names(d.key, nominal.shape), np.ravel(value)):
                if d.key in self.choices:  # by name, as --set takes it
                    result[name] = self.choices[d.key][int(x)]
                else:
                    result[name] = int(x) if d.key in self.integers else x.item()
        return result

    def run_options(self, parameters: dict | None = None) -> RunOptions:
        """The options of a run of the campaign: its step, stop and algorithm, ``--set``
        and ``parameters`` on top; no figures, the FMUs built already."""
        return RunOptions(
            step=self.step,
            stop=self.stop,
            algorithm=self.spec.algorithm,
            parameters={**self.spec.set, **(parameters or {})},
            figures=False,
            build=False,
        )

    def parameters(self, index: int) -> dict:
        """Everything run ``index`` sets on top of the system: ``--set`` and its values."""
        return {**self.spec.set, **self.run_values(index)}

    def _variable(self, key: str, what: str) -> ArrayVariable:
        """The variable ``key`` ("A.x", or an element "A.x[i]") names, from its FMU's model
        description; a ValueError naming what there is for a name that is none."""
        instance, _, rest = key.partition(".")
        name = rest.partition("[")[0]
        if instance not in self.tables:
            raise ValueError(
                f"{what} {key}: no component {instance!r} in {self.system.path}; "
                f"components: {', '.join(self.fmus)}" + did_you_mean(instance, self.fmus)
            )
        table = self.tables[instance]
        if name not in table:
            raise ValueError(
                f"{what} {key}: {self.fmus[instance]} has no variable {name!r}"
                + did_you_mean(name, table)
            )
        var = table[name]
        if "[" in rest and rest not in _names(var):
            raise ValueError(
                f"{what} {key}: {instance}.{name} has shape {var.shape}; "
                f"elements are {var.first.name} .. {var.scalars[-1].name}"
            )
        return var

    def _check(self, d) -> tuple:
        """(the dispersion, named choices resolved to their values; the nominal value of
        the dispersed variable), after checking that the dispersion fits it."""
        var = self._variable(d.key, "--vary")
        kind, causality = var.first.type, var.first.causality
        names = choice_names(var.first)
        whole = "[" not in d.key
        if any(isinstance(a, str) for a in d.args) and names is None:
            raise ValueError(
                f"--vary {d.text}: names are for a named-choice parameter, "
                f"{d.instance}.{d.variable} has none: give numbers"
            )
        if causality != "parameter" or kind == "String":
            raise ValueError(
                f"--vary {d.text}: {d.instance}.{var.name} is a {kind} "
                f"{causality}; only numeric parameters can be dispersed"
            )
        if kind != "Real" and d.kind not in ("choice", "values", "integers"):
            raise ValueError(
                f"--vary {d.text}: {kind} parameter: use choice(), values() or integers()"
            )
        if names is not None:
            d = self._named(d, var.name, names)
        elif kind == "Integer":
            self.integers.add(d.key)
        flat = np.array(
            [
                self._number(f"{d.instance}.{scalar.name}", names, start)
                for scalar, start in zip(var.scalars, np.ravel(np.array(var.start(), object)))
            ],
            dtype=float,
        )
        if not whole:
            return d, np.asarray(flat[_names(var).index(d.key.partition(".")[2])])
        shape = var.shape
        if d.is_grid and shape:
            raise ValueError(
                f"--vary {d.text}: grids take scalar names, e.g. {d.instance}.{var.first.name}"
            )
        if d.kind == "rotate" and not (shape == (3,) or len(shape) == 2 and shape[1] == 3):
            raise ValueError(
                f"--vary {d.text}: rotate() turns a 3-vector or the rows of an "
                f"n×3 matrix; {d.instance}.{var.name} has shape {shape}"
            )
        norms = np.linalg.norm(flat.reshape(shape), axis=-1) if d.kind == "rotate" else None
        if norms is not None and not np.allclose(norms, 1.0, atol=1e-6):
            raise ValueError(
                f"--vary {d.text}: rotate() turns unit vectors; {d.instance}.{var.name} "
                f"has norm(s) {np.round(norms, 6).tolist()}, not 1"
            )
        if d.kind == "inertia" and shape != (3, 3):
            raise ValueError(
                f"--vary {d.text}: inertia() disperses a 3×3 inertia; "
                f"{d.instance}.{var.name} has shape {shape}"
            )
        nominal = flat.reshape(shape)
        _elementwise_on_a_symmetric_matrix(d, nominal)
        if d.kind == "inertia" and not (
            np.allclose(nominal, nominal.T) and np.linalg.eigvalsh(nominal).min() > 0
        ):
            raise ValueError(
                f"--vary {d.text}: nominal {nominal.tolist()} is not symmetric positive definite"
            )
        return d, nominal

    def _number(self, key: str, names, start) -> float:
        """The nominal value of scalar ``key``: the system's or ``--set``'s, else its start;
        a named choice's by its number."""
        value = self.values.get(key, start)
        return float(value if names is None else choice_value(key, names, value, key))

    def _named(self, d, variable: str, names):
        """choice()/values() of a named-choice parameter, its names (any case) or numbers
        resolved to the values 0, 1, ... (the draws then are those of the numbers)."""
        if d.mode:
            raise ValueError(f"--vary {d.text}: a named choice cannot be added or multiplied")
        args = tuple(
            float(
                choice_value(
                    variable,
                    names,
                    int(a) if isinstance(a, float) and a.is_integer() else a,
                    f"--vary {d.text}",
                )
            )
            for a in d.args
        )
        self.choices[d.key] = list(names)
        return replace(d, args=args)

    def _signal(self, key: str) -> list[str]:
        """The recorded columns of a ``--keep`` name (a whole variable: all its elements);
        a ValueError naming what there is if the run does not record it (only outputs
        are recorded)."""
        instance, _, name = key.partition(".")
        if instance not in self.fmus:
            self._variable(key, "--keep")  # raises, naming the components there are
        described = self.described[instance]
        base = name.partition("[")[0]
        columns = [o for o in described.outputs if o.partition("[")[0] == base]
        if not columns:
            causality = next(
                (
                    v.causality
                    for n, v in described.variables.items()
                    if n.partition("[")[0] == base
                ),
                None,
            )
            listing = ", ".join(dict.fromkeys(o.partition("[")[0] for o in described.outputs))
            raise ValueError(
                f"--keep {key}: {self.fmus[instance]} has "
                + (f"{base!r} as a {causality}" if causality else f"no variable {base!r}")
                + f"; a run records the outputs, {instance}'s are: {listing}"
            )
        if name != base:
            if name not in columns:
                raise ValueError(
                    f"--keep {key}: the elements of {instance}.{base} are "
                    f"{columns[0]} .. {columns[-1]}"
                )
            columns = [name]
        self.units.update({f"{instance}.{n}": described.variables[n].unit for n in columns})
        return [f"{instance}.{n}" for n in columns]


def _absolute(target: str) -> str:
    """A mission file's target with its absolute path (the workers' working directory may
    be another); any other target as it is."""
    if ".py" not in target:
        return target
    name, _, variant = target.rpartition(":") if ".py:" in target else (target, "", "")
    path = str(Path(name).resolve())
    return f"{path}:{variant}" if variant else path


def _names(var: ArrayVariable) -> list[str]:
    """The scalar names of a variable ("inertia[1,1]", ...; its name if a scalar)."""
    return [scalar.name for scalar in var.scalars]


def _scalar_names(key: str, shape) -> list[str]:
    if not shape:
        return [key]
    return [f"{key}[{','.join(str(i + 1) for i in idx)}]" for idx in np.ndindex(*shape)]


def time_axis(plan: Plan) -> np.ndarray:
    return plan.start + plan.step * np.arange(plan.points)


def _elementwise_on_a_symmetric_matrix(d, nominal: np.ndarray) -> None:
    """A random draw per element of a whole symmetric positive definite matrix (an
    inertia) would make no run's matrix symmetric: every run would fail ("inertia must be
    symmetric").  Refused up front, saying what disperses one."""
    square = nominal.ndim == 2 and nominal.shape[0] == nominal.shape[1] > 1
    if not (square and d.kind in ("normal", "uniform", "choice", "integers")):
        return
    if not (np.allclose(nominal, nominal.T) and np.linalg.eigvalsh(nominal).min() > 0):
        return  # not an inertia-like matrix (a misalignment's draws are free)
    expression = d.text.partition("=")[2].lstrip("+*")
    hint = ""
    if not d.mode and np.abs(nominal).max() > 10 * max(map(abs, d.args)):
        hint = (
            f" (and it draws them around {d.args[0]:g}, the nominal's are up to "
            f"{np.abs(nominal).max():g}: a leading * multiplies the nominal)"
        )
    raise ValueError(
        f"--vary {d.text}: draws each of the {nominal.size} elements of {d.key} on its own"
        f"{hint}, so no run's matrix would be symmetric as the nominal is: inertia(sd_rel, "
        f"sd_angle) disperses an inertia (its principal moments by sd_rel, its axes by "
        f"sd_angle), or disperse elements one by one ({d.key}[1,1]=*{expression})"
    )
