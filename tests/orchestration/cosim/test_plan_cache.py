"""What a run plan keeps between runs of one process (``cosim/plan.py``: the system's
check; ``cosim/master.py``: the parameter values set one call per instance and type): a
change to anything the check reads is checked again, and the values the FMUs get are the
ones set last.  Plans only, no FMU loaded (about 0.3 s)."""

import dataclasses
import shutil

import pytest

from agilesat.orchestration.cosim import master
from agilesat.orchestration.cosim.plan import plan_run
from agilesat.orchestration.system.ssp import ParameterValue, SystemFileError, read_system
from helpers import ROOT

SYSTEM = ROOT / "orchestration" / "systems" / "scan_pitch.ssd"


def test_a_kept_check_is_made_again_when_the_system_changes_in_place(fmus):
    """The same SystemFile object, planned, then given a value for a variable its FMU does
    not have: the check finds it (the kept one is keyed by the system's content, not the
    object), and goes on finding it."""
    system = read_system(SYSTEM)
    plan_run(system, stop=1.0)
    plan_run(system, stop=1.0)
    name = system.components[0].name
    system.parameters.append(ParameterValue(name, "no_such_variable", "Real", 1.0, "test:1"))
    for _ in range(2):
        with pytest.raises(SystemFileError, match="no_such_variable"):
            plan_run(system, stop=1.0)
    system.parameters.pop()
    plan_run(system, stop=1.0)


def test_a_kept_check_is_made_again_when_an_fmu_file_changes_behind_its_path(fmus, tmp_path):
    """A component's FMU copied aside, planned, then replaced by another FMU at the same
    path: the check reads the new file (keyed by its SHA-256) and finds its variables
    missing."""
    system = read_system(SYSTEM)
    ref = next(c for c in system.components if c.name == "PitchManeuverController")
    copy = tmp_path / "controller.fmu"
    shutil.copyfile(ref.source, copy)
    ref.source = copy
    plan_run(system, stop=1.0)
    shutil.copyfile(fmus["OrbitEnvironment"], copy)
    with pytest.raises(SystemFileError, match="PitchManeuverController"):
        plan_run(system, stop=1.0)


def test_plans_of_one_check_share_no_container():
    """Two plans of the same system: a run's results hold the plan's lists (the order, the
    open inputs), so changing one plan's leaves the other's as checked."""
    system = read_system(SYSTEM)
    first, second = plan_run(system, stop=1.0), plan_run(system, stop=1.0)
    assert first.wiring == second.wiring
    first.wiring.steps.step_order.reverse()
    first.wiring.open_inputs.append({"input": "X.u"})
    first.wiring.sources.clear()
    assert plan_run(system, stop=1.0).wiring == second.wiring != first.wiring


@dataclasses.dataclass
class _Variable:
    valueReference: int


class _Instance:
    def __init__(self, references: dict):
        self.variables = {name: _Variable(vr) for name, vr in references.items()}


def test_parameter_values_are_set_once_per_instance_and_type_the_last_bound_winning():
    """The system's values then the overrides, grouped: one set per instance and type, each
    value reference once, with the value bound last (what setting them one by one in order
    leaves in the FMU)."""
    instances = {"A": _Instance({"x": 3, "y": 1, "n": 7}), "B": _Instance({"x": 0})}
    bindings = [
        ParameterValue("A", "x", "Real", 1.0, "system"),
        ParameterValue("B", "x", "Real", 5.0, "system"),
        ParameterValue("A", "n", "Integer", 2, "system"),
        ParameterValue("A", "y", "Real", -0.0, "system"),
        ParameterValue("A", "x", "Real", 4.0, "--set A.x"),
    ]
    calls = master._binding_calls(bindings, instances)
    name = {id(v): k for k, v in instances.items()}
    made = [(name[id(i)], t, vrs, vs) for i, t, vrs, vs in calls]
    assert made == [
        ("A", "Real", [1, 3], [-0.0, 4.0]),
        ("B", "Real", [0], [5.0]),
        ("A", "Integer", [7], [2]),
    ]
