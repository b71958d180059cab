"""The C entries compiled ahead of time into the FMU (fmus/native.py): every built FMU
whose model declares kernels carries them; a run steps them from its first step without
importing numba, bit for bit as the kernels' Python; a library that cannot be used here
(another numba, a damaged file) is said and left for numba's in-process compile."""

import hashlib
import json
import zipfile

import pytest

from agilesat.components.runtime import jit
from agilesat.fmus import FMUS, model_class, native
from helpers import run_python

LIBRARY = f"binaries/linux64/{native.LIBRARY}"
MANIFEST = f"binaries/linux64/{native.MANIFEST}"

RUN = """
import json, sys
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
base, _, variant = sys.argv[1].partition(":")
results = simulate(get(base).system_file(variant or None), stop=float(sys.argv[2]))
calls = {}  # the Python calls of each FMU model's declared step and output kernels
for name, module in sys.modules.items():
    if name.startswith("agilesat_") and name.endswith(".components.runtime.jit"):
        for model, roles in module._DECLARED.items():
            for role, kernel in roles.items():
                calls[model.__name__ + "." + role] = kernel.calls
print(json.dumps({"numba": "numba" in sys.modules, "calls": calls,
                  "data": results.data.tolist(), "names": list(results.names)}))
"""


def _run(system: str, stop: float, **env) -> dict:
    import os

    saved = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        done = run_python(RUN, system, stop)
    finally:
        for k, v in saved.items():
            os.environ.pop(k) if v is None else os.environ.__setitem__(k, v)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


def test_every_fmu_with_kernels_carries_its_entries(fmus):
    for name in FMUS:
        step, output = jit.declared(model_class(name))
        with zipfile.ZipFile(fmus[name]) as fmu:
            listed = set(fmu.namelist())
            if not (step or output):
                assert LIBRARY not in listed, name
                continue
            manifest = json.loads(fmu.read(MANIFEST))
        roles = {role for role, kernel in (("step", step), ("output", output)) if kernel}
        assert set(manifest["models"][model_class(name).__qualname__]) == roles, name
        assert LIBRARY in listed, name


@pytest.mark.slow
@pytest.mark.parametrize(
    "system, stop", [("scan_pitch", 3.0), ("payload_sweep", 3.0), ("video_sar:sensed", 3.0)]
)
def test_a_run_steps_the_fmus_library_from_its_first_step_bit_for_bit(fmus, system, stop):
    """Against the kernels' Python (without the library a run this short keeps it): the
    same rows bit for bit; the library's run calls no kernel's Python after the first step
    (which checks the inputs in the slave) and never imports numba."""
    native_run = _run(system, stop)
    python_run = _run(system, stop, AGILESAT_NATIVE="0")
    assert native_run["names"] == python_run["names"]
    assert native_run["data"] == python_run["data"]
    assert not native_run["numba"]
    steps = [k for k in native_run["calls"] if k.endswith(".step")]
    assert steps and all(native_run["calls"][k] <= 1 for k in steps), native_run["calls"]
    assert any(python_run["calls"][k] > 10 for k in steps)  # the Python did step there


def _another_numba(root):
    manifest = json.loads((root / MANIFEST).read_text())
    (root / MANIFEST).write_text(json.dumps({**manifest, "numba": "0.0"}))


def _damaged_library(root):
    data = (root / LIBRARY).read_bytes()
    (root / LIBRARY).write_bytes(data[:-1] + bytes([data[-1] ^ 1]))


def _edited_code(root):
    (source,) = root.glob("resources/agilesat_*/components/cmg_cluster.py")
    source.write_text(source.read_text() + "\n# edited after the build\n")


@pytest.mark.parametrize(
    "damage, said",
    [
        (_another_numba, "built with numba 0.0"),
        (_damaged_library, "SHA-256"),
        (_edited_code, "not the code it was built from"),
    ],
)
def test_a_library_that_cannot_be_used_is_said_and_numba_compiles(fmus, tmp_path, damage, said):
    with zipfile.ZipFile(fmus["CmgCluster"]) as fmu:
        fmu.extractall(tmp_path)
    damage(tmp_path)
    package = (tmp_path / "resources/slavemodule.txt").read_text().strip().split("_")[-1]
    done = run_python(
        """
import importlib, sys, warnings
sys.path.insert(0, sys.argv[1])
package = "agilesat_" + sys.argv[2]
model = importlib.import_module(package + ".components.cmg_cluster").CmgCluster
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    entries = importlib.import_module(package + ".fmus.c_entries").of(model)
print(entries.native, entries.step.address, "|".join(str(w.message) for w in caught))
""",
        tmp_path / "resources",
        package,
    )
    assert done.returncode == 0, done.stderr
    used, address, message = done.stdout.strip().split(" ", 2)
    assert used == "False" and address == "None"  # numba's, once a run pays for it
    assert said in message and "CmgCluster's kernels are compiled in this process" in message


@pytest.mark.slow
def test_numba_imported_after_the_libraries_shares_its_runtime_with_them(fmus):
    """The FMUs' libraries loaded numba's runtime extensions alone; numba imported later in
    the same process (a metric's kernel) initialises its own runtime again: both then
    allocate and free through it, and a second run gives the first's rows bit for bit."""
    done = run_python(
        """
import sys
import numpy as np
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
ssd = get("video_sar").system_file("sensed")
first = np.asarray(simulate(ssd, stop=10.0).data)
assert "numba" not in sys.modules
import numba
total = numba.njit(lambda n: (np.arange(n) * 0.5).sum())(1000)
again = np.asarray(simulate(ssd, stop=10.0).data)
print(total, np.array_equal(first, again))
"""
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["249750.0", "True"]


@pytest.mark.slow
def test_a_rebuild_takes_the_kept_library_and_a_damaged_one_is_compiled_again(
    fmus, tmp_path, monkeypatch
):
    """A build keeps an FMU's library in the cache by its content's hash; a rebuild of the
    same content gives the same FMU, from the kept library while it is whole, compiled
    again (and kept anew) once it is damaged."""
    from agilesat.fmus.build import build_fmu

    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path / "cache"))
    first = build_fmu("CmgCluster", tmp_path / "a", force=True).read_bytes()
    (kept,) = (tmp_path / "cache" / "native").iterdir()
    library = kept / native.LIBRARY
    assert build_fmu("CmgCluster", tmp_path / "b", force=True).read_bytes() == first
    library.write_bytes(b"damaged")
    assert build_fmu("CmgCluster", tmp_path / "c", force=True).read_bytes() == first
    manifest = json.loads((kept / native.MANIFEST).read_text())
    assert hashlib.sha256(library.read_bytes()).hexdigest() == manifest["sha256"]
