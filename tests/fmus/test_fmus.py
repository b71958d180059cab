"""Our FMUs as users get them: built, validated, and run by a plain host in a clean process."""

import json
import re
import zipfile

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu
from lxml import etree

from agilesat.components.satellite_dynamics import N_EXTRA
from agilesat.fmus import FMUS
from helpers import TOOLS, run_python

HOST = TOOLS / "fmi_host.py"


def host(command, *args):
    """Run tests/tools/fmi_host.py in a fresh interpreter; its JSON answer."""
    result = run_python(
        f"import runpy, sys; sys.argv = ['fmi_host', {command!r}] + "
        f"{[str(a) for a in args]!r}; runpy.run_path({str(HOST)!r}, "
        "run_name='__main__')"
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("name", FMUS)
def test_fmpy_validator_finds_no_problem(fmus, name):
    assert validate_fmu(str(fmus[name])) == []


@pytest.mark.parametrize("name", FMUS)
def test_every_variable_has_a_description_and_every_real_a_declared_unit(fmus, name):
    md = read_model_description(str(fmus[name]))
    units = {u.name for u in md.unitDefinitions}
    for v in md.modelVariables:
        assert v.description, v.name
        if v.type == "Real":
            assert v.unit in units, v.name


def test_model_structure_declares_the_dependencies_of_the_variable_tables(fmus):
    """What the built modelDescription.xml declares (measured: tests/fmus/test_feedthrough.py)."""
    md = read_model_description(str(fmus["SatelliteDynamics"]))
    deps = {u.variable.name: {d.name for d in u.dependencies} for u in md.outputs}
    rows = range(1, N_EXTRA + 1)
    frequency = {f"h_extra_frequency[{r},1]" for r in rows}
    # the states, and the rotating rows' steady response (θ̃ from ḣ, Ω) on the attitude
    jitter = {f"hdot_extra[{r},{i}]" for r in rows for i in (1, 2, 3)} | frequency
    assert deps["q_BI[1]"] == jitter and deps["H_I[2]"] == set()
    assert (
        deps["w_BI_B[1]"]
        == {f"h_{d}[{i}]" for d in ("cmg", "wheel", "payload") for i in (1, 2, 3)}
        | {f"h_extra[{r},{i}]" for r in rows for i in (1, 2, 3)}
        | frequency
    )
    assert deps["q_BO[1]"] == {f"q_OI[{i}]" for i in (1, 2, 3, 4)} | jitter
    cluster = read_model_description(str(fmus["CmgCluster"]))
    assert all(not u.dependencies for u in cluster.outputs)  # no feedthrough
    initial = {u.variable.name: {d.name for d in u.dependencies} for u in md.initialUnknowns}
    assert "h_cmg[1]" in initial["q_BI[1]"] and "attitude0[2]" in initial["q_BI[1]"]


def test_required_and_optional_inputs_are_declared_for_masters(fmus):
    with zipfile.ZipFile(fmus["SatelliteDynamics"]) as archive:
        root = etree.fromstring(archive.read("modelDescription.xml"))
    declared = {
        e.get("name"): e.get("optional")
        for e in root.iterfind(".//Tool[@name='agilesat']/Inputs/Input")
    }
    inputs = {v.get("name") for v in root.iterfind(".//ScalarVariable[@causality='input']")}
    assert set(declared) == inputs  # every input, one way or the other
    assert (
        declared["q_OI[1]"].startswith("identity:")
        and declared["h_cmg[3]"] == "zero: no cmg momentum"
    )
    with zipfile.ZipFile(fmus["CmgSteering"]) as archive:
        root = etree.fromstring(archive.read("modelDescription.xml"))
    required = {
        e.get("name")
        for e in root.iterfind(".//Tool[@name='agilesat']//Input")
        if e.get("optional") is None
    }
    assert "tau_cmd[1]" in required and "delta[6]" in required


@pytest.mark.slow
def test_identical_sources_build_an_identical_file(fmus, tmp_path):
    from agilesat.fmus.build import build_fmu

    again = build_fmu("CmgCluster", tmp_path, force=True)
    assert again.read_bytes() == fmus["CmgCluster"].read_bytes()


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("name", FMUS)
def test_state_save_step_restore_step_is_bit_identical(fmus, name):
    result = host("state", fmus[name])
    assert result["outputs_change"]  # the test would see a difference
    assert result["restored_identical"] and result["deserialized_identical"]


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("name", FMUS)
def test_bad_calls_return_fmi2Error_with_a_message_and_the_instance_survives(fmus, name):
    result = host("errors", fmus[name])
    bad = {k: v for k, v in result.items() if k not in ("messages",) and "valid" not in k}
    assert set(bad.values()) == {3}, bad  # fmi2Error, never Fatal
    assert result["valid_step_after_errors"] == 0 and result["valid_get_after_errors"] == 0
    text = "\n".join(result["messages"])
    for expected in (
        "step size must be positive",
        "time discontinuity",
        "unknown value references [1000000]",
        "not of type Integer",
        "cannot be set",
        "are fixed",
    ):
        assert expected in text
    if "nan_input" in result:
        assert re.search(r"non-finite values rejected: \['\w+(\[[0-9,]+\])?=nan'\]", text)


@pytest.mark.slow
@pytest.mark.integration
def test_all_fmus_and_two_instances_of_one_run_side_by_side(fmus):
    first = fmus["CmgCluster"]  # has inputs: its twin gets other values and must differ
    result = host("together", first, *(p for p in fmus.values() if p != first))
    assert result == {"all_ok": True, "instances": len(FMUS) + 1, "twin_differs": True}


@pytest.mark.slow
@pytest.mark.integration
def test_many_live_instances_exit_the_host_cleanly(fmus):
    """pythonfmu 0.7.0 corrupts the heap at exit (a double free); the shim prevents it."""
    for _ in range(4):
        assert host("many", fmus["CmgCluster"], 25) == {"instances": 25}


def doubled(fmu, out, rename: bool):
    """A copy of the CmgCluster FMU whose code doubles the singularity output.

    With ``rename`` its package gets a new name and the FMU the GUID that goes with it, as
    our build gives changed code; without, it keeps the original's module names, as
    pythonfmu's own build would.
    """
    from agilesat.fmus.protocol import fmu_guid

    with zipfile.ZipFile(fmu) as archive:
        entries = {i.filename: archive.read(i) for i in archive.infolist()}
    package = next(n.split("/")[1] for n in entries if n.startswith("resources/agilesat_"))
    digest = package.removeprefix("agilesat_")
    cmg = f"resources/{package}/components/cmg_cluster.py"
    entries[cmg] = entries[cmg].replace(
        b"values[Y.singularity] = det3(gram(free))",
        b"values[Y.singularity] = 2.0 * det3(gram(free))",
    )
    assert b"2.0 * det3" in entries[cmg]
    if rename:
        old, new = (fmu_guid("CmgCluster", d).encode() for d in (digest, digest + "x"))
        assert old in entries["modelDescription.xml"]
        entries["modelDescription.xml"] = entries["modelDescription.xml"].replace(old, new)
        entries = {
            name.replace(digest, digest + "x"): data.replace(
                digest.encode(), (digest + "x").encode()
            )
            if name.endswith((".py", ".txt"))
            else data
            for name, data in entries.items()
        }
    with zipfile.ZipFile(out, "w") as archive:
        for name, data in entries.items():
            archive.writestr(name, data)
    return out


@pytest.mark.slow
@pytest.mark.integration
def test_each_fmu_runs_the_code_packed_inside_it(fmus, tmp_path):
    original = fmus["CmgCluster"]
    ours = host("singularity", original, doubled(original, tmp_path / "a.fmu", rename=True))
    q = ours["singularity"]
    assert q[1] == pytest.approx(2 * q[0])
    # control: with pythonfmu's default naming the second FMU silently runs the first's code
    shared = host("singularity", original, doubled(original, tmp_path / "b.fmu", rename=False))
    assert shared["singularity"][1] == pytest.approx(shared["singularity"][0])


@pytest.mark.slow
@pytest.mark.integration
def test_host_modules_do_not_shadow_the_fmus_code(fmus):
    result = host("shadowed", fmus["CmgCluster"])
    assert result["host_patched"] == 123.0 and result["singularity"] != 123.0


def test_the_import_follower_reads_every_form_of_relative_import(tmp_path):
    from agilesat.fmus.build import _relative_imports

    for name in (
        "fmus/slave.py",
        "fmus/shim_util.py",
        "components/cmg_cluster.py",
        "components/analysis/__init__.py",
        "components/analysis/passes.py",
    ):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("")
    module = tmp_path / "fmus" / "wrapper.py"
    module.write_text(
        "from . import slave, shim_util\nfrom .slave import ModelSlave\n"
        "from ..components.cmg_cluster import CmgCluster\n"
        "from ..components.analysis import passes\n"
        "from ..components import analysis\n"
        "import math\nfrom numpy import pi\n"
    )
    assert sorted(_relative_imports("fmus/wrapper.py", module, tmp_path)) == [
        "components/__init__.py",
        "components/analysis/__init__.py",
        "components/analysis/__init__.py",
        "components/analysis/passes.py",
        "components/cmg_cluster.py",
        "fmus/__init__.py",
        "fmus/shim_util.py",
        "fmus/slave.py",
        "fmus/slave.py",
    ]


def test_the_fmus_are_the_same_built_by_python_or_python3_of_one_environment():
    """``.venv/bin/agilesat build`` runs the environment's ``python3``, ``.venv/bin/python
    -m pytest`` its ``python``: the same Python, so the same FMUs (they were stale for each
    other: the first test session after the README's build built all 14 again)."""
    import subprocess
    import sys
    from pathlib import Path

    code = "from agilesat.fmus.build import _sources; print(_sources('SweepPlanner')[1])"
    bin_dir = Path(sys.executable).parent
    digests = {
        name: subprocess.run(
            [str(bin_dir / name), "-c", code], capture_output=True, text=True, check=True
        ).stdout
        for name in ("python", "python3")
        if (bin_dir / name).exists()
    }
    assert len(digests) == 2 and len(set(digests.values())) == 1, digests
