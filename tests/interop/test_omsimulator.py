"""Every shipped scenario, exported, in OpenModelica's OMSimulator (its command line:
``OMSimulator --stopTime=T --resultFile=R.csv PACKAGE.ssp``), as a user runs a package.

OMSimulator is on no package registry (it builds from source): give its executable in
``AGILESAT_OMSIMULATOR`` (components/runtime/switches.py); without it these tests are skipped, and
say so.  It is a host without Python: the FMUs start the Python they were built with.

- Each scenario runs to its end (exit 0, no error, the last row at the stop time), and the
  FMUs' warnings (payload_sweep's wheel torque limits) are in OMSimulator's log as warnings
  without stopping it: exported FMUs default ``warnings_return_ok`` to true, and the shim
  passes those warnings on as messages of status fmi2Warning from calls that return fmi2OK
  (OMSimulator stops on a call's fmi2Warning, and drops OK-level messages).
- OMSimulator's fixed-step master evaluates feedthrough in dependency order, as ours does:
  the attitude is ours to the digits its CSV prints.
- With ``--inputExtrapolation=true`` it steps every FMU twice per step: once to predict
  the inputs at t_{n+1}, then again from t_n with the inputs' slopes to those predictions
  as input derivatives (OMSimulator's SystemWC, "masiMax = 2").  Every scenario runs to its
  end without an error; the hub says once that the slope sent for ``h_cmg`` differs from
  the wired ``hdot_cmg`` and uses the slope.  The scheme interpolates the controllers'
  sampled commands too (a first-order hold where the flight computer holds them): the
  difference from our master is printed, and bounded by 1°.
"""

import csv
import subprocess

import numpy as np
import pytest

from agilesat.components.runtime.switches import value
from agilesat.orchestration.cosim.master import simulate
from agilesat.orchestration.scenarios import NAMES
from helpers import HOST_CASES, export_elsewhere

OMSIMULATOR = value("AGILESAT_OMSIMULATOR")
pytestmark = [
    pytest.mark.slow,
    pytest.mark.integration,
    pytest.mark.skipif(
        not OMSIMULATOR,
        reason="OMSimulator not given: set AGILESAT_OMSIMULATOR to its executable "
        "(OMSimulator builds from source; it is on no package registry)",
    ),
]


@pytest.fixture(scope="module")
def packages(fmus, tmp_path_factory):
    return export_elsewhere(tmp_path_factory)


def oms(package, stop, directory, *options):
    """(column names, rows after each step, log lines) of an OMSimulator run."""
    result = directory / "result.csv"
    run = subprocess.run(
        [OMSIMULATOR, f"--stopTime={stop}", f"--resultFile={result}", f"--tempDir={directory}"]
        + [*options, str(package)],
        capture_output=True,
        text=True,
        timeout=1800,
        cwd=directory,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    rows = list(csv.reader(result.open()))
    data = np.array(rows[1:], dtype=float)
    after = np.append(data[1:, 0] != data[:-1, 0], True)  # a row before and after each step
    log = (run.stdout + run.stderr).splitlines()
    return rows[0], data[after], log


def differences(scenario, package, names, data):
    stop, columns = HOST_CASES[scenario]
    ours = simulate(package, stop=stop)
    assert np.allclose(data[:, 0], ours.time, rtol=0, atol=1e-9)
    return [
        np.max(np.abs(data[:, names.index(f"{scenario}.{scenario}.{c}")] - ours[c]))
        for c in columns
    ]


@pytest.mark.parametrize("scenario", NAMES)
def test_each_scenario_runs_to_its_end_as_in_our_master(scenario, packages, tmp_path):
    stop, _ = HOST_CASES[scenario]
    names, data, log = oms(packages[scenario], stop, tmp_path)
    assert data[-1, 0] == pytest.approx(stop)
    assert not [line for line in log if line.startswith("error")]
    warnings = [line for line in log if line.startswith("warning: [fmi2Warning]")]
    if scenario == "payload_sweep":
        assert any("Flywheel" in w and "motor torque at the limit" in w for w in warnings)
    found = differences(scenario, packages[scenario], names, data)
    print(f"{scenario}: {len(warnings)} FMU warnings; max |OMSimulator - ours| {max(found):.3g}")
    assert max(found) < 1e-9


@pytest.mark.parametrize("scenario", NAMES)
def test_with_input_extrapolation_each_scenario_runs_to_its_end(scenario, packages, tmp_path):
    stop, _ = HOST_CASES[scenario]
    names, data, log = oms(packages[scenario], stop, tmp_path, "--inputExtrapolation=true")
    assert data[-1, 0] == pytest.approx(stop)
    assert not [line for line in log if line.startswith("error")]
    said = [line for line in log if "the derivative of h_cmg" in line]
    assert len(said) == (scenario != "payload_sweep")  # once, where there is a cluster
    found = differences(scenario, packages[scenario], names, data)
    print(f"{scenario} (--inputExtrapolation=true): max |OMSimulator - ours| {max(found):.3g}")
    assert max(found) < np.radians(1.0)
