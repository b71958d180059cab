"""Parameter values given to a run (``--set``, ``parameters=``, a scenario's variant, a
campaign's draws), parsed and typed once, here: :func:`typed_parameters`.

Whole variables: FMI 2.0 knows only scalars; an array variable is the scalars
``inertia[1,1]`` … ``inertia[3,3]`` (1-based, row-major).  A value can be given

* for one element: ``SatelliteDynamics.inertia[2,2]=900``;
* for the whole array, with its shape: ``SatelliteDynamics.inertia=[[900,0,0],[0,900,0],
  [0,0,900]]``, ``SatelliteDynamics.rate0=[0,0.01,0]``.

A bare number for an array is refused, never broadcast: ``inertia=900`` could mean 900 on
every element or 900 times the identity, and an attitude engineer means the second as often
as the first.  The error says which elements there are and shows both forms.

Types: each scalar value takes the type of the FMU's variable, and must be one: a Real a
finite number (``"0.01"``, ``1``, ``1e-3``; not ``1_000``, ``inf`` or ``nan``), an Integer
whole digits within fmi2Integer's 32 bits, a Boolean ``true``, ``false``, ``1`` or ``0``
(any case); anything else is an error naming the parameter.  A Real also takes a value
with a unit that converts to its own (``"120 deg"``, ``deg(120)``, ``"[0, 120, 0] deg"``;
:mod:`.units`): a unit that does not convert is an error naming both.  Named choices: an
Integer parameter whose model-description ``description`` lists its values as ``0 = NAME
(meaning), 1 = NAME (meaning), …`` (as every choice of our variable tables says it,
``components/variables.py`` :func:`choice`) takes a name in any case, or the number:
``CmgSteering.law=SR_INVERSE``.
Only the model description is read: any FMU that lists its values so has named choices.
"""

from __future__ import annotations

import ast
import difflib
import math
import re
import threading
from dataclasses import dataclass

import numpy as np

from ...components.runtime import choices
from .ssp import INTEGER_RANGE, ParameterValue, SystemFileError
from .units import Quantity, is_unit, pretty, quantity, to_si

_ELEMENT = re.compile(r"^(.*)\[([0-9,]+)\]$")


@dataclass
class ArrayVariable:
    """One variable of an FMU, scalar (shape ()) or array, from its model description."""

    name: str
    shape: tuple[int, ...]
    scalars: list  # fmpy ScalarVariables, row-major

    @property
    def first(self):
        return self.scalars[0]

    def start(self):
        """The start value(s) as the model description gives them, shaped."""
        values = [_typed(v, v.start) for v in self.scalars]
        return (
            values[0]
            if not self.shape
            else np.array(values, dtype=object).reshape(self.shape).tolist()
        )


def variables(description) -> dict[str, ArrayVariable]:
    """The variables of an FMU by whole name, in model-description order; array elements
    grouped (shape from the largest index in each dimension)."""
    groups: dict[str, list] = {}
    for v in description.md.modelVariables:
        match = _ELEMENT.match(v.name)
        groups.setdefault(match.group(1) if match else v.name, []).append(v)
    result = {}
    for name, scalars in groups.items():
        if len(scalars) == 1 and scalars[0].name == name:
            result[name] = ArrayVariable(name, (), scalars)
            continue
        indices = [tuple(int(i) for i in _element(v.name).group(2).split(",")) for v in scalars]
        shape = tuple(max(column) for column in zip(*indices))
        order = sorted(range(len(scalars)), key=lambda k: indices[k])
        result[name] = ArrayVariable(name, shape, [scalars[k] for k in order])
    return result


#: content key of an FMU (:attr:`.description.Description.key`) -> its :func:`variables`,
#: read only here (a campaign's runs each type their values against the same tables)
_tables: dict[str, dict[str, ArrayVariable]] = {}
_TABLES_KEPT = 256
_tables_lock = threading.Lock()


def _table(description) -> dict[str, ArrayVariable]:
    """:func:`variables` of a description, made once per FMU content (not to be changed)."""
    key = getattr(description, "key", None)
    if key is None:
        return variables(description)
    with _tables_lock:
        table = _tables.get(key)
    if table is None:
        table = variables(description)
        with _tables_lock:
            if len(_tables) >= _TABLES_KEPT:
                _tables.pop(next(iter(_tables)))
            _tables[key] = table
    return table


