"""Every shipped scenario, exported as an SSP package, runs unchanged in ECOS (Vico's
co-simulation engine, through ``ecospy``) and agrees with our master to the coupling error
of ECOS's fixed-step algorithm; each run in a fresh process.

ECOS applies, at init, only the one parameter set it is given by name (an unknown name is
accepted silently and nothing is applied); our exports give every component's set the
system's name, which is what ``tests/tools/ecos_run.py`` passes, and configure each FMU
with its values as its own defaults, so that ECOS given no name (its default) runs the
same system, bit for bit.  Like libcosim (see
test_libcosim.py), ECOS steps every FMU from the inputs of the last communication point,
so the runs differ from our Gauss-Seidel master by an error of order H: halving H must
shrink the difference about as fast as first order.

ECOS needs Intel TBB at run time: ``apt-get install -y libtbb12`` (Debian/Ubuntu).
"""

import ctypes.util
import math
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from agilesat.orchestration.cosim.master import simulate
from agilesat.orchestration.output.results import Results
from agilesat.orchestration.scenarios import NAMES, get
from helpers import HOST_CASES, TOOLS, agilesat, export_elsewhere

pytestmark = [pytest.mark.slow, pytest.mark.integration]


@pytest.fixture(scope="module")
def packages(fmus, tmp_path_factory):
    """Each scenario exported, then moved out of the repository."""
    if ctypes.util.find_library("tbb") is None:
        pytest.fail("ECOS (ecospy) needs the TBB runtime library: apt-get install -y libtbb12")
    return export_elsewhere(tmp_path_factory)


def ecos(package, stop, step, parameter_set, columns, out):
    run = subprocess.run(
        [
            sys.executable,
            str(TOOLS / "ecos_run.py"),
            str(package),
            str(stop),
            str(step),
            parameter_set,
            str(out),
            *columns,
        ],
        capture_output=True,
        text=True,
        timeout=900,
        cwd=out.parent,
    )
    assert run.returncode == 0, run.stderr
    return Results.from_npz(out)


def ours(package, stop, step, out_dir):
    run = agilesat(
        "run",
        package,
        "--stop",
        stop,
        "--step",
        step,
        "--out",
        out_dir,
        "--no-figures",
        "--no-report",
        cwd=out_dir.parent,
    )
    assert run.returncode == 0, run.stderr
    return Results.from_npz(out_dir / "results.npz")


def test_every_shipped_scenario_is_covered():
    assert set(HOST_CASES) == set(NAMES)


@pytest.mark.parametrize("scenario", NAMES)
def test_ecos_agrees_with_our_master_to_the_coupling_error(scenario, packages, tmp_path):
    stop, columns = HOST_CASES[scenario]
    step = get(scenario).step
    differences = []
    for h in (step, step / 2):
        theirs = ecos(packages[scenario], stop, h, scenario, columns, tmp_path / f"ecos_{h}.npz")
        mine = ours(packages[scenario], stop, h, tmp_path / f"ours_{h}")
        assert len(theirs.time) == round(stop / h)
        assert np.allclose(theirs.time, mine.time[1:], rtol=0, atol=1e-9)  # after steps
        differences.append([np.max(np.abs(theirs[c] - mine[c][1:])) for c in columns])
    coarse, fine = np.array(differences)
    for column, c, f in zip(columns, coarse, fine):
        print(f"{scenario}: max |ECOS - ours| of {column}: {c:.3g} at H = {step} s, {f:.3g} at H/2")
    # the host's two extra steps of command delay (controller -> steering -> cluster) hold
    # scan_pitch's 4 N·m torque switches 2 H too long, open loop for the 60 s imaging
    # phase: 2 H · 4 / 956 · 60 = 1.4° at H = 0.05 s, the largest of the scenarios
    assert np.all(coarse < np.radians(2.0))
    assert np.all(fine <= 0.65 * coarse), fine / coarse  # first order, with 30 % margin


@pytest.mark.parametrize("scenario", NAMES)
def test_without_a_parameter_set_name_ecos_runs_the_named_run_exactly(scenario, packages, tmp_path):
    """ECOS given no set name (or a wrong one) applies no parameter set: the exported FMUs'
    own defaults are the scenario's values, so the run is the named one, bit for bit (before
    they were, scan_pitch started at pitch 0, not 120°)."""
    _, columns = HOST_CASES[scenario]
    step, stop = get(scenario).step, 20.0
    named = ecos(packages[scenario], stop, step, scenario, columns, tmp_path / "named.npz")
    nameless = ecos(packages[scenario], stop, step, "-", columns, tmp_path / "nameless.npz")
    wrong = ecos(packages[scenario], stop, step, "nope", columns, tmp_path / "wrong.npz")
    assert named.data.tobytes() == nameless.data.tobytes() == wrong.data.tobytes()
    if scenario == "scan_pitch":
        pitch = "SatelliteDynamics.euler_BO[2]"
        assert math.degrees(nameless[pitch][0]) == pytest.approx(120.0, abs=0.1)


def test_two_components_of_one_fmu_file(fmus, tmp_path):
    """ECOS's loader closes and reopens an FMU's binary per instance, the first instance
    alive: the shim is NODELETE, so both hubs of one FMU file run as in our master (an
    unloaded shim forgot the first: its pitch read 0)."""
    from agilesat.orchestration.mission import System

    rate = [0.01, -0.02, 0.03]  # the same values: one configured FMU file
    hubs = System("two_hubs", stop=2.0, step=0.05, algorithm="jacobi")
    hubs.add("A", "SatelliteDynamics", rate0=rate)
    hubs.add("B", "SatelliteDynamics", rate0=rate)
    hubs.connect("A.H_I", "B.h_wheel")
    system = hubs.write(tmp_path / "two_hubs.ssp")
    with zipfile.ZipFile(system) as archive:
        assert sorted(archive.namelist()) == [
            "SystemStructure.ssd",
            "resources/SatelliteDynamics.fmu",
        ]
    columns = ["A.euler_BO[2]", "B.euler_BO[2]", "B.w_BI_B[1]"]
    theirs = ecos(system, 2.0, 0.05, "two_hubs", columns, tmp_path / "ecos.npz")
    mine = simulate(system, stop=2.0)
    for column in columns:
        assert np.allclose(theirs[column], mine[column][1:], rtol=1e-12, atol=1e-15), column
    assert theirs["A.euler_BO[2]"][-1] != 0.0
