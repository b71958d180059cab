"""System files (SSP) and the master: validation errors, failures, settings.

Everything that runs FMUs goes through the ``agilesat`` command in a fresh process.
"""

import re

import numpy as np
import pytest

from agilesat.orchestration.output.results import Results
from agilesat.orchestration.scenarios import get
from agilesat.orchestration.system.ssp import SystemFileError, read_system
from helpers import agilesat

SCAN_PITCH = get("scan_pitch").ssd


@pytest.mark.slow
@pytest.mark.integration
def test_committed_generated_files_are_up_to_date():
    """The .ssd files and fmus/INTERFACES.md come from the scenarios and variable tables."""
    result = agilesat("generate", "--check")
    assert result.returncode == 0, result.stderr


def test_shipped_system_follows_the_ssp_schema_and_reads_back():
    system = read_system(SCAN_PITCH)
    assert [c.name for c in system.components] == list(get("scan_pitch").components)
    assert (system.stop_time, system.step_size, system.algorithm) == (150.0, 0.05, "jacobi")
    # orbit→dynamics 10, cluster→dynamics 6, dynamics→controller 7, controller→steering 3,
    # cluster→steering 9, dynamics→steering 3, steering→cluster 6 scalar connections
    assert len(system.connections) == 10 + 6 + 7 + 3 + 9 + 3 + 6


@pytest.fixture
def broken(fmus, tmp_path):
    """Write a copy of scan_pitch.ssd with an edit applied; return its path."""
    text = SCAN_PITCH.read_text()
    for name, path in fmus.items():
        text = text.replace(f'source="../../fmus/build/{name}.fmu"', f'source="{path}"')

    def write(edit):
        path = tmp_path / "broken.ssd"
        path.write_text(edit(text))
        return path

    return write


def connection(a, x, b, y):
    return (
        f'<ssd:Connection startElement="{a}" startConnector="{x}" endElement="{b}" '
        f'endConnector="{y}"/>'
    )


def retarget(text, old, new):
    assert old in text
    return text.replace(old, new, 1)


R_I = connection("OrbitEnvironment", "r_I[1]", "SatelliteDynamics", "r_I[1]")
W_OI = connection("OrbitEnvironment", "w_OI_O[1]", "SatelliteDynamics", "w_OI_O[1]")
TAU = connection("PitchManeuverController", "tau_cmd[2]", "CmgSteering", "tau_cmd[2]")

CASES = {
    "unknown component": (
        lambda s: retarget(s, R_I, R_I.replace('"OrbitEnvironment"', '"Orbit"')),
        ["unknown component 'Orbit'"],
    ),
    "unknown variable": (
        lambda s: retarget(s, R_I, R_I.replace('endConnector="r_I[1]"', 'endConnector="r_I[4]"')),
        ["SatelliteDynamics", "has no variable 'r_I[4]'"],
    ),
    "causality": (
        lambda s: retarget(
            s, R_I, connection("SatelliteDynamics", "tau_ext[1]", "SatelliteDynamics", "r_I[1]")
        ),
        ["'tau_ext[1]' of SatelliteDynamics is an input, expected an output"],
    ),
    "type": (
        lambda s: retarget(
            s, TAU, connection("PitchManeuverController", "phase", "CmgSteering", "tau_cmd[2]")
        ),
        ["type mismatch, Integer -> Real"],
    ),
    "unit": (
        lambda s: retarget(
            s, R_I, connection("OrbitEnvironment", "v_I[1]", "SatelliteDynamics", "r_I[1]")
        ),
        ["unit mismatch, 'm/s' -> 'm'"],
    ),
    "driven twice": (
        lambda s: retarget(
            s, R_I, R_I + connection("OrbitEnvironment", "r_I[2]", "SatelliteDynamics", "r_I[1]")
        ),
        ["input SatelliteDynamics.r_I[1] is already driven by OrbitEnvironment.r_I[1]"],
    ),
    "required input open": (
        lambda s: retarget(s, TAU, ""),
        ["required input CmgSteering.tau_cmd[2] is not connected"],
    ),
    "not a parameter": (
        lambda s: s.replace('<ssv:Parameter name="h_rotor">', '<ssv:Parameter name="hdot[1]">', 1),
        ["CmgCluster.hdot[1] is an output, expected a parameter"],
    ),
    "algebraic loop": (
        lambda s: retarget(
            s, W_OI, connection("CmgSteering", "delta_dot_cmd[1]", "SatelliteDynamics", "w_OI_O[1]")
        ),
        ["algebraic loop", "SatelliteDynamics", "CmgSteering"],
    ),
    "schema": (
        lambda s: s.replace("<ssd:Connections>", "<ssd:Wires>", 1).replace(
            "</ssd:Connections>", "</ssd:Wires>", 1
        ),
        ["does not follow the SSP 1.0 schema", "Wires"],
    ),
    "not XML": (lambda s: s[:-40], ["not well-formed XML"]),
}


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("case", CASES)
def test_a_bad_system_is_refused_naming_file_line_and_variable(broken, case, tmp_path):
    edit, expected = CASES[case]
    path = broken(edit)
    result = agilesat("run", path, "--stop", "0.1", "--out", tmp_path / "out")
    assert result.returncode == 1
    message = result.stderr
    assert str(path) in message
    for text in expected:
        assert text in message
    if case not in ("schema", "not XML", "algebraic loop"):
        assert re.search(rf"{re.escape(str(path))}:\d+", message)  # with a line number
    assert not (tmp_path / "out" / "results.csv").exists()  # nothing was run


