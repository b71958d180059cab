"""Units as people write them, and the one conversion the toolkit offers at its edges.

Inside, every value is SI in the unit strings of the model descriptions (``rad/s2``,
``N.m.s``, ``1``).  :func:`pretty` writes them for people (``rad/s²``, ``N·m·s``, no unit
for ``1``); :func:`to_degrees` gives the factor and unit of an angle-valued unit in degrees.
"""

from __future__ import annotations

import math

_SUPERSCRIPT = str.maketrans("23", "²³")
_PRETTY = {"deg": "°", "deg/s": "°/s", "deg/s2": "°/s²", "1": ""}
#: SI angle units and their degree counterparts
DEGREES = {"rad": "deg", "rad/s": "deg/s", "rad/s2": "deg/s2"}


def pretty(unit: str | None) -> str:
    """'rad/s2' -> 'rad/s²', 'N.m.s' -> 'N·m·s', 'kg.m2' -> 'kg·m²', '1' -> '', 'deg' -> '°'."""
    if not unit:
        return ""
    if unit in _PRETTY:
        return _PRETTY[unit]
    return unit.replace(".", "·").translate(_SUPERSCRIPT)


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
