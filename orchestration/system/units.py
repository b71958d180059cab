"""Units as people write them, and the conversions the toolkit offers at its edges.

Inside, every value is SI in the unit strings of the model descriptions (``rad/s2``,
``N.m.s``, ``1``).  :func:`pretty` writes them for people (``rad/s²``, ``N·m·s``, no unit
for ``1``); :func:`to_degrees` gives the factor and unit of an angle-valued unit in degrees.

Values with a unit (:class:`Quantity`, ``deg(120)``; text ``"120 deg"``, ``"0.5 °/s"``,
``"[0, 120, 0] deg"``) are converted to a variable's SI unit by :func:`to_si`: the same unit
as is, a unit of :data:`CONVERSIONS` whose SI unit is the variable's, or a display unit the
variable's model description defines for it (FMI 2.0 ``DisplayUnit``: shown value =
factor · value + offset).  Anything else is a unit mismatch, an error that says both units.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

_SUPERSCRIPT = str.maketrans("23", "²³")
_PRETTY = {"deg": "°", "deg/s": "°/s", "deg/s2": "°/s²", "1": ""}
#: SI angle units and their degree counterparts
DEGREES = {"rad": "deg", "rad/s": "deg/s", "rad/s2": "deg/s2"}
_DEG = math.pi / 180
#: units people write -> (the SI unit of the model descriptions, factor to it)
CONVERSIONS = {
    "deg": ("rad", _DEG),
    "arcmin": ("rad", _DEG / 60),
    "arcsec": ("rad", _DEG / 3600),
    "mrad": ("rad", 1e-3),
    "urad": ("rad", 1e-6),
    "deg/s": ("rad/s", _DEG),
    "deg/h": ("rad/s", _DEG / 3600),
    "arcsec/s": ("rad/s", _DEG / 3600),
    "rpm": ("rad/s", math.pi / 30),
    "deg/s2": ("rad/s2", _DEG),
    "km": ("m", 1e3),
    "km/s": ("m/s", 1e3),
    "ms": ("s", 1e-3),
    "min": ("s", 60.0),
    "h": ("s", 3600.0),
    "mN.m": ("N.m", 1e-3),
    "nT": ("T", 1e-9),
}
#: what a value in an SI unit is, for messages
_KINDS = {
    "rad": "an angle",
    "rad/s": "an angular rate",
    "rad/s2": "an angular acceleration",
    "m": "a length",
    "m/s": "a speed",
    "s": "a time",
    "N.m": "a torque",
    "N.m.s": "an angular momentum",
    "kg.m2": "an inertia",
    "1": "a number without unit",
}
_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_PLAIN = re.compile(rf"^\s*{_NUMBER}\s*$")
_WITH_UNIT = re.compile(rf"^\s*({_NUMBER}|\[.*\])\s*([A-Za-zµ°][A-Za-z0-9µ°/.·²³]*)\s*$", re.S)


def pretty(unit: str | None) -> str:
    """'rad/s2' -> 'rad/s²', 'N.m.s' -> 'N·m·s', 'kg.m2' -> 'kg·m²', '1' -> '', 'deg' -> '°'."""
    if not unit:
        return ""
    if unit in _PRETTY:
        return _PRETTY[unit]
    return unit.replace(".", "·").translate(_SUPERSCRIPT)


def join(number: str, unit: str) -> str:
    """A number and its unit as people write them: '0.5 rad/s', '0.006 °/s', '2.1°' (no
    space before a degree sign that stands alone, as before ′ and ″; ISO 80000-1), '0.57'
    (no unit).  ``unit`` as :func:`pretty` writes it."""
    if not unit:
        return number
    return number + ("" if unit in ("°", "′", "″") else " ") + unit


def label(name: str, unit: str | None) -> str:
    """An axis label: 'w_BI_B [rad/s]', or the name alone for a dimensionless value."""
    text = pretty(unit)
    return f"{name} [{text}]" if text else f"{name} [-]"


def to_degrees(unit: str | None) -> tuple[float, str | None]:
    """(factor, unit) that express a value of ``unit`` in degrees; (1, unit) for a unit
    that is not an angle."""
    if unit in DEGREES:
        return 180 / math.pi, DEGREES[unit]
    return 1.0, unit


#: {unit: {display unit: factor}} of the FMI display units (shown value = factor · value)
#: the model descriptions read in this process define (:func:`declare`)
DECLARED: dict[str, dict[str, float]] = {}


def declare(unit_definitions) -> None:
    """Take the display units of a model description's ``UnitDefinitions`` (fmpy's), for
    :func:`display_factor`: any FMU's, ours or not (one with an offset, which a factor
    cannot convert, is left out)."""
    for unit in unit_definitions or ():
        for display in unit.displayUnits:
            if not display.offset:
                DECLARED.setdefault(unit.name, {}).setdefault(display.name, display.factor)


def display_factor(unit: str | None, display_unit: str | None) -> float | None:
    """The factor that turns a value in ``unit`` (SI) into ``display_unit``: 1 for the
    same unit, a display unit's a model description defines (:data:`DECLARED`), 180/π from
    rad to deg (and their rates), 1/f for a unit of :data:`CONVERSIONS`; None when they do
    not convert."""
    if not display_unit or display_unit == unit:
        return 1.0
    if display_unit in DECLARED.get(unit or "", {}):
        return DECLARED[unit or ""][display_unit]
    if DEGREES.get(unit or "") == display_unit:
        return 180 / math.pi
    if display_unit in CONVERSIONS and CONVERSIONS[display_unit][0] == unit:
        return 1.0 / CONVERSIONS[display_unit][1]
    return None


def plain(unit: str) -> str:
    """A unit as people write it in the model descriptions' spelling: '°/s' -> 'deg/s',
    'N·m' -> 'N.m', 'rad/s²' -> 'rad/s2', 'µrad' -> 'urad'."""
    text = unit.strip().replace("·", ".").replace("²", "2").replace("³", "3").replace("µ", "u")
    return "deg" + text[1:] if text.startswith("°") else text


@dataclass(frozen=True)
class Quantity:
    """A value (a number or a nested list/array) in a unit: ``Quantity(120, "deg")``,
    ``Quantity([0, 0.5, 0], "deg/s")``.  :func:`to_si` converts it to a variable's unit."""

    value: Any
    unit: str

    def __post_init__(self):
        object.__setattr__(self, "unit", plain(self.unit))

    def __str__(self):
        return f"{self.value} {self.unit}"


