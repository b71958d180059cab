"""Compiled kernels (components/runtime/jit.py): the tiers (the Python until a threshold or
a run's length says the compiled pays, a kernel numba cannot compile, no numba at all), a
switch back to the Python, the gimbal lock and the errors of the compiled hub, and a compile
cache that survives fresh FMU extractions.  Compiled against Python over every model:
tests/fast_paths/test_kernels_models.py."""

import json
import math
import re
import types

import numpy as np
import pytest

from agilesat.components import cmg_cluster, cmg_steering, rotations, satellite_dynamics
from agilesat.components.cmg_cluster import CmgCluster
from agilesat.components.cmg_steering import CmgSteering
from agilesat.components.model import Model, ModelError
from agilesat.components.runtime import jit
from agilesat.components.satellite_dynamics import SatelliteDynamics
from agilesat.fmus import fmu_state
from agilesat.orchestration.scenarios import get as get_scenario
from helpers import run_python

needs_numba = pytest.mark.skipif(
    jit._numba() is None, reason="numba not installed or AGILESAT_JIT=0"
)


def _random_dynamics(seed: int, gravity_gradient: bool, spin: float) -> SatelliteDynamics:
    """A SatelliteDynamics at a random state, parameters and inputs (|w| ~ ``spin``)."""
    rng = np.random.default_rng(seed)
    J = np.diag([900.0, 950.0, 1000.0]) + rng.normal(scale=5.0, size=(3, 3))
    model = SatelliteDynamics(inertia=(J + J.T) / 2, gravity_gradient=gravity_gradient)
    model.set("attitude0", rng.uniform(-3.0, 3.0, size=3))
    model.set("rate0", rng.normal(scale=spin, size=3))
    model.start(0.0)
    for v in model.layout.group("input"):
        model.set(v.name, rng.normal(scale=20.0, size=v.size))
    q = rng.normal(size=4)
    model.set("q_OI", q / np.linalg.norm(q))
    model.set("r_I", 7e6 * rng.normal(size=3))
    model.set("w_OI_O", 1e-3 * rng.normal(size=3))
    return model


@pytest.mark.slow
@needs_numba
def test_euler_angles_compiled_are_those_of_the_python_through_the_gimbal_lock():
    """euler123 / euler123_dot (rotations) compiled as in a kernel, on pitches across ±90°
    (the lock zone, and exact lock) from random previous angles."""
    numba = jit._numba()
    angles = numba.njit(lambda q, C, previous: rotations.euler123(q, C, previous, True))
    rates = numba.njit(rotations.euler123_dot)
    rng = np.random.default_rng(5)
    pitches = np.concatenate([np.linspace(-1.7, 1.7, 101), [math.pi / 2, -math.pi / 2]])
    zone = exact = 0
    half = math.sqrt(0.5)
    for pitch in pitches:
        euler = (rng.uniform(-3, 3), pitch, rng.uniform(-3, 3))
        q = tuple(rotations.quat_from_euler123(euler).tolist())
        if pitch == pitches[-1]:
            q = (half, 0.0, -half, 0.0)  # pitch -90° exactly
        C = rotations.dcm(q)
        previous = tuple((np.array(euler) + rng.normal(scale=0.3, size=3)).tolist())
        readable = rotations.euler123(q, C, previous, True)
        assert angles(q, C, previous) == readable
        w = tuple(rng.normal(size=3).tolist())
        assert rates(readable, w) == rotations.euler123_dot(readable, w)
        zone += abs(math.cos(readable[1])) < rotations.LOCK_ZONE_COS
        exact += abs(math.cos(readable[1])) <= rotations.GIMBAL_LOCK_COS
    assert zone >= 3 and exact >= 1  # the lock zone was crossed, exact lock reached


@pytest.fixture(params=[pytest.param("compiled", marks=pytest.mark.slow), "python"])
def dynamics_kernels(request, monkeypatch):
    """SatelliteDynamics' kernels run compiled (numba; the slow layer: compiled first on a
    fresh machine) or as their Python."""
    if request.param == "compiled" and jit._numba() is None:
        pytest.skip("numba not installed or AGILESAT_JIT=0")
    for kernel in jit.kernels(satellite_dynamics).values():
        attribute = "compiled" if request.param == "compiled" else "py_func"
        monkeypatch.setattr(kernel, "_run", getattr(kernel, attribute))
    return request.param


