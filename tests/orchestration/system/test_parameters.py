"""One typed parameter path (orchestration/system/parameters.py): a run's values are parsed
and typed once, in its plan; named choices come from the model description alone."""

from types import SimpleNamespace

import pytest

from agilesat.orchestration import runner
from agilesat.orchestration.scenarios import get
from agilesat.orchestration.system import parameters
from agilesat.orchestration.system.parameters import choice_names, typed_parameters
from agilesat.orchestration.system.ssp import SystemFileError


def integer_parameter(description: str):
    return SimpleNamespace(type="Integer", causality="parameter", description=description)


@pytest.mark.parametrize(
    "description, names",
    [
        ("mode: 0 = OFF (nothing), 1 = ON (all of it)", ("OFF", "ON")),
        ("law: 0 = A (x, y), 1 = B_2 (z), 2 = C (w)", ("A", "B_2", "C")),
        ("0 = OFF (nothing), 1 = ON (all of it)", ("OFF", "ON")),
        ("mode: 1 = OFF (nothing), 2 = ON (all of it)", None),  # not 0, 1, ...
        ("mode: 0 = OFF (nothing)", None),  # one value is no choice
        ("a count of 0 = none (empty), 1 = one (a single)", None),  # not "N = NAME ("
        ("number of wheels", None),
        ("", None),
    ],
)
def test_named_choices_are_read_from_the_variables_description(description, names):
    assert choice_names(integer_parameter(description)) == names


def test_one_parser_of_named_choices_for_the_tables_and_the_master():
    """What a variable table writes (components/variables.py ``choice``) the master reads
    back, and a value given to the model (``Var.choice_value``) and to a run (``--set``)
    is parsed by one function, with one message."""
    from agilesat.components.variables import choice

    law = choice("law", 0, "steering law", [("FIRST", "the first"), ("SECOND", "the 2nd")])
    read = SimpleNamespace(type="Integer", causality="parameter", description=law.description)
    names = choice_names(read)
    assert names == ("FIRST", "SECOND")
    for given in ("second", " 1 ", 1, "FIRST", 0):
        assert law.choice_value(given) == parameters.choice_value("law", names, given, "x")
    with pytest.raises(ValueError) as model:
        law.choice_value("THIRD")
    with pytest.raises(SystemFileError) as run:
        parameters.choice_value("law", names, "THIRD", "--set A.law=THIRD")
    assert str(run.value) == f"--set A.law=THIRD: {model.value}"
    assert str(model.value) == "law must be one of 0 (FIRST), 1 (SECOND), got 'THIRD'"


def test_only_integer_parameters_have_named_choices():
    text = "mode: 0 = OFF (nothing), 1 = ON (all of it)"
    real = SimpleNamespace(type="Real", causality="parameter", description=text)
    one_input = SimpleNamespace(type="Integer", causality="input", description=text)
    assert choice_names(real) is None and choice_names(one_input) is None


def test_any_fmu_that_lists_its_values_takes_their_names():
    """Nothing of our model registry is asked: an FMU of someone else's with a description
    in that form gets named choices, by name (any case) or number."""
    mode = SimpleNamespace(
        name="mode", unit=None, start="0", **vars(integer_parameter("0 = OFF (x), 1 = ON (y)"))
    )
    theirs = SimpleNamespace(variables={"mode": mode}, md=SimpleNamespace(modelVariables=[mode]))
    for text, value in (("on", 1), ("OFF", 0), ("1", 1), (1, 1)):
        [typed] = typed_parameters({"Other": theirs}, {"Other.mode": text}).values()
        assert (typed.type, typed.value) == ("Integer", value)
    with pytest.raises(SystemFileError, match=r"mode must be one of 0 \(OFF\), 1 \(ON\), got 'up'"):
        typed_parameters({"Other": theirs}, {"Other.mode": "up"})


