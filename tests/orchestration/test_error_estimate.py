"""A run's own numerical error (orchestration/error_estimate.py, ``agilesat run
--error-estimate``): Richardson extrapolation with the observed order, against closed forms
and, for scan_pitch, against the error the run actually has (a run at a 32 times smaller
step as the truth)."""

import json
import math

import pytest

from agilesat.orchestration.error_estimate import estimate, lines, richardson
from helpers import agilesat


@pytest.mark.parametrize("order", [1.0, 2.0, 3.0])
def test_richardson_finds_the_error_and_order_of_a_power_law(order):
    m = lambda h: 1.5 + 0.3 * h**order  # noqa: E731 - the value at step h, exact 1.5
    error, found, observed = richardson(m(0.1), m(0.05), m(0.025))
    assert observed and found == pytest.approx(order)
    assert error == pytest.approx(m(0.1) - 1.5, rel=1e-9)


def test_an_order_it_cannot_observe_is_assumed_first_and_said():
    assert richardson(2.0, 2.0, 2.0) == (0.0, math.inf, True)  # converged to its digits
    error, order, observed = richardson(1.0, 1.1, 1.0)  # the finer difference not smaller
    assert (order, observed) == (1.0, False) and error == pytest.approx(-0.2)


def _summary(step, value):
    entry = {"value": value, "unit": "rad", "display_unit": "deg", "requirement": {"max": 0.5}}
    return {"settings": {"step": step}, "metrics": {"pointing": entry}}


def test_a_requirement_whose_margin_is_within_the_error_is_said_undecided():
    runs = {0.05: 0.499, 0.025: 0.459, 0.0125: 0.449}  # second order: error 0.0533
    found = estimate(_summary(0.05, runs[0.05]), lambda h: _summary(h, runs[h]))
    assert found["requirements"]["pointing"]["decided"] is False
    assert found["metrics"]["pointing"]["order"] == pytest.approx(2.0)
    assert any("does not decide it" in line for line in lines(found))
    far = estimate(_summary(0.05, 0.3), lambda h: _summary(h, 0.3 - (0.05 - h) / 100))
    assert far["requirements"]["pointing"]["decided"] is True


@pytest.mark.slow
@pytest.mark.integration
def test_scan_pitchs_estimate_is_its_error(fmus, tmp_path):
    """pitch at T = 100 s: the estimate at 0.05 s against the run's distance from a run at
    0.05 / 16 s (itself within 2 % of it at the observed order 1.5): within 20 %."""
    common = ("--stop", 100, "--no-figures", "--no-report")
    run = agilesat("run", "scan_pitch", "--error-estimate", *common, "--out", tmp_path / "a")
    assert run.returncode == 0, run.stderr
    assert "numerical error (Richardson over the steps 0.05, 0.025, 0.0125 s):" in run.stdout
    found = json.loads((tmp_path / "a" / "summary.json").read_text())["numerical_error"]
    fine = agilesat("run", "scan_pitch", "--step", 0.05 / 16, *common, "--out", tmp_path / "f")
    assert fine.returncode == 0, fine.stderr
    truth = json.loads((tmp_path / "f" / "summary.json").read_text())["metrics"]["pitch_at_T"]
    pitch = found["metrics"]["pitch_at_T"]
    actual = pitch["values"][0] - truth["value"]
    estimated = math.degrees(pitch["estimate"])
    print(f"pitch_at_T: estimate {estimated:.4g}°, actual {math.degrees(actual):.4g}°")
    assert pitch["estimate"] == pytest.approx(actual, rel=0.2)
