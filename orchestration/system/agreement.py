"""Parameters that describe one thing in two FMUs, and the check that they agree.

A CMG steering law computes gimbal rates for a cluster geometry: its ``h_rotor``,
``gimbal_axis`` and ``spin_ref`` must be the cluster's.  A controller's feedforward uses the
hub inertia: AttitudeController's ``inertia`` must be the satellite's (when its
``acceleration_feedforward`` is on), PitchManeuverController's ``inertia`` its pitch-axis
element.
Two instances are paired by the connection that makes them work together (the steering
reads the cluster's ``h``; the controller reads the satellite's rates).

The shipped scenarios give each such value once, one name of the scenario's module for both
FMUs (``H_ROTOR`` in :mod:`agilesat.orchestration.scenarios.scan_pitch`);
:func:`disagreements` checks any system against :data:`RULES` with the values the run will
use (bound in the system file, else the FMU's start value).  A value given at run time
(``--set``, a variant, a campaign's overrides) is a deliberate choice of the user and is not
checked (e.g. a robustness study of a controller that does not know the true inertia).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Rule:
    """``a.a_parameter`` == ``b.b_parameter`` (scalar names, ``[i,j]`` selecting elements),
    for every pair of instances of FMUs ``a``, ``b`` joined by ``link`` = (output of a,
    input of b); ``when``: only if b's Boolean parameter of that name is true."""

    a: str
    a_parameter: str
    b: str
    b_parameter: str
    link: tuple[str, str]
    when: str | None = None
    why: str = ""


RULES = (
    *(
        Rule(
            "CmgCluster",
            name,
            "CmgSteering",
            name,
            ("h[1]", "h[1]"),
            why="the steering law must be computed for the cluster it steers",
        )
        for name in ("h_rotor", "gimbal_axis", "spin_ref")
    ),
    Rule(
        "SatelliteDynamics",
        "inertia",
        "AttitudeController",
        "inertia",
        ("w_BI_B[1]", "w_BI_B[1]"),
        when="acceleration_feedforward",
        why="the acceleration feedforward J ẇ_ref + ω × J ω needs the hub inertia",
    ),
    Rule(
        "SatelliteDynamics",
        "inertia[2,2]",
        "PitchManeuverController",
        "inertia",
        ("w_BO_B[2]", "w_BO_B[2]"),
        why="the feedforward torque I θ̈ needs the pitch-axis inertia",
    ),
)


def disagreements(instances: dict, bindings: list, sources: dict) -> list[str]:
    """One message per rule broken: ``instances`` {name: its
    :class:`.description.Description`}, ``bindings`` the system's ParameterValues,
    ``sources`` {(B, input): (A, output)}."""
    bound = {(p.component, p.name): p for p in bindings}
    kind = {name: d.md.coSimulation.modelIdentifier for name, d in instances.items()}
    problems = []
    for rule in RULES:
        for (b, u), (a, y) in sources.items():
            if (kind[a], y, kind[b], u) != (rule.a, rule.link[0], rule.b, rule.link[1]):
                continue
            ours = _values(instances[a], rule.a_parameter, a, bound)
            theirs = _values(instances[b], rule.b_parameter, b, bound)
            switch = _values(instances[b], rule.when, b, bound) if rule.when else {"": 1.0}
            if ours is None or theirs is None or switch is None:  # set at run time: the
                continue  # user's choice
            if list(ours.values()) == list(theirs.values()) or not all(switch.values()):
                continue
            differ = [
                f"{a}.{x} = {ours[x]!r} vs {b}.{z} = {theirs[z]!r}"
                for x, z in zip(ours, theirs)
                if ours[x] != theirs[z]
            ]
            origin = next(
                (bound[(b, z)].origin for z in theirs if (b, z) in bound), f"{b}'s start values"
            )
            problems.append(
                f"{origin}: {b}.{rule.b_parameter} must equal "
                f"{a}.{rule.a_parameter} ({rule.why}): "
                + "; ".join(differ[:3])
                + (" ..." if len(differ) > 3 else "")
            )
    return problems


def _values(description, parameter: str, instance: str, bound: dict) -> dict | None:
    """{scalar name: value} of ``parameter`` (a variable or one element of it) as the run
    will use it; None if any scalar is set at run time."""
    names = [n for n in description.variables if n == parameter or n.startswith(parameter + "[")]
    values = {}
    for name in names:
        binding = bound.get((instance, name))
        if binding is not None and binding.origin.startswith("--set"):
            return None
        value = binding.value if binding is not None else description.variables[name].start
        values[name] = _number(value)
    return values


def _number(value) -> float:
    """A parameter value as a number (a start value from modelDescription.xml is text;
    Booleans "true"/"false" are 1/0)."""
    if isinstance(value, str):
        return {"true": 1.0, "false": 0.0}[value] if value in ("true", "false") else float(value)
    return float(value)
