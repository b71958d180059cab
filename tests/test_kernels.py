"""Compiled kernels (components/jit.py): the same results as the readable Python, a
switch back to it, and a compile cache that survives fresh FMU extractions."""

import json
import math

import numpy as np
import pytest
from test_c_host import host as c_host  # noqa: F401  (the C host fixture, compiled once)

from agilesat.components import cmg_cluster, jit, satellite_dynamics
from agilesat.components.cmg_cluster import CmgCluster
from agilesat.components.cmg_steering import CmgSteering
from agilesat.components.model import Model
from agilesat.components.satellite_dynamics import SatelliteDynamics
from agilesat.orchestration.scenarios import get as get_scenario
from helpers import run_python

needs_numba = pytest.mark.skipif(
    jit._numba() is None, reason="numba not installed or AGILESAT_JIT=0"
)


def _integrate_inputs(seed: int, n: int, gravity_gradient: bool):
    rng = np.random.default_rng(seed)
    J = np.diag([900.0, 950.0, 1000.0]) + rng.normal(scale=5.0, size=(3, 3))
    J = (J + J.T) / 2
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    vector = lambda scale: tuple((scale * rng.normal(size=3)).tolist())  # noqa: E731
    return (
        (*q.tolist(), *vector(50.0)),
        n,
        0.1 / n,
        vector(20.0),
        vector(1.0),
        vector(0.1),
        tuple((7e6 * rng.normal(size=3)).tolist()),
        tuple(map(tuple, J.tolist())),
        tuple(map(tuple, np.linalg.inv(J).tolist())),
        3.986004418e14,
        gravity_gradient,
    )


@needs_numba
@pytest.mark.parametrize("gravity_gradient", [False, True])
@pytest.mark.parametrize("seed, n", [(1, 1), (2, 3), (3, 17)])
def test_integration_kernel_is_bit_identical_to_the_python(seed, n, gravity_gradient):
    inputs = _integrate_inputs(seed, n, gravity_gradient)
    compiled = satellite_dynamics._integrate.compiled(*inputs)
    readable = satellite_dynamics._integrate.py_func(*inputs)
    assert compiled is not readable and type(satellite_dynamics._integrate.compiled) is not type(
        satellite_dynamics._integrate.py_func
    )
    assert type(compiled) is tuple and len(compiled) == 7
    assert compiled == readable
    assert compiled != inputs[0]  # it integrated something


def _spin_up(model: SatelliteDynamics, steps: int) -> np.ndarray:
    """A tumbling body (several sub-steps per step) with moving device momentum."""
    model.set("inertia", [[900.0, 12.0, -4.0], [12.0, 950.0, 7.0], [-4.0, 7.0, 1010.0]])
    model.set("rate0", [0.05, -0.4, 0.2])
    model.set("h_cmg", [3.0, -2.0, 1.0])
    model.start(0.0)
    rows = []
    for k in range(steps):
        model.set("hdot_cmg", [0.3 * math.sin(0.1 * k), 0.2, -0.1 * math.cos(0.05 * k)])
        model.set("tau_ext", [1e-3 * k, 0.0, -2e-3])
        model.advance(k * 0.05, 0.05)
        rows.append(model.values.copy())
    return np.array(rows)


def _gimbals(model: Model, steps: int) -> np.ndarray:
    """Random gimbal-rate commands (some beyond the rate limit) or steering inputs."""
    rng = np.random.default_rng(7)
    model.start(0.0)
    rows = []
    for k in range(steps):
        for v in model.layout.group("input"):
            model.set(v.name, rng.uniform(-0.8, 0.8, size=v.size))
        model.advance(k * 0.05, 0.05)
        rows.append(model.values.copy())
    return np.array(rows)


_RUNS = {
    SatelliteDynamics: (satellite_dynamics, _spin_up),
    CmgCluster: (cmg_cluster, _gimbals),
    CmgSteering: (cmg_cluster, _gimbals),
}


def _runs() -> str:
    return "".join(run(model(), 300).tobytes().hex() for model, (_, run) in _RUNS.items())


@needs_numba
@pytest.mark.parametrize("model", list(_RUNS), ids=lambda m: m.__name__)
def test_compiled_and_readable_model_runs_are_identical(model, monkeypatch):
    module, run = _RUNS[model]
    kernels = jit.kernels(module).values()
    assert kernels
    for kernel in kernels:
        monkeypatch.setattr(kernel, "_run", kernel.compiled)
    compiled = run(model(), 300)
    for kernel in kernels:
        monkeypatch.setattr(kernel, "_run", kernel.py_func)
    readable = run(model(), 300)
    assert np.array_equal(compiled, readable)
    assert np.all(np.ptp(compiled, axis=0)[model().layout.range["output"].start :] > 0)


_RUN_AS_TEXT = """
import os, sys
os.environ["AGILESAT_JIT_AFTER"] = "0"
{prelude}
sys.path.insert(0, "tests")
from agilesat.components import satellite_dynamics
from test_kernels import _runs
runs = _runs()
kernel = satellite_dynamics._integrate
print(kernel.compiled is kernel.py_func, kernel._run is kernel.py_func, "numba" in sys.modules)
print(runs)
"""
_NO_NUMBA = """
import importlib.abc
class _NoNumba(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.split(".")[0] in ("numba", "llvmlite"):
            raise ImportError("no numba here")
sys.meta_path.insert(0, _NoNumba())
"""


