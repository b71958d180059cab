"""Outputs at the end of a step are those of the inputs the FMU integrated (FMI 2.0
section 4.2.1; components/model.py ``inputs_to_step_end``), for a host that sets input
derivatives and reads the outputs right after ``fmi2DoStep``.

- Every FMU declaring ``canInterpolateInputs``, driven by a plain host in a clean process
  (tests/tools/shim_step_host.py) with the derivative of every Real input set before every
  step: reading right after the step gives bit for bit what a host gets that first sets
  the inputs again to their values at the step's end, with the shim's C step path and the
  compiled kernels and without them.
- Two cross-checks against Basilisk (tests/tools/reference/basilisk_devices.py: a hub with
  three reaction wheels, a hub with the six-CMG cluster) through a plain Gauss-Seidel host
  that interpolates the device momentum (tests/tools/interpolating_host.py
  ``--gauss-seidel``): the hub's rate read right after its step agrees with Basilisk to what
  the two models share (rounding for the wheels; the CMG reference's stated uncertainty
  and its gimbals' momentum model for the CMGs), as with a host that sets the inputs again;
  the held momentum would be off by a step of ḣ over the inertia.
"""

import json

import numpy as np
import pytest

from agilesat.fmus import model_class
from agilesat.orchestration.mission import System
from helpers import TOOLS, run_python

pytestmark = [pytest.mark.slow, pytest.mark.integration]
HOST = (TOOLS / "shim_step_host.py").read_text()
REFERENCE = json.loads((TOOLS / "reference" / "basilisk_devices.json").read_text())


@pytest.fixture(scope="module")
def interpolating(fmus):
    return {name: path for name, path in fmus.items() if model_class(name).INTERPOLATES_INPUTS}


@pytest.fixture(scope="module")
def hosts(interpolating):
    """{"on": results, "off": results}: the C step path on and off, one clean process each."""
    programs = "programs=end_of_step,end_of_step_again"
    got = {}
    for mode in ("on", "off"):
        fmus = (f"{name}={path}" for name, path in interpolating.items())
        result = run_python(HOST, mode, programs, *fmus)
        assert result.returncode == 0, result.stderr
        got[mode] = json.loads(result.stdout.strip().splitlines()[-1])
    return got


def test_every_fmu_that_interpolates_is_driven(interpolating):
    assert set(interpolating) == {"SatelliteDynamics", "CmgCluster", "PayloadGimbals", "Gyro"}


@pytest.mark.parametrize("name", ["SatelliteDynamics", "CmgCluster", "PayloadGimbals", "Gyro"])
def test_outputs_read_right_after_the_step_are_those_of_the_inputs_at_its_end(hosts, name):
    runs = [hosts[mode][f"{name}:{program}"] for mode in ("on", "off") for program in
            ("end_of_step", "end_of_step_again")]  # fmt: skip
    records = [run["record"] for run in runs]
    for record in records:  # OK, or the hub's one warning: hdot_* moved off h_*'s slope
        assert all(set(status) <= {0, 1} for status, _, _ in record)
    after, again = records[0], records[1]
    assert [row[1:] for row in after] == [row[1:] for row in again]  # outputs and inputs
    assert [row[0][:2] for row in after] == [row[0][:2] for row in again]
    assert runs[0]["messages"] == runs[1]["messages"]
    assert records[2] == after and records[3] == again  # the Python: the same bits
    assert runs[0]["counts"][1] > 0  # steps served by the C step path


# -- the Basilisk cross-checks -----------------------------------------------------------
def _wheels(fmus):
    case = REFERENCE["wheels"]
    system = System("wheels", step=REFERENCE["step"], stop=REFERENCE["stop"])
    system.add("Flywheel", fmus["Flywheel"])  # first: the hub interpolates its momentum
    system.add("SatelliteDynamics", fmus["SatelliteDynamics"])
    system.connect("Flywheel.h", "SatelliteDynamics.h_wheel")
    system.connect("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B")
    system.set("Flywheel.J_wheel", case["J_wheel"])
    system.set("Flywheel.viscous_friction", 0.0)
    system.set("Flywheel.coulomb_friction", 0.0)
    system.set("Flywheel.speed0", case["speed0"] + [0.0])
    system.set("Flywheel.tau_cmd", case["tau_cmd"])
    return system, case