def parse_value(text):
    """A command-line value: a bracketed list (``[[1,0],[0,1]]``) becomes nested lists, one
    with a unit (``[0, 120, 0] deg``) a :class:`.units.Quantity`; anything else stays text
    for the FMU's variable type to read (``120 deg`` included)."""
    if isinstance(text, str) and text.strip().startswith("["):
        try:
            with_unit = quantity(text)
        except ValueError as exc:
            raise SystemFileError(str(exc)) from None
        if with_unit is not None:
            return with_unit
        try:
            return ast.literal_eval(text.strip())
        except (ValueError, SyntaxError):
            raise SystemFileError(
                f"cannot read {text!r} as an array: write it like [1, 2, 3] or [[1, 0], [0, 1]]"
            ) from None
    return text


def typed_parameters(
    descriptions: dict, parameters: dict, origins: dict | None = None
) -> dict[str, ParameterValue]:
    """{"A.x": value} -> {"A.x" or "A.x[i,j]": ParameterValue}: each value parsed
    (:func:`parse_value`), whole arrays split into their elements, each element typed by
    the FMU's variable (:func:`typed_value`); unknown instances and variables answered
    with the closest names.  ``descriptions``: {instance: its
    :class:`.description.Description`}; ``origins``: {"A.x": where it was given}, for the
    messages and each value's ``origin`` (default ``--set A.x``)."""
    result, tables = {}, {}
    for key, value in parameters.items():
        at = (origins or {}).get(key) or f"--set {key}"
        name, _, variable = key.partition(".")
        if name not in descriptions or not variable:
            raise SystemFileError(
                f"{at}: expected Instance.variable with an instance "
                f"of {', '.join(descriptions)}" + did_you_mean(name, descriptions)
            )
        description = descriptions[name]
        table = tables.get(name) or tables.setdefault(name, _table(description))
        value = parse_value(value)
        if variable in description.variables:
            if np.ndim(_number(value)):
                raise SystemFileError(f"{at}: {name}.{variable} is a scalar, got an array {value}")
            result[key] = typed_value(description, key, value, at)
            continue
        base = variable.partition("[")[0]
        if base != variable and base in table:
            shape = table[base].shape
            raise SystemFileError(
                f"{at}: {name}.{variable}: index out of range "
                f"({'×'.join(map(str, shape)) or 'a scalar'}); the elements are "
                f"{table[base].first.name} .. {table[base].scalars[-1].name}"
            )
        if variable not in table:  # the closest parameters (else inputs): never outputs
            by = {c: [n for n, v in table.items() if v.first.causality == c] for c in SETTABLE}
            raise SystemFileError(
                f"{at}: {name} ({description.path.name}) has no variable {variable!r}"
                + (did_you_mean(variable, by["parameter"]) or did_you_mean(variable, by["input"]))
            )
        array = table[variable]
        if np.shape(_number(value)) != array.shape:
            raise SystemFileError(
                f"{at}: {name}.{variable} is an array of shape "
                f"{'×'.join(map(str, array.shape))} [{pretty(array.first.unit) or '1'}]; give it "
                f"whole, e.g. {variable}={_literal(array.start())}, or one element, e.g. "
                f"{array.first.name}={_typed(array.first, array.first.start)} (got "
                f"{value!r}; a single number is not spread over the elements)"
            )
        unit = value.unit if isinstance(value, Quantity) else None
        for scalar, element in zip(array.scalars, np.asarray(_number(value), dtype=object).ravel()):
            element_key = f"{name}.{scalar.name}"
            element = element if unit is None else Quantity(element, unit)
            origin = (origins or {}).get(key)  # else --set of the element
            result[element_key] = typed_value(description, element_key, element, origin)
    return result


def _number(value):
    """The number(s) of a value that may carry a unit (:func:`.units.quantity`)."""
    found = quantity(value)
    return value if found is None else found.value


