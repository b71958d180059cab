"""The shipped assertions (agilesat.orchestration.postprocess.checks), the progress reporter and the
unit spelling, on synthetic data: each check passes where it should and fails with a
message that says where."""

import math

import numpy as np
import pytest

from agilesat.orchestration.output.progress import Progress
from agilesat.orchestration.output.results import Results
from agilesat.orchestration.postprocess.checks import (
    assert_momentum_conserved,
    assert_requirements_met,
    assert_settles,
    assert_within,
    requirement_met,
)
from agilesat.orchestration.system.units import pretty
from helpers import Stream


@pytest.fixture
def decaying():
    """An error 1 rad · e^(−t/10) on three axes and a conserved momentum, t = 0 … 100 s."""
    t = np.linspace(0, 100, 1001)
    e = np.exp(-t / 10)
    H = np.column_stack([np.full_like(t, 3.0), np.full_like(t, 4.0), 1e-12 * t])
    names = ["time", "C.err[1]", "C.err[2]", "C.err[3]", "S.H_I[1]", "S.H_I[2]", "S.H_I[3]"]
    units = {n: "rad" for n in names[1:4]} | {n: "N.m.s" for n in names[4:]}
    return Results(names, np.column_stack([t, e, -e, 0.5 * e, H]), {"units": units})


def test_settles_after_the_settling_time(decaying):
    assert_settles(decaying, "C.err", bound=math.exp(-5), after=50.0)
    with pytest.raises(
        AssertionError,
        match=r"C\.err does not settle within ±0\.001 rad "
        r"after t = 50 s: max 0\.006.* last outside at t = 69 s",
    ):
        assert_settles(decaying, "C.err", bound=1e-3, after=50.0)


def test_settles_in_degrees(decaying):
    assert_settles(decaying, "C.err[1]", bound=0.4, after=50.0, deg=True)  # 0.386°
    with pytest.raises(AssertionError, match="°"):
        assert_settles(decaying, "C.err[1]", bound=0.38, after=50.0, deg=True)


def test_within_a_band_over_a_window(decaying):
    assert_within(decaying, "C.err[1]", 0.0, 1.0)
    assert_within(decaying, "C.err[2]", -0.5, 0.0, start=10.0)
    with pytest.raises(AssertionError, match=r"below -0\.5 rad .* first at t = 0 s"):
        assert_within(decaying, "C.err[2]", -0.5, 0.0)
    with pytest.raises(AssertionError, match="no communication point"):
        assert_within(decaying, "C.err", start=200.0)


def test_momentum_conserved(decaying):
    assert_momentum_conserved(decaying, rtol=1e-10, name="S.H_I")  # 1e-10 / 5 drift
    with pytest.raises(AssertionError, match=r"drifts by 2e-11 .* t = 100 s"):
        assert_momentum_conserved(decaying, rtol=1e-11, name="S.H_I")


def test_requirements_from_the_summary():
    summary = {
        "metrics": {
            "a": {"value": 0.5, "unit": "rad", "requirement": 1.0},
            "b": {"value": -0.81, "unit": "rad/s", "requirement": [-0.82, -0.78]},
            "c": {"value": 2.0, "unit": "1", "requirement": {"max": 1.0}},
            "d": {"value": 9.0, "unit": "1", "requirement": 1.0, "met": True},  # the flag wins
            "e": {"value": 9.0, "unit": "1"},
        }
    }
    assert [requirement_met(summary["metrics"][k]) for k in "abcd"] == [True, True, False, True]
    assert_requirements_met(summary, "a", "b", "d")
    with pytest.raises(AssertionError, match=r"requirement not met: c = 2\.0 1"):
        assert_requirements_met(summary)
    with pytest.raises(AssertionError, match="no metric"):
        assert_requirements_met(summary, "f")


def test_progress_plain_lines_without_a_terminal_bar_in_one_nothing_when_quiet():
    plain = Stream(False)
    with Progress("run", stream=plain, interval=0.0) as progress:
        progress(50, 100)
    assert plain.getvalue().startswith("run: 50/100 steps (50 %)")
    tty = Stream(True)
    with Progress("run", stream=tty) as progress:
        progress(50, 100)
    assert "run:" in tty.getvalue() and "|" in tty.getvalue()  # tqdm's bar
    quiet = Stream(True)
    with Progress("run", stream=quiet, quiet=True, interval=0.0) as progress:
        progress(50, 100)
    assert quiet.getvalue() == ""


@pytest.mark.parametrize(
    "unit, text",
    [
        ("rad/s2", "rad/s²"),
        ("N.m.s", "N·m·s"),
        ("kg.m2", "kg·m²"),
        ("1", ""),
        ("deg/s", "°/s"),
        ("m3/s2", "m³/s²"),
        ("rad", "rad"),
    ],
)
def test_units_as_people_write_them(unit, text):
    assert pretty(unit) == text