def test_read_system_reports_a_missing_fmu(broken, fmus):
    path = broken(
        lambda s: s.replace(f'source="{fmus["CmgCluster"]}"', 'source="nowhere/CmgCluster.fmu"')
    )
    with pytest.raises(
        SystemFileError,
        match=r"broken.ssd:\d+: component 'CmgCluster': "
        "FMU source 'nowhere/CmgCluster.fmu' not found",
    ):
        read_system(path)


@pytest.mark.slow
@pytest.mark.integration
def test_a_failing_fmu_stops_the_run_and_keeps_what_was_recorded(fmus, tmp_path):
    out = tmp_path / "out"
    result = agilesat(
        "run",
        "scan_pitch",
        "--set",
        "SatelliteDynamics.inertia[1,1]=1e-4",
        "--algorithm",
        "gauss-seidel",  # the failure time below is that of this scheme
        "--out",
        out,
        "--no-figures",
        "--no-report",
    )
    assert result.returncode == 1
    assert "SatelliteDynamics: fmi2DoStep at t=0.35 s returned fmi2Error" in result.stderr
    assert "the state is unphysical" in result.stderr
    kept = Results.from_csv(out / "results.csv")
    assert kept.time[-1] == pytest.approx(0.35) and len(kept) == 8  # t = 0 .. 0.35
    assert np.all(np.isfinite(kept.data))
    assert "unphysical" in (out / "log.txt").read_text()


@pytest.mark.slow
@pytest.mark.integration
def test_unknown_override_is_an_error(fmus, tmp_path):
    result = agilesat("run", "scan_pitch", "--set", "CmgCluster.nope=1", "--out", tmp_path)
    assert (
        result.returncode == 1
        and "CmgCluster (CmgCluster.fmu) has no variable 'nope'" in result.stderr
    )


@pytest.mark.slow
@pytest.mark.integration
def test_unknown_scenario_variant_is_an_error():
    result = agilesat("run", "scan_pitch:nope")
    assert result.returncode == 1 and "has no variant 'nope'" in result.stderr


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_results_have_named_columns_at_every_communication_point(fmus, tmp_path, algorithm):
    result = agilesat(
        "run",
        "scan_pitch",
        "--stop",
        "2",
        "--step",
        "0.1",
        "--algorithm",
        algorithm,
        "--out",
        tmp_path,
        "--no-figures",
        "--no-report",
    )
    assert result.returncode == 0, result.stderr
    results = Results.from_csv(tmp_path / "results.csv")
    assert results.names[0] == "time" and "SatelliteDynamics.q_BI[1]" in results.names
    assert np.allclose(results.time, np.arange(21) * 0.1)
    assert results["PitchManeuverController.phase"][0] == 1
    binary = Results.from_npz(tmp_path / "results.npz")
    assert binary.names == results.names and np.array_equal(binary.data, results.data)
