"""Every AGILESAT_* environment variable is in one table (components/runtime/switches.py) and on
one page (docs/fast_paths.md), and a value it cannot take is a one-line message naming the
variable and what it accepts."""

import os
import re
import subprocess
import sys

import pytest

from agilesat.components.runtime.switches import SWITCHES, SwitchError, value
from helpers import ROOT, logged, slave

#: AGILESAT_* names that are not environment variables: include guards, a tool's name
#: header guards, an annotation's name, a define of the shim's build (not the environment)
NOT_SWITCHES = {
    "AGILESAT_FMI2_ABI_H",
    "AGILESAT_PROTOCOL_H",
    "AGILESAT_SHIM_H",
    "AGILESAT_TOOL",
    "AGILESAT_PYTHON_VERSION",
    "AGILESAT_PYTHON_MINIMUM",
}
NAME = re.compile(r"AGILESAT_[A-Z0-9_]*[A-Z0-9]")


def tracked_files():
    listed = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    for name in listed.stdout.splitlines():
        path = ROOT / name
        if path.suffix in (".py", ".c", ".h", ".md", ".toml", ".yml", ".yaml", "") and (
            path.is_file()
        ):
            yield path


def test_every_agilesat_variable_in_the_repository_is_in_the_table():
    found = {}
    for path in tracked_files():
        for name in NAME.findall(path.read_text(errors="replace")):
            found.setdefault(name, path.relative_to(ROOT))
    unknown = {name: str(path) for name, path in found.items() if name not in SWITCHES}
    assert set(unknown) <= NOT_SWITCHES, unknown
    assert set(SWITCHES) <= set(found)


def test_the_fast_paths_page_lists_exactly_the_switches():
    page = (ROOT / "docs" / "fast_paths.md").read_text()
    assert set(NAME.findall(page)) - NOT_SWITCHES == set(SWITCHES)


@pytest.mark.parametrize(
    "name, text, expected",
    [
        ("AGILESAT_JIT_AFTER", "soon", "a whole number >= 0"),
        ("AGILESAT_JIT_AFTER", "-1", "a whole number >= 0"),
        ("AGILESAT_JIT", "yes", "0 (off) or 1 (on)"),
        ("AGILESAT_SHIM_STEP", "off", "0 (off) or 1 (on)"),
        ("AGILESAT_LOOP", "fast", "auto, compiled or python"),
        ("AGILESAT_SSP_MAX_BYTES", "2.5", "a whole number >= 0"),
        (
            "AGILESAT_TEST_SIGNAL",
            "SIGTERM@end",
            "SIGNAL@step:K, SIGNAL@run:K, SIGNAL@worker:K or SIGNAL@figure:K, SIGNAL as SIGTERM",
        ),
    ],
)
def test_a_value_a_switch_cannot_take_names_the_variable_and_what_it_accepts(name, text, expected):
    with pytest.raises(SwitchError) as error:
        value(name, {name: text})
    assert str(error.value).startswith(f"{name}={text!r}: expected {expected} ({name}: ")


@pytest.mark.parametrize("name", sorted(SWITCHES))
def test_unset_or_empty_is_the_default(name):
    assert value(name, {}) == value(name, {name: ""}) == SWITCHES[name].default


# a scenario by name imports the kernels (which read the switch); a system file's FMUs read
# it only as they are instantiated: the command line checks every switch before either
@pytest.mark.parametrize("target", ["scan_pitch", "orchestration/systems/scan_pitch.ssd"])
def test_the_command_line_says_it_in_one_line_before_anything_runs(target, tmp_path):
    out = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, "-m", "agilesat.orchestration", "run", target, "--stop", "0.1"]
        + ["--no-figures", "--no-report", "--out", str(out)],
        capture_output=True,
        text=True,
        env={**os.environ, "AGILESAT_JIT_AFTER": "soon"},
        cwd=ROOT,
    )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [
        "agilesat run: error: AGILESAT_JIT_AFTER='soon': expected a whole number >= 0 "
        "(AGILESAT_JIT_AFTER: the calls of a kernel before it runs compiled, fewer where a "
        "run's length says it pays; 0: from the first call)"
    ]
    assert not out.exists()


def test_an_fmu_checks_the_shims_switches_at_the_handshake(monkeypatch):
    """The shim reads AGILESAT_SHIM_STEP itself (off with 0); the slave refuses the
    handshake on a value it cannot take, with the message: the shim's fast paths stay off."""
    from agilesat.fmus.protocol import FAST_PATH_N, FAST_PATH_VR

    monkeypatch.setenv("AGILESAT_SHIM_STEP", "off")
    fmu = slave("CmgCluster")
    assert fmu.get_real([FAST_PATH_VR] * FAST_PATH_N) == [0] * FAST_PATH_N
    assert logged(fmu) == [
        "CmgCluster 'test_CmgCluster': get_real: AGILESAT_SHIM_STEP='off': expected 0 (off) "
        "or 1 (on) (AGILESAT_SHIM_STEP: 0: the shim's C step path is off, its fast get/set "
        "stay on)"
    ]
