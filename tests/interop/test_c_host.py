"""Our FMUs in a plain C FMI 2.0 host (tests/tools/c_host/fmi2_host.c), as a C/C++ tool
loads them.

The host runs in an empty environment (no PYTHONPATH, no LD_PRELOAD, no virtualenv on
PATH): the FMU binary itself must load libpython and find numpy in the environment it
was built in.  Fed the master's own sequence of FMI calls (tests/tools/c_host/script.py), it
must reproduce the master's results bit for bit.
"""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from c_host.harness import CLEAN_ENV, STOP, master_results, read_csv, run_host
from c_host.script import write_script

from agilesat.orchestration.scenarios import NAMES, get
from helpers import ISS_TLE

pytestmark = [pytest.mark.slow, pytest.mark.integration]


@pytest.mark.parametrize("scenario", NAMES)
def test_the_c_host_reproduces_the_master_bit_for_bit(scenario, fmus, c_host, tmp_path):
    script = tmp_path / "script.txt"
    names = write_script(get(scenario).ssd, script, tmp_path / "fmus", STOP)
    run = run_host(c_host, script, tmp_path / "c.csv")
    assert run.returncode == 0, run.stderr
    c_names, c_data = read_csv(tmp_path / "c.csv")
    assert c_names == ["time", *names]
    m_names, m_data = master_results(get(scenario).ssd, STOP, tmp_path / "master.npz")
    assert len(c_data) == len(m_data) == round(STOP / 0.05) + 1
    master = m_data[:, [m_names.index(n) for n in c_names]]
    assert np.array_equal(c_data, master), np.nanmax(np.abs(c_data - master))


def test_a_real_satellites_orbit_through_the_c_host(fmus, c_host, tmp_path):
    """video_sar over an ISS pass: OrbitEnvironment runs SGP4 from the ``sgp4`` package,
    which only the build environment has: the C host's interpreter must be that
    environment's.  Bit-identical to the master on the same system."""
    from agilesat.orchestration.studies.stare import pass_scenario, tle_pass

    orbit, _, _ = tle_pass(*ISS_TLE)
    ssd = pass_scenario(orbit, tmp_path).ssd
    script = tmp_path / "script.txt"
    write_script(ssd, script, tmp_path / "fmus", 10.0)
    run = run_host(c_host, script, tmp_path / "c.csv")
    assert run.returncode == 0, run.stderr
    c_names, c_data = read_csv(tmp_path / "c.csv")
    m_names, m_data = master_results(ssd, 10.0, tmp_path / "master.npz")
    assert np.array_equal(c_data, m_data[:, [m_names.index(n) for n in c_names]])


def test_the_hosts_python_variables_do_not_reach_the_fmus_python(c_host, tmp_path, fmus):
    """A C host that sets PYTHONHOME/PYTHONPATH for its own reasons: ignored by the FMU."""
    script = tmp_path / "script.txt"
    write_script(get("scan_pitch").ssd, script, tmp_path / "fmus", 1.0)
    env = {**CLEAN_ENV, "PYTHONHOME": "/nonexistent", "PYTHONPATH": "/nonexistent"}
    run = run_host(c_host, script, tmp_path / "c.csv", env)
    assert run.returncode == 0, run.stderr


def test_an_environment_under_a_non_ascii_path(c_host, tmp_path, fmus):
    """The recorded environment's path is decoded as Python decodes paths, whatever the
    host's locale (an alias of the build environment under 'vé/')."""
    import sys
    import sysconfig

    venv = Path(sys.prefix)
    alias = tmp_path / "vé"
    (alias / "bin").mkdir(parents=True)
    (alias / "pyvenv.cfg").write_text((venv / "pyvenv.cfg").read_text())
    (alias / "bin" / "python").symlink_to(Path(sys.executable).resolve())
    (alias / "lib").symlink_to(venv / "lib")
    assert Path(sysconfig.get_paths()["purelib"]).is_relative_to(venv)
    script = tmp_path / "script.txt"
    write_script(get("scan_pitch").ssd, script, tmp_path / "fmus", 1.0)
    run = run_host(
        c_host,
        script,
        tmp_path / "c.csv",
        {**CLEAN_ENV, "LANG": "C", "AGILESAT_PYTHON": str(alias / "bin" / "python")},
    )
    assert run.returncode == 0, run.stderr


@pytest.fixture
def scan_pitch_script(fmus, tmp_path):
    script = tmp_path / "script.txt"
    write_script(get("scan_pitch").ssd, script, tmp_path / "fmus", 1.0)
    return script


def needs(version: str) -> str:
    """The part of the message every failure to start Python ends with: what the FMU needs
    (a Python 3.10 or later, its libpython and environment of one minor version), the
    Python it was built with and both variables."""
    return (
        r"This FMU runs Python 3\.10 or later with numpy \(it was built with Python "
        rf"{re.escape(version)}, {re.escape(sys.executable)}\): in a host that does not run "
        r"Python, set AGILESAT_LIBPYTHON to the shared libpython of a Python and "
        r"AGILESAT_PYTHON to the python of an environment of the same minor version with numpy"
    )


VERSION = "{}.{}".format(*sys.version_info)


def test_a_missing_python_environment_is_named(c_host, scan_pitch_script, tmp_path):
    env = {**CLEAN_ENV, "AGILESAT_PYTHON": str(tmp_path / "gone" / "bin" / "python")}
    run = run_host(c_host, scan_pitch_script, tmp_path / "c.csv", env)
    assert run.returncode == 2
    assert "fmi2Instantiate returned NULL" in run.stderr
    assert re.search(
        r"it runs Python as .*gone/bin/python, which does not exist here\. " + needs(VERSION),
        run.stderr,
    )


