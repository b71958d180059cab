"""Helpers shared by the tests: paths, a real TLE, and clean processes to run FMUs in.

Built FMUs are only ever *run* in a separate, fresh interpreter (``run_python`` and
``agilesat``): pythonfmu executes FMU code inside the host's interpreter, where modules
this pytest process imported could mask a file missing from an FMU.
"""

import io
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: the tests' tools: benchmarks, hosts, fault cases, the monolithic references (on sys.path
#: in the tests: ``conftest.py``)
TOOLS = ROOT / "tests" / "tools"
#: a real satellite's two-line elements: the ISS set printed in the python-sgp4 README
#: (https://pypi.org/project/sgp4/), epoch 2019-12-09 16:38:29 UTC
ISS_TLE = (
    "1 25544U 98067A   19343.69339541  .00001764  00000-0  38792-4 0  9991",
    "2 25544  51.6439 211.2001 0007417  17.6667  85.6398 15.50103472202482",
)


def run_python(code: str, *args, timeout: float = 600, cwd=None) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter of this environment (nothing pre-imported)."""
    return subprocess.run(
        [sys.executable, "-c", code, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=cwd or ROOT,
    )


def agilesat(*args, timeout: float = 900, cwd=None) -> subprocess.CompletedProcess:
    """The ``agilesat`` command line, in a fresh interpreter."""
    return subprocess.run(
        [sys.executable, "-m", "agilesat.orchestration", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=cwd or ROOT,
    )


def slave(name: str, start_time: float = 0.0):
    """FMU ``name``'s wrapper (a ``ModelSlave``) instantiated in this process, in
    initialisation mode: drive it with ``set_real``/``do_step``/``get_real`` as a host
    would (pythonfmu's own tests do the same with their slaves)."""
    from agilesat.fmus import slave_class

    instance = slave_class(name)(instance_name=f"test_{name}")
    instance.setup_experiment(start_time)
    instance.enter_initialization_mode()
    return instance


def logged(instance, status: str = "error") -> list[str]:
    """Messages an in-process slave logged at ``status`` ("error", "warning", ...)."""
    return [entry.msg for entry in instance.log_queue if entry.status.name == status]


def operating_point(name: str, rng) -> dict:
    """Real input values (by variable) away from zero: quaternions unit, the staring
    and slew guidance fed a real orbit and target and the disturbance torques a real orbit (from
    OrbitEnvironment's defaults), the wheels' torque within their limit; Boolean and
    Integer inputs keep their start values."""
    import numpy as np

    from agilesat.fmus import model_class as _model_class

    orbit = _model_class("OrbitEnvironment")().start(0.0)
    if name == "StaringGuidance":
        return {v: orbit.get(v) for v in ("r_I", "v_I", "r_T_I", "v_T_I", "q_OI")}
    if name == "SlewGuidance":
        names = ("r_I", "v_I", "q_OI", "w_OI_O", "earth_angle")
        return {v: np.atleast_1d(orbit.get(v)) for v in names}
    values = {}
    for v in _model_class(name).VARIABLES:
        if v.causality == "input" and v.type == "Real":
            x = rng.uniform(-0.3, 0.3, v.size)
            values[v.name] = x / np.linalg.norm(x) if v.name.startswith("q_") else x
    if name == "Flywheel":  # within the wheels' torque limit (else a warning at the start)
        values["tau_cmd"] *= 0.5
    if name == "DisturbanceTorques":  # the atmosphere and the field need a real height
        values.update(r_I=orbit.get("r_I"), v_I=orbit.get("v_I"))
    return values


#: run length [s] and the attitude columns compared between our master and another host
#: (libcosim, ECOS), per scenario
HOST_CASES = {
    "scan_pitch": (150.0, ["SatelliteDynamics.euler_BO[2]", "SatelliteDynamics.w_BO_B[2]"]),
    "payload_sweep": (
        150.0,
        [
            "SatelliteDynamics.euler_BO[1]",
            "SatelliteDynamics.euler_BO[2]",
            "SatelliteDynamics.euler_BO[3]",
            "SatelliteDynamics.w_BO_B[3]",
        ],
    ),
    "video_sar": (
        200.0,
        [
            "SatelliteDynamics.euler_BO[1]",
            "SatelliteDynamics.euler_BO[2]",
            "SatelliteDynamics.euler_BO[3]",
        ],
    ),
}


def export_elsewhere(tmp_path_factory) -> dict:
    """{scenario: .ssp}: each shipped scenario exported by the CLI, then moved to a
    directory outside the repository (as a user hands it to another host)."""
    import shutil

    from agilesat.orchestration.scenarios import NAMES

    elsewhere = tmp_path_factory.mktemp("elsewhere")
    result = {}
    for name in NAMES:
        built = tmp_path_factory.mktemp("export") / f"{name}.ssp"
        run = agilesat("export", name, "--out", built)
        assert run.returncode == 0, run.stderr
        result[name] = shutil.move(built, elsewhere / built.name)
    assert not str(elsewhere).startswith(str(ROOT))
    return result


class Stream(io.StringIO):
    """A text stream that says whether it is a terminal (``tty``): progress output either
    way."""

    def __init__(self, tty: bool):
        super().__init__()
        self.tty = tty

    def isatty(self):
        return self.tty


def pythonfmu_damper(folder: Path) -> Path:
    """A third party's FMU, made with pythonfmu alone (no units, no agilesat annotations):
    ``folder/Damper.fmu``, tau_cmd = -gain w_BI_B."""
    source = folder / "damper.py"
    source.write_text(
        "from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real\n"
        "class Damper(Fmi2Slave):\n"
        "    def __init__(self, **kw):\n"
        "        super().__init__(**kw)\n"
        "        self.gain, self.w = 5.0, [0.0, 0.0, 0.0]\n"
        "        self.register_variable(Real('gain', causality=Fmi2Causality.parameter,"
        " variability=Fmi2Variability.fixed))\n"
        "        for i in range(3):\n"
        "            self.register_variable(Real(f'w_BI_B[{i + 1}]', causality="
        "Fmi2Causality.input, getter=lambda i=i: self.w[i], setter=lambda v, i=i:"
        " self.w.__setitem__(i, v)))\n"
        "            self.register_variable(Real(f'tau_cmd[{i + 1}]', causality="
        "Fmi2Causality.output, getter=lambda i=i: -self.gain * self.w[i]))\n"
        "    def do_step(self, t, dt):\n"
        "        return True\n"
    )
    built = subprocess.run(
        [sys.executable, "-m", "pythonfmu", "build", "-f", source, "-d", folder],
        capture_output=True,
        text=True,
    )
    assert built.returncode == 0, built.stderr
    return folder / "Damper.fmu"