def typed_value(description, key: str, value, origin: str | None = None) -> ParameterValue:
    """The value of the scalar variable ``key`` ("Instance.variable") of the FMU described
    by ``description``, in that variable's type; a named choice by its name or number; a
    Real with a unit converted to the variable's (:func:`.units.to_si`).  ``origin``: where
    it was given (default ``--set key``)."""
    origin = origin or f"--set {key}"
    name, _, variable = key.partition(".")
    declared = description.variables[variable]
    kind = declared.type
    names = choice_names(declared)
    with_unit = quantity(value) if kind == "Real" else None
    # "--set A.x=v", or where it was given and what: "mission.py:12: A.x=v"
    given = f"{origin}={value}" if origin == f"--set {key}" else f"{origin}: {key}={value}"
    if names is not None:
        value = choice_value(variable, names, value, given)
    elif with_unit is not None:
        display = _display_units(description, declared)
        try:
            value = float(to_si(with_unit, declared.unit, display))
        except ValueError as exc:
            said = str(exc)
            if not is_unit(with_unit.unit, display):  # 0x10, "5 apples"
                said = (
                    f"expected a finite Real number (like 0.01 or 1e-3), or one with a unit: {said}"
                )
            raise SystemFileError(f"{given}: {said}") from None
    elif kind in _READERS:
        if isinstance(value, Quantity):
            raise SystemFileError(f"{origin}: {name}.{variable} is an {kind}, not {value}")
        value = _READERS[kind](value, given)
    return ParameterValue(name, variable, kind, value, origin)


def _display_units(description, variable) -> list[tuple[str, float, float]]:
    """(name, factor, offset) of the display units the model description defines for the
    variable's unit."""
    for unit in getattr(description.md, "unitDefinitions", None) or ():
        if unit.name == variable.unit:
            return [(d.name, d.factor, d.offset) for d in unit.displayUnits]
    return []


#: a number as a user writes it: no "1_000" (Python's int() and float() take it), no
#: "inf" or "nan", no hexadecimal
_REAL = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
_INTEGER = re.compile(r"^[+-]?\d+$")
_BOOLEANS = {"true": True, "false": False, "1": True, "0": False}


def _real(value, where: str) -> float:
    text = str(value).strip()
    if isinstance(value, (int, float, np.number)) and not isinstance(value, (bool, np.bool_)):
        number = float(value)
    else:
        number = float(text) if _REAL.match(text) else math.nan
    if not math.isfinite(number):
        raise SystemFileError(f"{where}: expected a finite Real number, like 0.01 or 1e-3")
    return number


def _integer(value, where: str) -> int:
    text = str(value).strip()
    if isinstance(value, (float, np.floating)) and float(value).is_integer():
        text = str(int(value))
    if not _INTEGER.match(text) or not INTEGER_RANGE[0] <= int(text) <= INTEGER_RANGE[1]:
        raise SystemFileError(
            f"{where}: expected an Integer from {INTEGER_RANGE[0]} to {INTEGER_RANGE[1]} "
            "(fmi2Integer is 32 bits), written as digits"
        )
    return int(text)


def _boolean(value, where: str) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    text = str(value).strip().lower()
    if text not in _BOOLEANS:
        raise SystemFileError(f"{where}: expected a Boolean: true, false, 1 or 0")
    return _BOOLEANS[text]


_READERS = {"Real": _real, "Integer": _integer, "Boolean": _boolean}


def choice_names(variable) -> tuple[str, ...] | None:
    """The names of the values 0, 1, … of an Integer parameter whose model-description
    ``description`` lists them ("steering law: 0 = PSEUDO_INVERSE (pseudo-inverse with
    null motion), 1 = SR_INVERSE (…)", :mod:`agilesat.components.runtime.choices`), or
    None."""
    if variable.type != "Integer" or variable.causality != "parameter":
        return None
    return choices.names_in(variable.description)


def choice_value(variable: str, names, value, where: str) -> int:
    """The value of a choice given by its name (any case) or its number; a SystemFileError
    listing the choices for anything else."""
    try:
        return choices.value(variable, names, value)
    except ValueError as exc:
        raise SystemFileError(f"{where}: {exc}") from None


def _literal(array) -> str:
    return str(array).replace(" ", "")


#: the causalities of the variables a run is given values of: parameters, and inputs held
#: at a value (one FMU run alone)
SETTABLE = ("parameter", "input")


def did_you_mean(name: str, known) -> str:
    """'; did you mean X, Y?' for the names of ``known`` closest to ``name`` (or '')."""
    close = difflib.get_close_matches(name, list(known), n=3, cutoff=0.5)
    return f"; did you mean {', '.join(close)}?" if close else ""


def _typed(variable, text):
    """A model-description start value (text or number) in the variable's Python type."""
    if text is None:
        return None
    if variable.type == "Real":
        return float(text)
    if variable.type == "Integer":
        return int(text)
    if variable.type == "Boolean":
        return text in (True, 1, "true", "1") if not isinstance(text, bool) else text
    return str(text)


def _element(name: str) -> re.Match:
    """The match of a structured element name 'x[i,j]'."""
    match = _ELEMENT.match(name)
    if match is None:
        raise ValueError(f"{name!r} is not an array element name")
    return match