@pytest.mark.slow
@pytest.mark.parametrize(
    "prelude",
    ["import os; os.environ['AGILESAT_JIT'] = '0'", _NO_NUMBA],
    ids=["AGILESAT_JIT=0", "numba not installed"],
)
def test_without_the_compiler_the_readable_path_gives_the_same_results(prelude):
    result = run_python(_RUN_AS_TEXT.format(prelude=prelude))
    assert result.returncode == 0, result.stderr
    *switch, values = result.stdout.split()
    assert switch == ["True", "True", "False"]  # the Python ran; numba was not imported
    assert values == _runs()


_LOAD_EXTRACTED = """
import json, os, sys, tempfile
os.environ["AGILESAT_CACHE_DIR"] = sys.argv[2]
os.environ["AGILESAT_JIT_AFTER"] = "0"
import fmpy
folder = tempfile.mkdtemp(prefix="fmu_")
fmpy.extract(sys.argv[1], unzipdir=folder)
fmpy.simulate_fmu(folder, stop_time=1.0, output_interval=0.1)
module = next(m for n, m in sys.modules.items() if n.endswith(".components.satellite_dynamics"))
stats = module._integrate.compiled.stats
print(json.dumps({"folder": folder, "hits": len(stats.cache_hits),
                  "misses": len(stats.cache_misses), "path": stats.cache_path}))
"""


@pytest.mark.slow
@pytest.mark.integration
@needs_numba
def test_an_fmu_extracted_twice_compiles_its_kernels_once(fmus, tmp_path):
    """Two hosts unpack the FMU to two new folders: the first compiles, the second loads."""
    cache = tmp_path / "cache"
    loads = []
    for _ in range(2):
        result = run_python(_LOAD_EXTRACTED, fmus["SatelliteDynamics"], cache)
        assert result.returncode == 0, result.stderr
        loads.append(json.loads(result.stdout.splitlines()[-1]))
    first, second = loads
    assert first["folder"] != second["folder"]
    assert (first["misses"], first["hits"]) == (1, 0)  # compiled and saved
    assert (second["misses"], second["hits"]) == (0, 1)  # loaded, not compiled
    assert first["path"] == second["path"] and first["path"].startswith(str(cache))


_UNWRITABLE = """
import os, sys
os.environ["AGILESAT_CACHE_DIR"] = os.path.join(sys.argv[1], "cache")
os.environ["AGILESAT_JIT_AFTER"] = "0"
from agilesat.components import satellite_dynamics
from agilesat.components.satellite_dynamics import SatelliteDynamics
model = SatelliteDynamics().start(0.0).advance(0.0, 0.1)
print(len(satellite_dynamics._integrate.compiled.stats.cache_misses), model.get("q_BI").tolist())
"""


@pytest.mark.slow
@needs_numba
def test_an_unwritable_cache_costs_a_compile_and_says_so(tmp_path):
    (tmp_path / "a_file").write_text("not a directory")
    result = run_python(_UNWRITABLE, tmp_path / "a_file")
    assert result.returncode == 0, result.stderr
    assert "no compile cache for _integrate" in result.stderr
    misses, q = result.stdout.split(" ", 1)
    assert misses == "1"  # compiled in this process
    assert q.strip() == str(SatelliteDynamics().start(0.0).advance(0.0, 0.1).get("q_BI").tolist())


@needs_numba
def test_a_kernel_runs_its_python_until_the_threshold_then_the_compiled_function():
    tiered = jit.Kernel(satellite_dynamics._integrate.py_func, 3)
    inputs = [_integrate_inputs(seed, 2, True) for seed in range(6)]
    results = []
    for k, args in enumerate(inputs):
        results.append(tiered(*args))
        assert (tiered._run is tiered.compiled) == (k >= 3)
    assert results == [tiered.py_func(*args) for args in inputs]


_SHORT_RUN = """
import sys
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
simulate(get("scan_pitch").ssd, step=0.05, stop=5.0)
print("numba" in sys.modules)
"""


@pytest.mark.slow
@pytest.mark.integration
def test_a_short_run_does_not_import_numba(fmus):
    """Below the threshold the kernels' Python runs: no numba import, no compile load."""
    result = run_python(_SHORT_RUN)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["False"]


_IMPORTED_LATER = """
import os
os.environ["AGILESAT_JIT_AFTER"] = "0"
from agilesat.components.cmg_cluster import CmgCluster
CmgCluster().start(0.0).advance(0.0, 0.1)  # the first compile sets numba up
from agilesat.components import satellite_dynamics
satellite_dynamics.SatelliteDynamics().start(0.0).advance(0.0, 0.1)
print(satellite_dynamics._integrate._run is satellite_dynamics._integrate.compiled)
"""


@pytest.mark.slow
@needs_numba
def test_a_module_imported_after_the_first_compile_compiles_too():
    result = run_python(_IMPORTED_LATER)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["True"]


@pytest.mark.slow
@pytest.mark.integration
@needs_numba
def test_the_c_host_with_compiled_kernels_matches_the_master(fmus, c_host, tmp_path):  # noqa: F811
    """Kernels compiled from the first call in a host without Python (the FMUs' own
    interpreter) give the master's results (the kernels' Python) bit for bit."""
    import test_c_host as c

    ssd = get_scenario("scan_pitch").ssd
    c.write_script(ssd, tmp_path / "script.txt", tmp_path / "fmus", c.STOP)
    env = {**c.CLEAN_ENV, "AGILESAT_JIT_AFTER": "0"}
    run = c.run_host(c_host, tmp_path / "script.txt", tmp_path / "c.csv", env=env)
    assert run.returncode == 0, run.stderr
    names, data = c.read_csv(tmp_path / "c.csv")
    m_names, m_data = c.master_results(ssd, c.STOP, tmp_path / "master.npz")
    assert np.array_equal(data, m_data[:, [m_names.index(n) for n in names]])
