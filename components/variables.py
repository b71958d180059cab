"""Variable tables: the single source of truth for every model's interface.

Each model module declares ``VARIABLES``, a tuple of :class:`Var`.  From that one table
the FMU wrapper registers the FMI variables, ``modelDescription.xml`` gets its units,
start values and output dependencies, the docs get their interface tables and the tests
get their expectations.  Nothing else restates a name, unit or start value.

Array variables use FMI structured names, 1-based: ``w_BI_B[1]``, ``inertia[2,3]``.
All values of a model (Real, Integer and Boolean alike) live in one flat float64 array:
parameters, then inputs, then outputs, each group in table order; the offset of a scalar
in that array is its FMI value reference, so each group is one contiguous range.  String
parameters follow the numeric ones and are kept in a dict.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np

from .runtime import choices as runtime_choices

CAUSALITIES = ("parameter", "input", "output")
TYPES = ("Real", "Integer", "Boolean", "String")

#: every unit a table may use: name -> (SI base-unit exponents, {display unit: factor}),
#: display = factor * value (modelDescription.xml's UnitDefinitions, the SSDs' Units)
UNITS = {
    "1": ({}, {}),
    "s": ({"s": 1}, {}),
    "m": ({"m": 1}, {"km": 1e-3}),
    "m/s": ({"m": 1, "s": -1}, {"km/s": 1e-3}),
    "m3/s2": ({"m": 3, "s": -2}, {}),
    "rad": ({"rad": 1}, {"deg": 180 / math.pi}),
    "rad/s": ({"rad": 1, "s": -1}, {"deg/s": 180 / math.pi, "rpm": 30 / math.pi}),
    "rad/s2": ({"rad": 1, "s": -2}, {"deg/s2": 180 / math.pi}),
    "rad/s3": ({"rad": 1, "s": -3}, {"deg/s3": 180 / math.pi}),
    "kg": ({"kg": 1}, {}),
    "kg.m": ({"kg": 1, "m": 1}, {}),
    "N": ({"kg": 1, "m": 1, "s": -2}, {}),
    "kg.m2": ({"kg": 1, "m": 2}, {}),
    "N.m": ({"kg": 1, "m": 2, "s": -2}, {}),
    "N.m.s": ({"kg": 1, "m": 2, "s": -1}, {}),
    "N.m/rad": ({"kg": 1, "m": 2, "s": -2, "rad": -1}, {}),
    "N.m.s/rad": ({"kg": 1, "m": 2, "s": -1, "rad": -1}, {}),
    "N.m/rad/s": ({"kg": 1, "m": 2, "s": -3, "rad": -1}, {}),
    "Hz": ({"s": -1}, {}),
    "1/s": ({"s": -1}, {}),
    "m2": ({"m": 2}, {}),
    "kg/m3": ({"kg": 1, "m": -3}, {}),
    "N/m2": ({"kg": 1, "m": -1, "s": -2}, {}),
    "A.m2": ({"A": 1, "m": 2}, {}),
    "T": ({"kg": 1, "s": -2, "A": -1}, {"nT": 1e9}),
    # gyro noise densities (IEEE Std 952-1997): FMI 2.0 base-unit exponents are integers,
    # so these carry their dimension in the name only (an empty BaseUnit)
    "rad/s0.5": ({}, {"deg/h0.5": 180 / math.pi * 60}),
    "rad/s1.5": ({}, {"deg/h1.5": 180 / math.pi * 3600 * 60}),
    # mass-normalised modal coordinates and participation factors (kg^½·m), likewise
    "kg0.5.m": ({}, {}),
    "kg0.5.m/s": ({}, {}),
}


@dataclass(frozen=True)
class Var:
    """One row of a variable table.

    ``depends`` (outputs only) names the inputs with direct feedthrough to this output at
    a communication point; an output that is a function of the state alone leaves it
    empty.  ``optional`` (inputs only): empty, a system must connect the input (or give it
    a parameter value); else the input may be left open and keeps its start value, and the
    text says what that default means ("zero: no wheel momentum"): a master lists each open
    optional input with it.  An array input is connected as a whole or not at all.
    ``start`` is a scalar (broadcast) or a nested sequence of ``shape``.  ``choices``
    (scalar Integer parameters only, made by :func:`choice`): the (NAME, meaning) of the
    values 0, 1, …: a named choice instead of a bare number; :meth:`choice_value` reads a
    name or a number.  ``derivative_of`` (Real inputs and outputs): this variable is the
    time derivative of that one of the same causality and shape (its unit per second):
    ``hdot`` of ``h``.  The model description says so (FMI 2.0 ``derivative``
    attribute), and the FMU answers ``fmi2GetRealOutputDerivatives`` of the output with
    the derivative's value and stores ``fmi2SetRealInputDerivatives`` of the input in it.
    """

    name: str
    causality: str
    unit: str
    description: str
    start: object = 0.0
    shape: tuple[int, ...] = ()
    type: str = "Real"
    display_unit: str | None = None
    depends: tuple[str, ...] = ()
    optional: str = ""
    choices: tuple[tuple[str, str], ...] = ()
    derivative_of: str = ""

    def __post_init__(self):
        if self.causality not in CAUSALITIES:
            raise ValueError(f"{self.name}: causality {self.causality!r} not in {CAUSALITIES}")
        if self.type not in TYPES:
            raise ValueError(f"{self.name}: type {self.type!r} not in {TYPES}")
        if self.unit not in UNITS:
            raise ValueError(
                f"{self.name}: unit {self.unit!r} is not in UNITS (components/variables.py): "
                "add it there with its SI base-unit exponents"
            )
        if self.depends and self.causality != "output":
            raise ValueError(f"{self.name}: only outputs have feedthrough dependencies")
        if not isinstance(self.optional, str):
            raise TypeError(
                f"{self.name}: optional= is the text saying what the default "
                f"means, got {self.optional!r}"
            )
        if self.optional and self.causality != "input":
            raise ValueError(f"{self.name}: only inputs can be optional")
        if self.type == "String" and (self.shape or self.causality != "parameter"):
            raise ValueError(f"{self.name}: String variables must be scalar parameters")
        if self.choices:
            self._check_choices()
        if self.derivative_of and (self.type != "Real" or self.causality == "parameter"):
            raise ValueError(f"{self.name}: only Real inputs and outputs can be derivatives")

    def _check_choices(self) -> None:
        names = [name for name, _ in self.choices]
        if self.type != "Integer" or self.shape or self.causality != "parameter":
            raise ValueError(f"{self.name}: only scalar Integer parameters have choices")
        if len(set(names)) < len(names) or not all(n.isidentifier() for n in names):
            raise ValueError(f"{self.name}: choice names must be distinct identifiers: {names}")
        if self.start not in range(len(names)):
            raise ValueError(f"{self.name}: start {self.start!r} is not a choice ({names})")

    def choice_value(self, value) -> int:
        """The value of a choice given by its name (any case) or its number; ValueError
        listing the choices for anything else (:func:`.runtime.choices.value`)."""
        return runtime_choices.value(self.name, [name for name, _ in self.choices], value)

    def choice_error(self, value) -> str:
        """'law must be one of 0 (PSEUDO_INVERSE), 1 (SR_INVERSE), got 2'."""
        return runtime_choices.error(self.name, [name for name, _ in self.choices], value)

    @property
    def required(self) -> bool:
        """An input a system must connect (or give a parameter value)."""
        return self.causality == "input" and not self.optional

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    def scalar_names(self) -> list[str]:
        """FMI names of the scalars of this variable, in row-major order."""
        if not self.shape:
            return [self.name]
        return [
            f"{self.name}[{','.join(str(i + 1) for i in idx)}]"
            for idx in itertools.product(*(range(n) for n in self.shape))
        ]

    def start_array(self) -> np.ndarray:
        """Start value as a flat float array of length ``size``."""
        value = np.broadcast_to(np.asarray(self.start, dtype=float), self.shape)
        return np.array(value, dtype=float).reshape(-1)


def _check_derivative(derivative: Var, base: Var | None) -> None:
    """``derivative`` is d/dt of ``base``: same causality and shape, unit per second."""
    per_second = {}
    if base is not None:
        per_second = dict(UNITS[base.unit][0])
        per_second["s"] = per_second.get("s", 0) - 1
    if (
        base is None
        or base.derivative_of
        or (base.causality, base.shape, base.type)
        != (derivative.causality, derivative.shape, "Real")
        or UNITS[derivative.unit][0] != {k: e for k, e in per_second.items() if e}
    ):
        raise ValueError(
            f"{derivative.name}: derivative_of={derivative.derivative_of!r} must name a Real "
            f"{derivative.causality} of shape {derivative.shape}, no derivative itself, whose "
            "unit per second is this one's"
        )


def parameter(name, start, unit, description, **kw) -> Var:
    return Var(name, "parameter", unit, description, start, **kw)


def choice(name, start: int, description, choices) -> Var:
    """A scalar Integer parameter whose values 0, 1, … are the named ``choices``
    ((NAME, meaning) pairs); the description lists them ("steering law: 0 = PSEUDO_INVERSE
    (pseudo-inverse with null motion), 1 = …"), so the model description, the docs and the
    command line (``--set CmgSteering.law=SR_INVERSE``) all read them from this one row."""
    named = tuple((str(name_), str(meaning)) for name_, meaning in choices)
    listed = f"{description}: {runtime_choices.listing(named)}"
    return Var(name, "parameter", "1", listed, start, type="Integer", choices=named)


def input_(name, unit, description, start=0.0, *, optional: str = "", **kw) -> Var:
    """An input; required unless ``optional`` says what its default (``start``) means."""
    if "required" in kw:
        raise TypeError(
            f"{name}: declare an optional input with optional='what its "
            "default means' (there is no required=)"
        )
    if not isinstance(optional, str) or (optional and not optional.strip()):
        raise ValueError(f"{name}: optional= must say what the default means")
    return Var(name, "input", unit, description, start, optional=optional.strip(), **kw)


def output(name, unit, description, depends=(), **kw) -> Var:
    return Var(name, "output", unit, description, None, depends=tuple(depends), **kw)


class Layout:
    """Offsets of a table's variables in the flat value array (offset = value reference).

    ``interpolated`` (a model that interpolates its inputs, ``Model.INTERPOLATES_INPUTS``):
    after the numeric variables the array holds, per input scalar (value reference order),
    the first time derivative a host set with ``fmi2SetRealInputDerivatives``
    (``derivative[name]``: offset of the derivative of input ``name``), then 1.0 where one
    was set, 0.0 where none was (``given[name]``).  No value reference reaches them: they
    are state (FMU states save them), read by the model where it integrates its inputs.
    ``step_end``: per Real input scalar, the offsets (value, derivative, given, rate, the
    rate's derivative, the rate's given) that bring it to the step's end
    (``Model.inputs_to_step_end``), those with a rate first; rate: the input declared its
    derivative (``hdot_cmg`` of ``h_cmg``), -1 (and -1, -1) if none.
    ``n_values`` is the array's length, ``n_numeric`` that of the variables alone."""

    def __init__(self, variables: tuple[Var, ...], interpolated: bool = False):
        names = [v.name for v in variables]
        duplicates = {n for n in names if names.count(n) > 1}
        if duplicates:
            raise ValueError(f"duplicate variable names {sorted(duplicates)}")
        inputs = {v.name for v in variables if v.causality == "input"}
        for v in variables:
            unknown = set(v.depends) - inputs
            if unknown:
                raise ValueError(f"{v.name}: depends on unknown inputs {sorted(unknown)}")
        by_name = {v.name: v for v in variables}
        for v in variables:
            if v.derivative_of:
                _check_derivative(v, by_name.get(v.derivative_of))
        numeric = [
            v for c in CAUSALITIES for v in variables if v.causality == c and v.type != "String"
        ]
        strings = [v for v in variables if v.type == "String"]
        self.variables = tuple(numeric + strings)
        self.by_name = {v.name: v for v in self.variables}
        self.offset: dict[str, int] = {}
        self._slices: dict[str, slice] = {}
        position = 0
        for v in numeric:
            self.offset[v.name] = position
            self._slices[v.name] = slice(position, position + v.size)
            position += v.size
        self.n_numeric = position
        #: contiguous value-reference range of each causality group
        self.range = {
            c: range(
                min([self.offset[v.name] for v in numeric if v.causality == c], default=0),
                max([self.offset[v.name] + v.size for v in numeric if v.causality == c], default=0),
            )
            for c in CAUSALITIES
        }
        input_range = self.range["input"]
        self.derivative: dict[str, int] = {}
        self.given: dict[str, int] = {}
        self.step_end: tuple[tuple[int, ...], ...] = ()
        if interpolated:
            for v in numeric:
                if v.causality == "input" and v.type == "Real":
                    at = self.offset[v.name] - input_range.start
                    self.derivative[v.name] = self.n_numeric + at
                    self.given[v.name] = self.n_numeric + len(input_range) + at
            rates = {
                v.derivative_of: v.name for v in numeric if v.derivative_of and v.name in self.given
            }
            rows = [
                (self.offset[name] + k, self.derivative[name] + k, self.given[name] + k)
                + (
                    (
                        self.offset[rates[name]] + k,
                        self.derivative[rates[name]] + k,
                        self.given[rates[name]] + k,
                    )
                    if name in rates
                    else (-1, -1, -1)
                )
                for name in self.derivative
                for k in range(by_name[name].size)
            ]
            self.step_end = tuple(sorted(rows, key=lambda row: row[3] < 0))
        self.n_values = self.n_numeric + (2 * len(input_range) if interpolated else 0)
        for v in strings:
            self.offset[v.name] = position
            position += 1
        self.n_total = position
        # per value reference: (variable, scalar name)
        self.scalars = [(v, s) for v in self.variables for s in v.scalar_names()]

    def start_values(self) -> np.ndarray:
        """A new value array at the variables' start values."""
        return self._start_values.copy()

    @functools.cached_property
    def _start_values(self) -> np.ndarray:
        # made once per layout (a model with many variables spent more on this than on
        # its initialisation, at every instantiation)
        values = np.zeros(self.n_values)
        for v in self.variables:
            if v.type != "String" and v.causality != "output":
                values[self.slice(v.name)] = v.start_array()
        return values

    def slice(self, name: str) -> slice:
        return self._slices[name]

    def group(self, causality: str) -> tuple[Var, ...]:
        return tuple(v for v in self.variables if v.causality == causality)


class Bus:
    """Attribute access to one causality group of a model's values.

    Array variables are numpy views into the flat value array: read ``u.w_BI_B`` and write
    ``y.h[:] = ...`` (rebinding an array attribute raises, so a write can never be lost).
    Scalars read and write through to the array and come back as float, int or bool.
    """

    def __init__(self, values: np.ndarray, layout: Layout, causality: str, strings: dict):
        object.__setattr__(self, "_values", values)
        object.__setattr__(self, "_strings", strings)
        scalars: dict[str, tuple[int | None, type]] = {}
        for v in layout.group(causality):
            if v.type == "String":
                scalars[v.name] = (None, str)
            elif v.shape:
                object.__setattr__(self, v.name, values[layout.slice(v.name)].reshape(v.shape))
            else:
                scalars[v.name] = (layout.offset[v.name], _PYTHON_TYPE[v.type])
        object.__setattr__(self, "_scalars", scalars)

    def __getattr__(self, name):
        try:
            offset, kind = self._scalars[name]
        except KeyError:
            raise AttributeError(name) from None
        if offset is None:
            return self._strings[name]
        return kind(self._values[offset])

    def __setattr__(self, name, value):
        if name not in self._scalars:
            raise AttributeError(f"{name} is an array or unknown: write into it with [:]")
        offset, kind = self._scalars[name]
        if offset is None:
            self._strings[name] = str(value)
        else:
            self._values[offset] = float(value)


_PYTHON_TYPE = {"Real": float, "Integer": int, "Boolean": bool}