def deg(value) -> Quantity:
    """A value in degrees (an angle, or with a unit like ``deg/s`` through :class:`Quantity`)."""
    return Quantity(value, "deg")


def arcsec(value) -> Quantity:
    """A value in arcseconds."""
    return Quantity(value, "arcsec")


def quantity(value) -> Quantity | None:
    """``value`` as a :class:`Quantity` if it has a unit (a Quantity, or text such as
    ``"120 deg"``, ``"0.8°/s"``, ``"[0, 120, 0] deg"``), else None."""
    if isinstance(value, Quantity):
        return value
    if not isinstance(value, str):
        return None
    match = _WITH_UNIT.match(value)
    if match is None or _PLAIN.match(value):  # "2e4" is a number, not 2 in a unit "e4"
        return None
    number, unit = match.groups()
    if number.startswith("["):
        import ast

        try:
            return Quantity(ast.literal_eval(number), unit)
        except (ValueError, SyntaxError):
            raise ValueError(
                f"cannot read {number!r} as an array: write it like [1, 2, 3]"
            ) from None
    return Quantity(float(number), unit)


def kind(unit: str | None) -> str:
    """'rad' -> "an angle [rad]", for messages."""
    return f"{_KINDS[unit]} [{unit}]" if unit in _KINDS else f"[{unit}]"


def to_si(value: Quantity, unit: str | None, display_units=()) -> Any:
    """The number(s) of ``value`` in ``unit`` (a variable's SI unit); ``display_units``:
    (name, factor, offset) of the unit's FMI display units.  A ValueError says both units
    when they do not convert."""
    import numpy as np

    number = value.value
    if value.unit == unit:
        return number
    if value.unit in CONVERSIONS and CONVERSIONS[value.unit][0] == unit:
        factor = CONVERSIONS[value.unit][1]
        scaled = np.asarray(number, dtype=float) * factor
        return float(scaled) if scaled.ndim == 0 else scaled.tolist()
    for name, factor, offset in display_units:
        if plain(name) == value.unit:
            array = (np.asarray(number, dtype=float) - offset) / factor
            return float(array) if array.ndim == 0 else array.tolist()
    known = [u for u, (si, _) in CONVERSIONS.items() if si == unit]
    known += [plain(name) for name, _, _ in display_units if plain(name) not in known]
    accepted = f"; it takes {', '.join([str(unit), *known])}" if unit else ""
    raise ValueError(
        f"unit mismatch: {value.value} {value.unit} is {kind(_si_of(value.unit))}, the variable "
        f"is {kind(unit) if unit else 'without a declared unit'}{accepted}"
    )


def is_unit(text: str, display_units=()) -> bool:
    """Does ``text`` name a unit the toolkit converts (an SI unit of a model description, a
    unit of :data:`CONVERSIONS`, one of the display units given)?"""
    return (
        text in CONVERSIONS
        or text in _KINDS
        or any(plain(name) == text for name, _, _ in display_units)
    )


def _si_of(unit: str) -> str:
    return CONVERSIONS[unit][0] if unit in CONVERSIONS else unit
