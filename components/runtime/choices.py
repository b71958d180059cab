"""Named choices: an Integer parameter whose values 0, 1, … have names.

One text format and one parser for the physics and the master: a variable table lists the
names in the variable's description (:func:`listing`, which ``components/variables.py``'s
``choice`` writes into the model description), the master reads them back from any FMU's
model description (:func:`names_in`), and a value is given by its name, in any case, or by
its number (:func:`value`), as ``Model.set`` and ``--set CmgSteering.law=SR_INVERSE`` take
it.
"""

from __future__ import annotations

import re

#: one value of a named choice in a description: "0 = PSEUDO_INVERSE (", "1 = SR_INVERSE ("
_CHOICE = re.compile(r"(?:^|[:,] )(\d+) = ([A-Za-z_][A-Za-z0-9_]*) \(")


def listing(choices) -> str:
    """'0 = NAME (meaning), 1 = NAME (meaning), …' of ``choices``, (NAME, meaning) pairs."""
    return ", ".join(f"{i} = {name} ({meaning})" for i, (name, meaning) in enumerate(choices))


def names_in(description: str | None) -> tuple[str, ...] | None:
    """The names of the values 0, 1, … a description lists (:func:`listing`; at least
    two, numbered from 0 in order), or None."""
    found = _CHOICE.findall(description or "")
    if len(found) < 2 or [int(number) for number, _ in found] != list(range(len(found))):
        return None
    return tuple(name for _, name in found)


def value(variable: str, names, given) -> int:
    """The value of a choice of ``variable`` given by its name (any case) or its number; a
    ValueError listing the choices for anything else."""
    text = str(given).strip()
    if text.upper() in names:
        return list(names).index(text.upper())
    number = given if isinstance(given, int) and not isinstance(given, bool) else None
    if number is None and text.isdigit():
        number = int(text)
    if number is None or number not in range(len(names)):
        raise ValueError(error(variable, names, given))
    return number


def error(variable: str, names, given) -> str:
    """'law must be one of 0 (PSEUDO_INVERSE), 1 (SR_INVERSE), got 2'."""
    listed = ", ".join(f"{i} ({name})" for i, name in enumerate(names))
    return f"{variable} must be one of {listed}, got {given!r}"