def _cmgs(fmus):
    case = REFERENCE["cmgs"]
    system = System("cmgs", step=REFERENCE["step"], stop=REFERENCE["stop"])
    system.add("CmgCluster", fmus["CmgCluster"])
    system.add("SatelliteDynamics", fmus["SatelliteDynamics"])
    system.connect("CmgCluster.h", "SatelliteDynamics.h_cmg")
    system.set("CmgCluster.h_rotor", case["h_rotor"])
    system.set("CmgCluster.accel_limit", 1e4)  # the rates from the first instant
    system.set("CmgCluster.delta_dot_cmd", case["delta_dot_cmd"])
    system.set("SatelliteDynamics.h_payload", case["h_gimbals"])  # the gimbal frames'
    return system, case


@pytest.fixture(scope="module")
def crosscheck(fmus, tmp_path_factory):
    """{(case, host options): w_BI_B every step}, each run in a clean process."""
    folder, got = tmp_path_factory.mktemp("basilisk"), {}
    for make in (_wheels, _cmgs):
        system, case = make(fmus)
        system.set("SatelliteDynamics.inertia", case["hub_inertia"])
        system.set("SatelliteDynamics.rate0", case["rate0"])
        system.set("SatelliteDynamics.gravity_gradient", False)
        ssd = system.write(folder / f"{system.name}.ssd")
        for options in (("--read-after-step",), ()):
            out = folder / f"{system.name}{len(options)}.npz"
            result = run_python(
                (TOOLS / "interpolating_host.py").read_text(),
                ssd,
                REFERENCE["stop"],
                REFERENCE["step"],
                out,
                "--gauss-seidel",
                *options,
            )
            assert result.returncode == 0, result.stderr
            found = np.load(out)
            names = list(found["names"])
            columns = [names.index(f"SatelliteDynamics.w_BI_B[{i}]") for i in (1, 2, 3)]
            got[system.name, options] = found["data"][:, columns]
    return got


@pytest.mark.parametrize(
    "case, bound, held",
    [
        # rounding: the two integrate the same polynomial motion over each step but for
        # the gyroscopic term (5e-4 rad a step: RK4's error 1e-17 relative)
        ("wheels", 1e-12, 1e-5),
        # the reference's servo: 8.5e-7 rad of gimbal angle (1.5e-8 rad/s on w) and its
        # extrapolation (servo_uncertainty, 1.5e-9); the rotors' spin change with the body
        # rate (I_W Δω, 4e-9); the hub's momentum taken linear over a step (its curvature
        # ḧ H² / 8 on the attitude, 3e-9 on w): 1e-7
        ("cmgs", 1e-7, 1e-5),
    ],
)
def test_the_hub_read_right_after_its_step_agrees_with_basilisk(crosscheck, case, bound, held):
    reference = np.array(REFERENCE[case]["w_BI_B"])
    after = crosscheck[case, ("--read-after-step",)]
    again = crosscheck[case, ()]
    assert after.shape == reference.shape
    worst = np.max(np.abs(after - reference))
    print(f"{case}: read right after the step {worst:.3g} rad/s from Basilisk, "
          f"inputs set again first {np.max(np.abs(again - reference)):.3g}")  # fmt: skip
    assert worst < bound
    assert np.max(np.abs(again - reference)) < bound
    # what holding the momentum over the step would give: a step of ḣ over the inertia
    step_of_hdot = np.max(np.abs(np.diff(reference, axis=0)))
    assert step_of_hdot > held > 10 * bound
