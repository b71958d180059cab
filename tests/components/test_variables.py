"""The variable-table machinery every model and FMU is built on."""

import numpy as np
import pytest

from agilesat.components.model import Model
from agilesat.components.variables import Bus, Layout, Var, choice, input_, output, parameter


class Toy(Model):
    VARIABLES = (
        parameter("gain", 2.0, "1", "gain"),
        parameter("inertia", np.eye(2), "kg.m2", "inertia", shape=(2, 2)),
        parameter("enabled", True, "1", "switch", type="Boolean"),
        parameter("label", "x", "1", "a name", type="String"),
        input_("u", "N.m", "input vector", shape=(3,)),
        output("y", "N.m", "output vector", shape=(3,), depends=("u",)),
        output("count", "1", "steps", type="Integer"),
    )

    def initialize(self, t0):
        self.t, self.steps = t0, 0

    def step(self, t, dt):
        self.steps += 1
        self.t = t + dt

    def output(self):
        self.y.y[:] = self.p.gain * self.u.u
        self.y.count = self.steps


def test_structured_names_are_one_based_row_major():
    assert Var("m", "parameter", "1", "d", shape=(2, 3)).scalar_names()[:4] == [
        "m[1,1]",
        "m[1,2]",
        "m[1,3]",
        "m[2,1]",
    ]


def test_value_references_group_parameters_inputs_outputs():
    layout = Layout(Toy.VARIABLES)  # its table + the common warnings_return_ok
    assert layout.range == {
        "parameter": range(0, 7),
        "input": range(7, 10),
        "output": range(10, 14),
    }
    assert [name for _, name in layout.scalars][-1] == "label"  # strings after numerics


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(name="a", causality="state", unit="1", description=""), "causality"),
        (
            dict(name="a", causality="input", unit="1", description="", depends=("b",)),
            "only outputs",
        ),
        (
            dict(name="a", causality="output", unit="1", description="", optional="zero"),
            "only inputs",
        ),
        (dict(name="a", causality="input", unit="1", description="", type="String"), "String"),
        (dict(name="a", causality="input", unit="furlong", description=""), "not in UNITS"),
    ],
)
def test_bad_rows_are_rejected(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Var(**kwargs)


def test_dependencies_must_name_inputs():
    with pytest.raises(ValueError, match="unknown inputs"):
        Layout((output("y", "1", "", depends=("nope",)),))


def test_duplicate_names_are_rejected():
    with pytest.raises(ValueError, match="duplicate"):
        Layout((parameter("a", 1.0, "1", ""), parameter("a", 2.0, "1", "")))


def test_buses_are_views_of_the_value_array():
    m = Toy(gain=3.0)
    m.set("u", [1.0, 2.0, 3.0])
    m.start()
    assert m.get("y").tolist() == [3.0, 6.0, 9.0]
    assert m.values[m.layout.slice("y")].tolist() == [3.0, 6.0, 9.0]
    assert m.p.enabled is True and m.p.label == "x" and isinstance(m.y.count, int)


def test_rebinding_an_array_signal_is_an_error_not_a_silent_loss():
    m = Toy().start()
    with pytest.raises(AttributeError, match=r"\[:\]"):
        m.y.y = np.ones(3)


def test_set_rejects_outputs_and_wrong_shapes():
    m = Toy()
    with pytest.raises(KeyError, match="output"):
        m.set("y", [1, 2, 3])
    with pytest.raises(ValueError, match="shape"):
        m.set("u", [1, 2])


def test_state_roundtrip_is_a_deep_copy():
    m = Toy().start()
    m.advance(0.0, 1.0)
    saved = m.get_state()
    m.advance(1.0, 1.0)
    m.set("u", [5.0, 5.0, 5.0])
    m.set_state(saved)
    m.output()
    assert m.steps == 1 and m.t == 1.0 and m.get("y").tolist() == [0.0, 0.0, 0.0]
    m.advance(1.0, 1.0)
    assert saved[2]["steps"] == 1  # the saved copy is untouched


def test_bus_reads_scalars_with_their_type():
    layout = Layout(Toy.VARIABLES)
    values = layout.start_values()
    bus = Bus(values, layout, "parameter", {"label": "z"})
    assert bus.gain == 2.0 and bus.label == "z" and bus.inertia.shape == (2, 2)


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        (dict(required=False), TypeError, "optional='what its default means'"),
        (dict(optional="  "), ValueError, "must say what the default means"),
        (dict(optional=True), ValueError, "must say what the default means"),
    ],
)
def test_an_optional_input_must_say_what_its_default_means(kwargs, error, message):
    with pytest.raises(error, match=message):
        input_("u", "N.m", "torque", **kwargs)


def test_inputs_are_required_unless_declared_optional():
    assert input_("u", "N.m", "torque").required
    optional = input_("u", "N.m", "torque", optional="zero: no torque")
    assert not optional.required and optional.optional == "zero: no torque"
    assert not parameter("p", 1.0, "1", "gain").required


def test_every_shipped_input_is_required_or_says_what_its_default_means():
    from agilesat.fmus import FMUS, model_class

    for name in FMUS:
        for v in model_class(name).VARIABLES:
            if v.causality == "input":
                assert v.required or len(v.optional) > 5, (name, v.name)


LAWS = (("FIRST", "the first way"), ("SECOND", "the second way"))


def test_a_named_choice_lists_its_names_in_the_description_and_reads_a_name_or_number():
    law = choice("law", 0, "the way", LAWS)
    assert (law.type, law.causality, law.unit) == ("Integer", "parameter", "1")
    assert law.description == "the way: 0 = FIRST (the first way), 1 = SECOND (the second way)"
    assert [law.choice_value(v) for v in ("SECOND", "second", " 1 ", 0, "0")] == [1, 1, 1, 0, 0]
    for bad in ("THIRD", 2, "-1", "1.0", True):
        with pytest.raises(ValueError, match=r"law must be one of 0 \(FIRST\), 1 \(SECOND\), got"):
            law.choice_value(bad)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(start=2), "start 2 is not a choice"),
        (dict(choices=(("A", ""), ("A", ""))), "distinct identifiers"),
        (dict(choices=(("not a name", ""),)), "distinct identifiers"),
        (dict(type="Real"), "only scalar Integer parameters"),
        (dict(shape=(2,)), "only scalar Integer parameters"),
    ],
)
def test_bad_choices_are_rejected(kwargs, message):
    row = dict(name="law", causality="parameter", unit="1", description="", start=0, type="Integer")
    with pytest.raises(ValueError, match=message):
        Var(**{**row, "choices": LAWS, **kwargs})


def test_a_model_takes_a_choice_by_name_and_checks_a_number_at_initialize():
    from agilesat.components.cmg_steering import SR_INVERSE, CmgSteering

    assert CmgSteering(law="sr_inverse").p.law == SR_INVERSE
    with pytest.raises(ValueError, match=r"law must be one of .*got 'SR'"):
        CmgSteering(law="SR")
