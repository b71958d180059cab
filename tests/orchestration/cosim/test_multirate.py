"""Multi-rate stepping (orchestration/cosim/multirate.py, orchestration/system/steps.py): the
SSD annotation, its checks and the master's schedule (controller and steering at their flight
rate, the plant finer)."""

import math

import numpy as np
import pytest
from lxml import etree

from agilesat.orchestration.cosim import multirate
from agilesat.orchestration.cosim.master import simulate
from agilesat.orchestration.output.results import Results
from agilesat.orchestration.scenarios import get
from agilesat.orchestration.system.ssp import read_system
from helpers import agilesat

CONTROL = ("PitchManeuverController", "CmgSteering")


def write_system(fmus, tmp_path, steps, name="multirate.ssd"):
    """scan_pitch with its own steps for some components, FMUs from the build."""
    scenario = get("scan_pitch").system.copy()
    for component, step in steps.items():
        scenario.set_step(component, step)
    path = tmp_path / name
    sources = {n: str(fmus[n]) for n in scenario.components}
    path.write_bytes(scenario.ssd(sources))
    return path


def test_the_step_annotation_is_written_for_us_and_for_libcosim_and_reads_back(fmus, tmp_path):
    path = write_system(fmus, tmp_path, {"PitchManeuverController": 0.1})  # schema-checked
    system = read_system(path)
    steps = {c.name: c.step_size for c in system.components}
    assert steps == {n: (0.1 if n == "PitchManeuverController" else None) for n in steps}
    tree = etree.parse(str(path))
    hint = tree.xpath(
        "//ssd:Component[@name='PitchManeuverController']//osp:StepSizeHint",
        namespaces={
            "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
            "osp": "https://opensimulationplatform.com/SSP/1.0",
        },
    )
    assert [h.get("value") for h in hint] == ["0.1"]


@pytest.mark.parametrize(
    "step, base, stop, expected",
    [
        (0.03, 0.02, 1.2, "is not an integer multiple of the base macro step 0.02 s"),
        (0.01, 0.02, 1.2, "is not an integer multiple of the base macro step 0.02 s"),
        (0.0, 0.02, 1.2, "must be a positive, finite number of seconds, got 0.0"),
        (-0.1, 0.02, 1.2, "must be a positive, finite number of seconds, got -0.1"),
        (math.inf, 0.02, 1.2, "must be a positive, finite number of seconds, got inf"),
        (0.5, 0.05, 1.2, "does not end on a communication point of its step 0.5 s"),
    ],
)
def test_a_step_the_master_cannot_honour_is_refused_naming_file_line_component(
    fmus, tmp_path, step, base, stop, expected
):
    path = write_system(fmus, tmp_path, {"CmgSteering": step})
    line = read_system(path).component("CmgSteering").line
    with pytest.raises(multirate.StepError) as error:
        simulate(path, step=base, stop=stop)
    assert f"{path}:{line}: component 'CmgSteering': " in str(error.value)
    assert expected in str(error.value)


def test_a_step_annotation_without_a_number_is_refused(fmus, tmp_path):
    path = write_system(fmus, tmp_path, {"CmgSteering": 0.1})
    path.write_text(path.read_text().replace('stepSize="0.1"', 'stepSize="fast"'))
    with pytest.raises(multirate.StepError, match="CmgSteering.*got 'fast'"):
        read_system(path)


def test_multiples_of_components_without_the_annotation_are_one(fmus):
    system = read_system(get("scan_pitch").ssd)
    assert set(multirate.multiples(system, 0.05, 3000).values()) == {1}


@pytest.mark.slow
@pytest.mark.integration
def test_the_master_holds_a_slow_component_between_its_communication_points(fmus, tmp_path):
    """Controller and steering at 0.1 s, plant at 0.025 s, through the CLI: their outputs
    change only at multiples of 0.1 s; the plant's at every step; total momentum exact."""
    path = write_system(fmus, tmp_path, dict.fromkeys(CONTROL, 0.1))
    for algorithm in ("gauss-seidel", "jacobi"):
        out = tmp_path / algorithm
        run = agilesat(
            "run", path, "--step", 0.025, "--stop", 4, "--algorithm", algorithm,
            "--out", out, "-q",
        )  # fmt: skip
        assert run.returncode == 0, run.stderr
        results = Results.from_csv(out / "results.csv")
        k = np.rint(results.time / 0.025).astype(int)
        for column in ("PitchManeuverController.tau_cmd", "CmgSteering.delta_dot_cmd"):
            values = results.vector(column)
            changed = np.any(values[1:] != values[:-1], axis=1)
            assert changed.any()
            assert np.all(k[1:][changed] % 4 == 0), column  # only at t = j·0.1 s
        plant = results.vector("CmgCluster.h")
        assert np.all(np.any(plant[1:] != plant[:-1], axis=1)[k[1:] > 1])
        H = results.vector("SatelliteDynamics.H_I")
        assert np.abs(H - H[0]).max() <= 1e-12 * np.linalg.norm(H[0])


@pytest.mark.slow
@pytest.mark.integration
def test_libcosim_reads_its_own_equivalent_of_the_step(fmus, tmp_path):
    """The exported osp:StepSizeHint: libcosim steps the controller every second base
    step, so its torque command changes only at multiples of 0.1 s."""
    import subprocess
    import sys

    from agilesat.fmus.build import write_archive
    from helpers import TOOLS

    scenario = get("scan_pitch").system.copy().set_step("PitchManeuverController", 0.1)
    entries = {f"resources/{n}.fmu": fmus[n].read_bytes() for n in scenario.components}
    entries["SystemStructure.ssd"] = scenario.ssd(
        {n: f"resources/{n}.fmu" for n in scenario.components}
    )
    package = write_archive(tmp_path / "multirate.ssp", entries)
    out = tmp_path / "libcosim.npz"
    run = subprocess.run(
        [sys.executable, str(TOOLS / "libcosim_run.py"), str(package), "3", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=tmp_path,
    )
    assert run.returncode == 0, run.stderr
    results = Results.from_npz(out)
    k = np.rint(results.time / 0.05).astype(int)
    tau = results.vector("PitchManeuverController.tau_cmd")
    changed = np.any(tau[1:] != tau[:-1], axis=1)
    assert changed.any() and np.all(k[1:][changed] % 2 == 0)
    h = results.vector("CmgCluster.h")
    assert np.any(np.any(h[1:] != h[:-1], axis=1)[k[1:] % 2 == 1])  # the plant at 0.05 s
