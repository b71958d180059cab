"""Every FMU through a generic host that interpolates inputs (tests/tools/interpolating_host.py):
it sends the first derivative of every input it can (from an FMU declaring output
derivatives into one declaring canInterpolateInputs) and asks the derivatives of every
Real output of every FMU declaring them, at every step.  The systems: the three shipped
scenarios (exported packages, moved out of the repository), a closed loop through the
sensing FMUs (tests/tools/sensing_loop.py) and the guide's two-target pass
(examples/two_targets: slew guidance and momentum management, its first 20 s: nadir, then
the slew into the first stare): every FMU.

Without derivatives the host is our master's Jacobi scheme: its runs are the master's to
the last bits (the hub's Euler angles follow the branch of their latest evaluation, and this
host evaluates the outputs more often, with inputs not yet settled: 1e-15 relative in
payload_sweep, nothing elsewhere).  With them, every call is answered (no error, every derivative
finite) and the runs differ from the wired ones only by what the derivatives change:

- the hub's momentum slope: the derivative of ``h`` the devices answer is their ``hdot``,
  the number the ḣ wires carry: nothing;
- the hub's momentum curvature: the derivative of ``hdot`` (the cluster's ḧ, one-sided at
  t_n) curves h over the step; in scan_pitch and video_sar the gimbals reach their
  commanded rates within most steps, so this extrapolation overshoots: printed, bounded
  below by what it is (a different coupling), above by 0.05°;
- the gyro's true rate over the step: the parabola with the hub's ẇ at t_n (third order)
  instead of the line: a difference at the level of the gyro's own interpolation error.
"""

import subprocess
import sys

import numpy as np
import pytest
from sensing_loop import STEP, STOP, write_ssd

from agilesat.orchestration.cosim.master import simulate
from agilesat.orchestration.scenarios import NAMES, get
from helpers import HOST_CASES, ROOT, TOOLS, agilesat, export_elsewhere

pytestmark = [pytest.mark.slow, pytest.mark.integration]
ATTITUDE = [f"SatelliteDynamics.q_BI[{i}]" for i in (1, 2, 3, 4)]
SYSTEMS = [*NAMES, "sensing_loop", "two_targets"]


@pytest.fixture(scope="module")
def systems(fmus, tmp_path_factory):
    """{name: (system file, stop, step)}: the shipped scenarios, exported, and the loop."""
    packages = export_elsewhere(tmp_path_factory)
    found = {name: (packages[name], HOST_CASES[name][0], get(name).step) for name in NAMES}
    found["sensing_loop"] = (write_ssd(tmp_path_factory.mktemp("loop")), STOP, STEP)
    package = tmp_path_factory.mktemp("mission") / "two_targets.ssp"
    exported = agilesat(
        "export", ROOT / "examples" / "two_targets" / "mission.py", "--out", package
    )
    assert exported.returncode == 0, exported.stderr
    found["two_targets"] = (package, 20.0, 0.05)
    return found


def host(system, stop, step, out, *options):
    run = subprocess.run(
        [sys.executable, str(TOOLS / "interpolating_host.py"), str(system), str(stop), str(step)]
        + [str(out), *options],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    assert run.returncode == 0, run.stderr
    saved = np.load(out)
    return list(saved["names"]), saved["data"], run.stdout


def master(system, stop):
    results = simulate(system, stop=stop, algorithm="jacobi")
    return results.names, results.data


def angle(q_a, q_b) -> np.ndarray:
    """The rotation between two attitudes (rows of quaternions), rad."""
    dot = np.abs(np.sum(q_a * q_b, axis=1)) / (
        np.linalg.norm(q_a, axis=1) * np.linalg.norm(q_b, axis=1)
    )
    return 2 * np.arccos(np.clip(dot, 0.0, 1.0))


def test_every_fmu_is_in_a_system(systems):
    from agilesat.fmus import FMUS
    from agilesat.orchestration.system.ssp import read_system

    used = {
        c.source.name.split("_")[0].removesuffix(".fmu")
        for path, _, _ in systems.values()
        for c in read_system(path).components
    }
    assert used == set(FMUS)


@pytest.mark.parametrize("name", SYSTEMS)
def test_without_derivatives_the_host_is_our_masters_jacobi(name, systems, tmp_path):
    system, stop, step = systems[name]
    names, data, _ = host(system, stop, step, tmp_path / "held.npz", "--no-derivatives")
    theirs, ours = master(system, stop)
    assert len(data) == len(ours) == round(stop / step) + 1
    columns = [n for n in names[1:] if n in theirs]
    assert len(columns) > 40
    mine, other = (
        ours[:, [theirs.index(n) for n in columns]],
        data[:, [names.index(n) for n in columns]],
    )
    scale = np.maximum(np.abs(mine).max(axis=0), 1e-300)
    assert np.all(np.abs(other - mine) <= 1e-14 * scale)


@pytest.mark.parametrize("name", SYSTEMS)
def test_with_every_derivative_sent_and_asked_the_host_runs_to_the_end(name, systems, tmp_path):
    system, stop, step = systems[name]
    names, data, said = host(system, stop, step, tmp_path / "derived.npz")
    theirs, ours = master(system, stop)
    assert len(data) == round(stop / step) + 1 and data[-1, 0] == pytest.approx(stop)
    assert "[3]" not in said and "[4]" not in said  # no error logged by any FMU
    attitude = angle(
        data[:, [names.index(c) for c in ATTITUDE]], ours[:, [theirs.index(c) for c in ATTITUDE]]
    )
    links = int(said.strip().splitlines()[-1].split()[0])
    print(
        f"{name}: {links} derivative links; attitude off the wired run by up to "
        f"{np.degrees(attitude.max()):.3g} deg"
    )
    assert links > 0
    assert attitude.max() < np.radians(0.05)
