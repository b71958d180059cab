"""The evaluation schedule: variable-level dependencies, not FMU-level ones."""

from types import SimpleNamespace

import pytest

from agilesat.orchestration.system.schedule import schedule
from agilesat.orchestration.system.ssp import SystemFileError


def fmu(outputs: dict):
    """A stand-in with the attributes the schedule reads: outputs -> inputs they depend on."""
    deps = {n: set(d) for n, d in outputs.items()}
    return SimpleNamespace(outputs=list(outputs), feedthrough=deps, initial_feedthrough=deps)


def test_mutually_dependent_fmus_without_an_algebraic_loop_are_read_twice():
    """Wheel momentum (a state) -> hub rate -> wheel momentum derivative (feedthrough)."""
    instances = {"wheel": fmu({"h": (), "hdot": ("w",)}), "hub": fmu({"w": ("h_wheel",)})}
    sources = {("hub", "h_wheel"): ("wheel", "h"), ("wheel", "w"): ("hub", "w")}
    plan = schedule(instances, sources, "feedthrough", "test.ssd")
    assert plan.blocks == [("wheel", ("h",)), ("hub", ("w",)), ("wheel", ("hdot",))]
    assert plan.step_order == ["wheel", "hub"]


def test_a_cycle_through_feedthrough_outputs_is_an_algebraic_loop():
    instances = {"a": fmu({"y": ("u",)}), "b": fmu({"z": ("v",)})}
    sources = {("a", "u"): ("b", "z"), ("b", "v"): ("a", "y")}
    with pytest.raises(
        SystemFileError,
        match=r"test.ssd: algebraic loop: .*a\.y depends on "
        r"input a\.u driven by b\.z",
    ):
        schedule(instances, sources, "feedthrough", "test.ssd")


def test_acyclic_fmus_are_read_once_in_dependency_order():
    instances = {"c": fmu({"y": ("u",)}), "a": fmu({"x": ()}), "b": fmu({"y": ("u",)})}
    sources = {("b", "u"): ("a", "x"), ("c", "u"): ("b", "y")}
    plan = schedule(instances, sources, "feedthrough", "test.ssd")
    assert plan.step_order == ["a", "b", "c"]
    assert [name for name, _ in plan.blocks] == ["a", "b", "c"]
