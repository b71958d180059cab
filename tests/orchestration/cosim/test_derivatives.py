"""FMI 2.0 input and output derivatives (``fmi2SetRealInputDerivatives``,
``fmi2GetRealOutputDerivatives``): second-order coupling without the explicit ḣ wires.

The system: scan_pitch with its ``SatelliteDynamics.hdot_*`` connections removed, so the hub
learns the cluster's ḣ only through the FMI derivative calls (the master passes them where
both FMUs declare them).  The yardstick is the monolithic sampled-data reference
(tests/tools/reference/scan_pitch.py, ``control_period=P``); coupling error = max over the 150 s
run of |pitch(co-simulation) − pitch(reference)|.  Controller and steering run at
P = 0.05 s, the plant FMUs at H (multi-rate), so a smaller H changes the coupling only.

``python tests/orchestration/cosim/test_derivatives.py`` prints the table the README quotes.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

TESTS = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(TESTS), str(TESTS / "tools")]  # also run as a script: helpers, reference

from agilesat.orchestration.cosim.master import simulate  # noqa: E402
from agilesat.orchestration.scenarios import get  # noqa: E402
from agilesat.orchestration.system.ssp import read_system  # noqa: E402
from helpers import run_python  # noqa: E402
from reference import scan_pitch as reference  # noqa: E402

DEG = math.pi / 180
FINE, P, STOP = 1e-3, 0.05, 150.0
STEPS = (0.05, 0.025)
CONTROLLERS = ("PitchManeuverController", "CmgSteering")


def twist(q):
    """Pitch as the twist of q_BO about y (well defined through 90°)."""
    q = np.where(q[:, :1] < 0, -q, q)
    return 2 * np.arctan2(q[:, 2], q[:, 0])


def system(directory: Path, fmus: dict, wired: bool, step: float):
    """scan_pitch with controller and steering at P and the plant at ``step``; without the
    ḣ wires unless ``wired``."""
    scenario = get("scan_pitch").system.copy()
    if step != P:
        for name in CONTROLLERS:
            scenario.set_step(name, P)
    path = directory / f"scan_pitch_{step}.ssd"
    path.write_bytes(scenario.ssd({n: str(fmus[n]) for n in scenario.components}))
    result = read_system(path)
    if not wired:
        result.connections = [
            c for c in result.connections if not c.end_connector.startswith("hdot_")
        ]
    return result


def run(directory, fmus, step, algorithm, wired=False, derivatives=True, stop=STOP):
    return simulate(
        system(directory, fmus, wired, step),
        step=step,
        stop=stop,
        algorithm=algorithm,
        derivatives=derivatives,
    )


def pitch_error(results, truth, step) -> float:
    every = round(step / FINE)
    assert np.allclose(truth["time"][::every], results.time)
    pitch = twist(results.vector("SatelliteDynamics.q_BO"))
    return float(np.abs(pitch - twist(truth["q_BO"])[::every]).max())


SCHEMES = {  # label: (algorithm, ḣ wired, derivatives)
    "jacobi, ḣ wired (as shipped)": ("jacobi", True, True),
    "jacobi, no ḣ wires, derivatives": ("jacobi", False, True),
    "jacobi, no ḣ wires, no derivatives": ("jacobi", False, False),
    "gauss-seidel, ḣ wired": ("gauss-seidel", True, True),
    "gauss-seidel, no ḣ wires, derivatives (interpolation)": ("gauss-seidel", False, True),
}


# -- the tests -------------------------------------------------------------------------
def _var(name, causality, unit, shape=(3,), **kw):
    from agilesat.components.variables import input_, output, parameter

    make = {"input": input_, "output": output}.get(causality)
    if make is None:
        return parameter(name, 0.0, unit, name, shape=shape, **kw)
    return make(name, unit, name, shape=shape, **kw)


@pytest.mark.parametrize(
    "base",
    [
        _var("h", "output", "N.m.s", shape=(2,)),  # another shape
        _var("h", "input", "N.m.s"),  # another causality
        _var("h", "output", "rad"),  # N.m is not rad per second
        _var("g", "output", "N.m.s"),  # not the one named
    ],
)
def test_a_derivative_must_match_what_it_is_the_derivative_of(base):
    from agilesat.components.variables import Layout

    derivative = _var("hdot", "output", "N.m", derivative_of="h")
    with pytest.raises(ValueError, match="hdot: derivative_of='h' must name a Real output"):
        Layout((base, derivative))
    with pytest.raises(ValueError, match="only Real inputs and outputs can be derivatives"):
        _var("p", "parameter", "N.m", derivative_of="h")


def test_a_declared_derivative_reaches_the_model_description():
    import xml.etree.ElementTree as ET

    from agilesat.components.satellite_dynamics import SatelliteDynamics
    from agilesat.fmus.model_description import model_description

    root = ET.fromstring(model_description("S", SatelliteDynamics, "g", "d", "t"))
    variables = root.findall("ModelVariables/ScalarVariable")
    derivative = {v.get("name"): v[0].get("derivative") for v in variables}
    assert variables[int(derivative["hdot_wheel[2]"]) - 1].get("name") == "h_wheel[2]"
    assert derivative["h_wheel[2]"] is None and derivative["tau_ext[1]"] is None
    assert root.find("CoSimulation").get("canInterpolateInputs") == "true"
    assert root.find("CoSimulation").get("maxOutputDerivativeOrder") == "1"


@pytest.fixture(scope="module")
def truth():
    return reference.simulate(FINE, STOP, control_period=P)


@pytest.fixture(scope="module")
def errors(fmus, truth, tmp_path_factory):
    """Coupling error in pitch [rad] of each scheme at each plant step."""
    directory = tmp_path_factory.mktemp("systems")
    return {
        (label, step): pitch_error(
            run(directory, fmus, step, algorithm, wired, derivatives), truth, step
        )
        for label, (algorithm, wired, derivatives) in SCHEMES.items()
        for step in STEPS
    }


def order(errors, label) -> float:
    return math.log(errors[label, STEPS[0]] / errors[label, STEPS[1]]) / math.log(
        STEPS[0] / STEPS[1]
    )


@pytest.mark.slow
@pytest.mark.integration
def test_without_the_wires_jacobi_with_derivatives_is_the_wired_run_bit_for_bit(fmus, tmp_path):
    """Tolerance zero, by construction: fmi2GetRealOutputDerivatives of the cluster's h is
    its output hdot at t_n, and fmi2SetRealInputDerivatives of the hub's h_cmg makes it the
    slope of h_cmg over the step, where the wired run has hdot_cmg: the same number the wire
    passes, at the same time."""
    wired = run(tmp_path, fmus, P, "jacobi", wired=True, stop=20.0)
    derived = run(tmp_path, fmus, P, "jacobi", stop=20.0)
    assert wired.names == derived.names
    assert wired.data.tobytes() == derived.data.tobytes()
    assert "derivatives" not in wired.meta  # the wire wins: no derivative calls at all
    assert derived.meta["derivatives"] == [
        f"CmgCluster.h[{i}] -> SatelliteDynamics.h_cmg[{i}] (extrapolated)" for i in (1, 2, 3)
    ]


@pytest.mark.slow
@pytest.mark.integration
def test_without_derivatives_the_coupling_is_first_order_and_larger(errors):
    off, on = "jacobi, no ḣ wires, no derivatives", "jacobi, no ḣ wires, derivatives"
    for step in STEPS:
        assert errors[off, step] > 10 * errors[on, step], (step, errors)
    assert order(errors, off) < 1.3, errors


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize(
    "label",
    ["jacobi, no ḣ wires, derivatives", "gauss-seidel, no ḣ wires, derivatives (interpolation)"],
)
def test_with_derivatives_the_coupling_is_second_order(errors, label):
    assert order(errors, label) >= 1.9, errors
    assert errors[label, P] <= 0.01 * DEG, errors


@pytest.mark.slow
@pytest.mark.integration
def test_wired_gauss_seidel_stays_the_first_order_scheme(errors):
    """The explicit ḣ wire wins over the derivatives (nothing to interpolate): Gauss-Seidel
    with the wires is the first-order scheme it was."""
    label = "gauss-seidel, ḣ wired"
    assert errors[label, P] > 0.1 * DEG and order(errors, label) < 1.3, errors


FMPY_HOST = """
import json, sys
import numpy as np
from fmpy import simulate_fmu
path = sys.argv[1]
# FMPy's Input keeps 9 input derivatives whatever the number of inputs (fmpy 0.3
# simulation.py, Input.__init__; no upstream issue found): the table has exactly the hub's
# 9 momentum inputs (h_cmg[3] = 0.1 t, slope 0.1 exactly; the rest zero)
ramp = [(-20.0, -2.0), (40.0, 4.0)]  # FMPy: derivative 0 at the table's first time
momenta = [f"h_{d}[{i}]" for d in ("cmg", "wheel", "payload") for i in (1, 2, 3)]
def table(*extra):
    names = ["time", *momenta, *extra]
    rows = [(t, 0, 0, h, 0, 0, 0, 0, 0, 0) + (0, 0, 0.1)[: len(extra)] for t, h in ramp]
    return np.array(rows, dtype=[(n, np.double) for n in names])