def test_a_python_without_numpy_is_named_once(c_host, scan_pitch_script, tmp_path):
    """An environment of the building Python without numpy (pythonfmu alone would say
    'findClass ModuleNotFoundError'): one message naming that Python and what is needed."""
    subprocess.run(
        [sys._base_executable, "-m", "venv", "--without-pip", tmp_path / "bare"], check=True
    )
    env = {**CLEAN_ENV, "AGILESAT_PYTHON": str(tmp_path / "bare" / "bin" / "python")}
    run = run_host(c_host, scan_pitch_script, tmp_path / "c.csv", env)
    assert run.returncode == 2
    assert "findClass" not in run.stderr and "ModuleNotFoundError" not in run.stderr
    assert re.search(
        r"the Python it runs in, .*bare/bin/python, has no numpy\. " + needs(VERSION), run.stderr
    ), run.stderr


def test_a_libpython_and_an_environment_of_two_versions_are_named(
    c_host, scan_pitch_script, tmp_path
):
    """The environment's pyvenv.cfg says another minor version than the libpython: named
    before Python starts (it would start with the other version's standard library)."""
    other = f"3.{sys.version_info.minor + 1}"
    env_dir = tmp_path / "other"
    (env_dir / "bin").mkdir(parents=True)
    (env_dir / "bin" / "python").symlink_to(Path(sys.executable).resolve())
    (env_dir / "pyvenv.cfg").write_text(f"home = /usr/bin\nversion = {other}.0\n")
    env = {**CLEAN_ENV, "AGILESAT_PYTHON": str(env_dir / "bin" / "python")}
    run = run_host(c_host, scan_pitch_script, tmp_path / "c.csv", env)
    assert run.returncode == 2
    assert re.search(
        rf"the libpython .* is Python {re.escape(VERSION)} and the environment of "
        rf".*other/bin/python is Python {re.escape(other)}\. " + needs(VERSION),
        run.stderr,
    ), run.stderr


def test_a_missing_libpython_is_named(c_host, scan_pitch_script, tmp_path):
    env = {**CLEAN_ENV, "AGILESAT_LIBPYTHON": str(tmp_path / "libpython3.so")}
    run = run_host(c_host, scan_pitch_script, tmp_path / "c.csv", env)
    assert run.returncode == 2
    assert re.search(
        r"cannot load the libpython .*libpython3.so \(.*\)\. " + needs(VERSION), run.stderr
    )


def test_an_error_mid_run_is_reported_and_the_rows_so_far_are_kept(
    c_host, scan_pitch_script, tmp_path
):
    """A NaN input at t = 1 s: fmi2Error from the FMU, named by the host; 21 rows kept."""
    lines = scan_pitch_script.read_text().splitlines()
    body = lines[
        lines.index(next(l for l in lines if l.startswith("loop"))) + 1 : lines.index("end") + 1
    ]
    k = next(
        l.split()[1] for l in lines if l.startswith("fmu") and l.endswith(" SatelliteDynamics")
    )
    vr = next(l.split()[3] for l in body if l.startswith(f"put {k} R"))
    lines[lines.index("end") + 1 : lines.index("end") + 1] = [
        f"set {k} R {vr} nan",
        "loop 1 1.0 0.05",
        *body,
    ]
    scan_pitch_script.write_text("\n".join(lines) + "\n")
    run = run_host(c_host, scan_pitch_script, tmp_path / "c.csv")
    assert run.returncode == 2
    assert re.search(r"\[SatelliteDynamics\] status 3 .*non-finite values rejected", run.stderr)
    assert "SatelliteDynamics: fmi2SetReal at t=1 returned status 3" in run.stderr
    assert len(read_csv(tmp_path / "c.csv")[1]) == 21


def two_hubs(fmus, directory: Path) -> Path:
    """Two components of one FMU file (two hubs turning at different rates, B carrying A's
    momentum as its wheels')."""
    from agilesat.orchestration.mission import System

    system = System("two_hubs", stop=2.0, step=0.05, algorithm="jacobi")
    system.add("A", fmus["SatelliteDynamics"], rate0=[0.01, -0.02, 0.03])
    system.add("B", fmus["SatelliteDynamics"], rate0=[-0.05, 0.0, 0.01])
    system.connect("A.H_I", "B.h_wheel")
    return system.write(directory / "two_hubs.ssd")


def test_two_components_of_one_fmu_file_in_a_host_that_reloads_it_per_instance(
    fmus, c_host, tmp_path
):
    """ECOS's loader closes and reopens an FMU's binary for each instance, while the
    instances made before live on.  The shim is linked NODELETE (fmus/build.py,
    shim_flags): the close unloads nothing, its registry of instances survives, and the run
    is the master's bit for bit (unloaded, the first instance's handle would be unknown to
    the reloaded shim)."""
    ssd = two_hubs(fmus, tmp_path)
    script = tmp_path / "script.txt"
    write_script(ssd, script, tmp_path / "fmus", 2.0)
    directories = {
        line.split()[2] for line in script.read_text().splitlines() if line[:4] == "fmu "
    }
    assert len(directories) == 1  # one binary, two instances
    run = run_host(c_host, script, tmp_path / "c.csv", CLEAN_ENV, "--reload-per-instance")
    assert run.returncode == 0, run.stderr
    c_names, c_data = read_csv(tmp_path / "c.csv")
    m_names, m_data = master_results(ssd, 2.0, tmp_path / "master.npz")
    assert np.array_equal(c_data, m_data[:, [m_names.index(n) for n in c_names]])
    pitch = [c_names.index(f"{k}.euler_BO[2]") for k in "AB"]
    assert c_data[-1, pitch[0]] != c_data[-1, pitch[1]]  # two instances, two motions