@pytest.mark.parametrize(
    "inputs, message",
    [
        (
            {"r_I": [0.0, 0.0, 0.0]},
            "^gravity_gradient is on but r_I is zero: connect r_I or set gravity_gradient = false$",
        ),
        (
            {"h_cmg": [0.0, 0.0, -4e5]},
            r"^t=2 s: body rate 418 rad/s would need 1046\d sub-steps "
            r"of 0.5 s: the state is unphysical$",
        ),
        ({"h_cmg": [math.nan, 0.0, 0.0]}, r"^t=2 s: body rate nan rad/s would need nan sub-steps"),
        ({"tau_ext": [math.inf, 0.0, 0.0]}, r"^non-finite state at t=2.5 s$"),
        (
            {"q_OI": [0.0, 0.0, 0.0, 0.0]},
            r"^q_OI must be a unit quaternion, got \[0.0, 0.0, 0.0, "
            r"0.0\] \(norm 0.0\)$",
        ),
    ],
    ids=["no r_I", "too many sub-steps", "nan rate", "non-finite state", "q_OI"],
)
def test_each_error_of_the_kernels_is_raised_with_its_message(inputs, message, dynamics_kernels):
    model = SatelliteDynamics(rate0=[0.01, 0.02, 0.0]).start(0.0).advance(0.0, 2.0)
    for name, value in inputs.items():
        model.set(name, value)
    values, state = model.values.copy(), model.state.copy()
    with pytest.raises(ModelError) as error:
        model.output() if "q_OI" in inputs else model.step(2.0, 0.5)  # q_OI: output's check
    assert re.search(message, str(error.value)), error.value
    assert np.array_equal(model.values, values, equal_nan=True)  # nothing changed
    assert np.array_equal(model.state, state)


def test_inputs_set_after_initialisation_are_still_caught(dynamics_kernels):
    model = SatelliteDynamics()
    model.initialize(0.0)  # as an FMU does: the first step checks the inputs it used
    model.set("q_OI", [0.6, 0.8, 0.0, 0.0])
    with pytest.raises(ModelError, match=r"^at the first step the inputs \['q_OI'\] are not"):
        model.step(0.0, 0.05)


def test_a_saved_state_restores_the_run_bit_for_bit(dynamics_kernels):
    """get_state / set_state through the FMU state's bytes (fmus/fmu_state.py)."""
    model = _random_dynamics(4, True, 0.3)

    def run(steps):
        rows = []
        for k in range(steps):
            model.set("tau_ext", [1e-3 * k, -2e-3, 0.0])
            model.advance(k * 0.1, 0.1)
            rows.append(model.values.copy())
        return np.array(rows)

    run(20)
    saved = fmu_state.encode("test", model.get_state(), "agilesat")
    first = run(30)
    model.set_state(fmu_state.decode("test", saved, "agilesat"))
    assert np.array_equal(run(30), first)


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
    CmgSteering: (cmg_steering, _gimbals),
}


def _runs() -> str:
    return "".join(run(model(), 300).tobytes().hex() for model, (_, run) in _RUNS.items())


_RUN_AS_TEXT = """
import os, sys
os.environ["AGILESAT_JIT_AFTER"] = "0"
{prelude}
sys.path[:0] = ["tests/fast_paths", "tests"]
from agilesat.components import satellite_dynamics
from test_kernels import _runs
runs = _runs()
kernel = satellite_dynamics._step
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
stats = module._step.compiled.stats
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
from agilesat.fmus import fmu_state
model = SatelliteDynamics().start(0.0).advance(0.0, 0.1)
print(len(satellite_dynamics._step.compiled.stats.cache_misses), model.get("q_BI").tolist())
"""


@pytest.mark.slow
@needs_numba
def test_an_unwritable_cache_costs_a_compile_and_says_so(tmp_path):
    (tmp_path / "a_file").write_text("not a directory")
    result = run_python(_UNWRITABLE, tmp_path / "a_file")
    assert result.returncode == 0, result.stderr
    assert "no compile cache for _step" in result.stderr
    misses, q = result.stdout.split(" ", 1)
    assert misses == "1"  # compiled in this process
    assert q.strip() == str(SatelliteDynamics().start(0.0).advance(0.0, 0.1).get("q_BI").tolist())


@needs_numba
def test_a_kernel_runs_its_python_until_the_threshold_then_the_compiled_function():
    tiered = jit.Kernel(satellite_dynamics._step.py_func, 3)
    models = [_random_dynamics(seed, True, 0.3) for seed in range(6)]
    states = [m.state.copy() for m in models]
    results = []
    for k, model in enumerate(models):
        results.append(tiered(model.values, model.state, 0.0, 0.1))
        assert (tiered._run is tiered.compiled) == (k >= 3)
    expected = [tiered.py_func(m.values, state, 0.0, 0.1) for m, state in zip(models, states)]
    assert results == expected
    assert all(np.array_equal(m.state, state) for m, state in zip(models, states))


def _not_jitable(x):  # a plain function kernels may not call (no @jitable)
    return x + 1.0


def _calls_a_plain_function(x):
    return 2.0 * _not_jitable(x)


@needs_numba
def test_a_kernel_numba_cannot_compile_keeps_its_python_and_says_so():
    tiered = jit.Kernel(_calls_a_plain_function, 1)
    assert tiered(1.0) == 4.0  # the Python
    with pytest.warns(UserWarning, match=r"_calls_a_plain_function could not be compiled \(Typing"):
        assert tiered(2.0) == 6.0
    assert tiered._run is tiered.compiled is tiered.py_func
    assert not jit.runs_compiled(tiered)  # no C entry: the FMU's C path stays off
    assert tiered(3.0) == 8.0