def run(signals, derivatives):
    return simulate_fmu(path, stop_time=20.0, step_size=0.5, output_interval=0.5,
                        input=signals, set_input_derivatives=derivatives,
                        start_values={"gravity_gradient": False},
                        output=["w_BI_B[3]", "q_BI[1]", "q_BI[4]"])
wired = run(table("hdot_cmg[1]", "hdot_cmg[2]", "hdot_cmg[3]"), False)
derived, held = run(table(), True), run(table(), False)
diff = lambda a, b, names: max(float(np.abs(a[n] - b[n]).max()) for n in names)
# FMPy reads the outputs right after the step: the rate of h at the step's end where the
# derivative moved it (h_cmg[3] by 0.1 * 0.5 after every step), of h held at the step's
# start where the wire gave the slope
moved = wired["w_BI_B[3]"] - np.where(wired["time"] > 0.0, 0.1 * 0.5 / 956.0, 0.0)
print(json.dumps({
    "attitude": diff(wired, derived, ["q_BI[1]", "q_BI[4]"]),
    "rate": float(np.abs(derived["w_BI_B[3]"] - moved).max()),
    "held": diff(wired, held, wired.dtype.names[1:]),
}))
"""


@pytest.mark.slow
@pytest.mark.integration
def test_fmpy_as_host_sets_input_derivatives_in_a_clean_process(fmus):
    """FMPy's own simulate_fmu(set_input_derivatives=True) on the hub with a momentum ramp
    and no ḣ input: the same motion, bit for bit, as with ḣ given as an input, and the rate
    FMPy reads right after each step that of the momentum at the step's end (the wired run
    reports it from the momentum held at the step's start: a step of ḣ over the inertia
    apart); without the derivatives the hub holds h over each step (a different run)."""
    from fmpy.validation import validate_fmu

    for name in ("CmgCluster", "Flywheel", "PayloadGimbals", "SatelliteDynamics"):
        assert validate_fmu(str(fmus[name])) == [], name
    run = run_python(FMPY_HOST, fmus["SatelliteDynamics"])
    assert run.returncode == 0, run.stderr
    found = json.loads(run.stdout.strip().splitlines()[-1])
    assert found["attitude"] == 0.0 and found["rate"] < 1e-15 and found["held"] > 1e-6, found


FMPY_PAYLOAD = """
import json, sys
import numpy as np
from fmpy import simulate_fmu
path = sys.argv[1]
# 9 continuous inputs (FMPy keeps 9 input derivatives): both payloads' angle and rate
# commands, payload 1's roll acceleration command; the angles ramp at 0.1 rad/s while the
# rate commands ramp from 0.05 rad/s at 0.01 rad/s2 (a table of one segment: FMPy gives a
# table's left segment's slope at a breakpoint, and 0 at its first time)
names = ["roll_cmd[1]", "roll_cmd[2]", "pitch_cmd[1]", "pitch_cmd[2]", "roll_rate_cmd[1]",
         "roll_rate_cmd[2]", "pitch_rate_cmd[1]", "pitch_rate_cmd[2]", "roll_accel_cmd[1]"]