def test_a_run_parses_and_types_each_value_once(fmus, tmp_path, monkeypatch):
    """``agilesat run --set`` / ``run(parameters=)``: each scalar is typed once, in the run's
    plan, and the plan carries the typed values to the master and into the summary."""
    typed, parsed, planned = [], [], []
    monkeypatch.setattr(
        parameters,
        "typed_value",
        lambda d, key, value, origin=None, real=parameters.typed_value: (
            typed.append(key) or real(d, key, value, origin)
        ),
    )
    monkeypatch.setattr(
        parameters,
        "parse_value",
        lambda text, real=parameters.parse_value: parsed.append(text) or real(text),
    )

    def execute(plan):
        planned.append(plan)
        raise ValueError("stopped before anything runs")

    monkeypatch.setattr(runner, "execute", execute)
    given = {"SatelliteDynamics.inertia": "[[900,0,0],[0,900,0],[0,0,900]]", "CmgSteering.law": "1"}
    with pytest.raises(ValueError, match="stopped before"):
        runner.run(get("scan_pitch").ssd, parameters=given, out_dir=tmp_path, figures=False)
    assert parsed == list(given.values())
    assert sorted(typed) == sorted(planned[0].overrides) and len(typed) == 10
    assert planned[0].overrides["SatelliteDynamics.inertia[1,1]"].value == 900.0
    assert planned[0].overrides["CmgSteering.law"].value == 1
    assert planned[0].bindings[-10:] == list(planned[0].overrides.values())


def test_a_value_is_said_with_its_parameter_where_it_was_given(fmus):
    """A mission's value is given at its file and line: the message names the parameter
    after it (it read 'mission.py:9=1 deg'), a Real with a unit that does not convert says
    both units (it said "'kg' is no unit"), '2e4' is a number (it read 2 in a unit 'e4')."""
    from agilesat.orchestration.system.description import Description
    from agilesat.orchestration.system.parameters import typed_value
    from agilesat.orchestration.system.units import quantity

    source = get("scan_pitch").system_file().component("SatelliteDynamics").source
    described = Description("SatelliteDynamics", source)
    at = "mission.py:9"
    cases = [
        (
            "gravity_gradient",
            "1 deg",
            "mission.py:9: SatelliteDynamics.gravity_gradient=1 deg: expected a Boolean",
        ),
        ("mu", "5 kg", "mission.py:9: SatelliteDynamics.mu=5 kg: expected a finite Real number"),
        ("mu", "0x10", "mission.py:9: SatelliteDynamics.mu=0x10: expected a finite Real number"),
        ("rate0[1]", "1 deg/h", None),
    ]
    for name, value, message in cases:
        if message is None:
            assert typed_value(described, f"SatelliteDynamics.{name}", value, at).value > 0
            continue
        with pytest.raises(SystemFileError) as error:
            typed_value(described, f"SatelliteDynamics.{name}", value, at)
        assert str(error.value).startswith(message) and "is no unit" not in str(error.value)
    with pytest.raises(SystemFileError, match=r"^--set SatelliteDynamics.mu=5 kg: .*\[kg\]"):
        typed_value(described, "SatelliteDynamics.mu", "5 kg")
    assert quantity("2e4") is None and quantity("1E-3") is None and quantity("2 km").unit == "km"
    assert typed_value(described, "SatelliteDynamics.mu", "2e4").value == 2e4


def test_two_aliases_given_two_values_are_refused():
    """Two variables of one FMU at one value reference and type are one variable (FMI 2.0
    section 2.2.7): two values for them are refused, naming both; one value is fine."""
    from agilesat.orchestration.system.ssp import ParameterValue
    from agilesat.orchestration.system.validation import _binding_problems

    def real(vr):
        return SimpleNamespace(
            type="Real", valueReference=vr, causality="parameter", variability="fixed"
        )

    instance = SimpleNamespace(
        name="G",
        path=SimpleNamespace(name="G.fmu"),
        variables={"a": real(0), "b": real(0), "c": real(1)},
    )
    given = [
        ParameterValue("G", "a", "Real", 1.0, "x.ssd:3"),
        ParameterValue("G", "b", "Real", 2.0, "--set G.b"),
    ]
    (problem,) = _binding_problems({"G": instance}, given)
    assert problem.startswith(
        "--set G.b and x.ssd:3: G.b=2.0 and a=1.0: the FMU has them as one variable "
        "(value reference 0"
    )
    same = [given[0], ParameterValue("G", "b", "Real", 1.0, "--set G.b")]
    assert _binding_problems({"G": instance}, same) == []
    later = [given[0], ParameterValue("G", "a", "Real", 2.0, "--set G.a"), given[1]]
    assert _binding_problems({"G": instance}, later) == []  # a set again, to b's value