_SHORT_RUN = """
import os, sys
os.environ.pop("AGILESAT_JIT_AFTER", None)  # the default threshold
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
print(satellite_dynamics._step._run is satellite_dynamics._step.compiled)
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
def test_the_c_host_with_compiled_kernels_matches_the_master(fmus, c_host, tmp_path):
    """Kernels compiled from the first call in a host without Python (the FMUs' own
    interpreter) give the master's results (the kernels' Python) bit for bit."""
    from c_host import harness as c
    from c_host.script import write_script

    ssd = get_scenario("scan_pitch").ssd
    write_script(ssd, tmp_path / "script.txt", tmp_path / "fmus", c.STOP)
    env = {**c.CLEAN_ENV, "AGILESAT_JIT_AFTER": "0"}
    run = c.run_host(c_host, tmp_path / "script.txt", tmp_path / "c.csv", env=env)
    assert run.returncode == 0, run.stderr
    names, data = c.read_csv(tmp_path / "c.csv")
    m_names, m_data = c.master_results(ssd, c.STOP, tmp_path / "master.npz")
    assert np.array_equal(data, m_data[:, [m_names.index(n) for n in names]])


def test_a_models_tier_is_decided_by_its_own_kernels_alone(monkeypatch):
    """A kernel of the model's module that the model does not declare (a metric's, run on
    a run's history) neither holds back nor moves the model's switch: its compiled code
    is not in the FMU's cache, and need not be."""
    monkeypatch.setattr(jit, "_DECLARED", {})
    monkeypatch.setattr(jit, "ENABLED", True)
    monkeypatch.setattr(jit, "RUNS", 0)
    module = types.ModuleType("a_model_module")

    class Modelled:
        pass

    Modelled.__module__ = module.__name__
    module.model_step = jit.Kernel(lambda values, state, t, dt: 0, 10**9)
    module.history = jit.Kernel(lambda rows: 0, 10**9)
    jit._DECLARED[Modelled] = {"step": module.model_step}
    monkeypatch.setattr(jit, "cached", lambda kernel: kernel is module.model_step)
    jit.expect(module, jit.PAYS_AFTER)
    assert module.model_step._left == 0  # compiled from the run's first step
    assert module.history._left == 10**9
    jit.expect_rows(module.history, jit.PAYS_AFTER - 1)  # a short history: its Python
    assert module.history._left == 10**9


_TIER = """
import os, sys
os.environ["AGILESAT_CACHE_DIR"] = sys.argv[1]
os.environ["AGILESAT_NATIVE"] = "0"  # the FMUs' own compiled entries decide nothing
if len(sys.argv) > 3:
    os.environ["AGILESAT_JIT_RUNS"] = sys.argv[3]
from agilesat.orchestration import simulate
from agilesat.orchestration.scenarios import get
for stop in sys.argv[2].split(","):
    simulate(get("scan_pitch").ssd, stop=float(stop))
    # the most calls a kernel of the FMUs made of its Python; -1: numba not imported
    modules = [m for n, m in list(sys.modules.items()) if n.startswith("agilesat_")]
    jits = {m.__name__.split(".")[0]: m for m in modules if m.__name__.endswith(".jit")}
    calls = [k.calls for m in modules if ".components." in m.__name__
             for k in jits[m.__name__.split(".")[0]].kernels(m).values()]
    print(max(calls) if "numba" in sys.modules else -1)
"""


def _tier(cache, stops: str, runs: str = "") -> list[int]:
    result = run_python(_TIER, cache, stops, *([runs] if runs else []))
    assert result.returncode == 0, result.stderr
    return [int(x) for x in result.stdout.split()]


@pytest.mark.slow
@pytest.mark.integration
@needs_numba
def test_the_tier_is_decided_at_the_first_step_from_the_runs_length(fmus, tmp_path):
    """Without the FMUs' ahead-of-time entries (AGILESAT_NATIVE=0, tests/fast_paths/
    test_native.py): with the compiled code cached, a run expected to take PAYS_AFTER steps
    or more runs compiled from its first step; a shorter one runs the Python (no numba
    import), unless the process made runs before (a notebook) or expects several
    (AGILESAT_JIT_RUNS, a campaign worker); with nothing cached, only from AFTER steps."""
    cache = str(tmp_path / "cache")
    seconds = jit.PAYS_AFTER * 0.05  # of scan_pitch at its step
    short, long = round(0.6 * seconds), round(1.1 * seconds)
    assert _tier(cache, f"{long}") == [-1]  # nothing cached: the Python
    fill = "import os\nos.environ['AGILESAT_JIT_AFTER'] = '0'\n" + _TIER
    assert run_python(fill, cache, "1").returncode == 0  # compiles, and caches
    assert _tier(cache, f"{short}") == [-1]  # too short to pay: the Python
    first_outputs = 3  # outputs evaluated in initialisation, before the first step
    assert _tier(cache, f"{long}") == [first_outputs]  # compiled from the first step
    steps = round(short / 0.05)
    assert _tier(cache, f"{short},{short}")[1] <= steps + 2 * first_outputs  # from its start
    assert _tier(cache, f"{short}", "2") == [first_outputs]  # a worker of two runs