def row(t):
    angle, rate = 0.2 + 0.1 * t, 0.05 + 0.01 * t
    return (t, angle, -angle, 0.5 * angle, -0.5 * angle, rate, -rate, 0.5 * rate, -0.5 * rate, 0.0)
table = np.array([row(-20.0), row(40.0)], dtype=[(n, np.double) for n in ["time", *names]])
def run(step, derivatives):
    return simulate_fmu(path, stop_time=10.0, step_size=step, output_interval=step, input=table,
                        set_input_derivatives=derivatives,
                        start_values={"bandwidth": 3.0, "damping": 0.7},
                        output=["roll[1]", "pitch[2]", "roll_rate[1]", "h[3]"])
def diff(a, fine):
    every = round((a["time"][1] - a["time"][0]) / (fine["time"][1] - fine["time"][0]))
    return max(float(np.abs(a[n] - fine[n][::every]).max()) for n in a.dtype.names[1:])
fine = run(0.005, True)
print(json.dumps({"derived": diff(run(0.5, True), fine), "held": diff(run(0.5, False), fine)}))
"""


@pytest.mark.slow
@pytest.mark.integration
def test_fmpy_drives_the_payload_servo_with_interpolated_commands(fmus):
    """FMPy's simulate_fmu(set_input_derivatives=True) on the payload servo with commands
    ramping (angles at one slope, rate commands at another): the servo follows linearly
    interpolated commands in closed form, so steps of 0.5 s are 100 times finer steps to
    rounding; held, the commands are 0.3 rad off.  (The servo's states only: FMPy reads the
    outputs of t_{n+1} before it sets that time's inputs, which the accelerations in ḣ
    depend on.)"""
    run = run_python(FMPY_PAYLOAD, fmus["PayloadGimbals"])
    assert run.returncode == 0, run.stderr
    found = json.loads(run.stdout.strip().splitlines()[-1])
    assert found["derived"] < 1e-11 and found["held"] > 0.1, found


@pytest.mark.slow
@pytest.mark.integration
def test_model_descriptions_declare_the_derivatives(fmus):
    from fmpy import read_model_description

    declared = {}
    for name in ("CmgCluster", "Flywheel", "PayloadGimbals", "SatelliteDynamics", "CmgSteering"):
        md = read_model_description(str(fmus[name]))
        pairs = {v.name: v.derivative.name for v in md.modelVariables if v.derivative}
        cs = md.coSimulation
        declared[name] = (cs.canInterpolateInputs, cs.maxOutputDerivativeOrder, pairs)
    axes = (1, 2, 3)
    device = {f"hdot[{i}]": f"h[{i}]" for i in axes}
    # the rotors' jitter momentum, for the hub's rotating rows (docs/jitter.md)
    cluster = device | {f"hdot_jitter_B[{i}]": f"h_jitter_B[{i}]" for i in axes}
    wheels = device | {
        f"hdot_jitter_B[{w},{i}]": f"h_jitter_B[{w},{i}]" for w in (1, 2, 3, 4) for i in axes
    }
    assert declared["CmgCluster"] == (True, 1, cluster)
    assert declared["PayloadGimbals"] == (True, 1, device)
    assert declared["Flywheel"] == (False, 1, wheels)  # its drive samples its inputs
    hub = {f"hdot_{d}[{i}]": f"h_{d}[{i}]" for d in ("cmg", "wheel", "payload") for i in axes}
    hub |= {f"hdot_extra[{r},{i}]": f"h_extra[{r},{i}]" for r in range(1, 7) for i in axes}
    assert declared["SatelliteDynamics"] == (True, 1, hub)
    assert declared["CmgSteering"] == (False, 0, {})


# -- the table ---------------------------------------------------------------------------
def main() -> None:
    import tempfile
    import time

    from agilesat.fmus.build import build_all

    fmus = {path.stem: path for path in build_all()}
    truth = reference.simulate(FINE, STOP, control_period=P)
    print(f"coupling error in pitch against the sampled reference (P = {P} s), {STOP:g} s run")
    print("| scheme | plant step H [s] | coupling error [deg] | observed order |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as directory:
        for label, (algorithm, wired, derivatives) in SCHEMES.items():
            found = {}
            for step in STEPS:
                results = run(Path(directory), fmus, step, algorithm, wired, derivatives)
                found[label, step] = pitch_error(results, truth, step)
                rate = f"{order(found, label):.2f}" if step == STEPS[-1] else "—"
                print(f"| {label} | {step} | {found[label, step] / DEG:.2g} | {rate} |")
        timed = [label for label in SCHEMES if "no derivatives" not in label]
        best = dict.fromkeys(timed, math.inf)
        for _ in range(5):  # interleaved, best of 5, in one process
            for label in timed:
                algorithm, wired, derivatives = SCHEMES[label]
                start = time.perf_counter()
                run(Path(directory), fmus, P, algorithm, wired, derivatives)
                best[label] = min(best[label], time.perf_counter() - start)
        print(f"wall per simulated second at H = {P} s (best of 5, interleaved):")
        for label in timed:
            print(f"  {label}: {1e3 * best[label] / STOP:.1f} ms")


if __name__ == "__main__":
    main()
