"""The master's compiled loop (orchestration/cosim/loop.py, loop.c) against its Python loop:
the same results bit for bit, the same errors and rows kept, interrupts, the fall-back
when no compiler or cache is available, the content-keyed compile cache."""

import ctypes
import os
import re
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from agilesat.orchestration.cosim import derivatives, loop, master
from agilesat.orchestration.cosim.master import Interrupted, SimulationError, simulate
from agilesat.orchestration.output import recorder
from agilesat.orchestration.scenarios import NAMES, get
from agilesat.orchestration.system.ssp import read_system


def same_run(a, b) -> None:
    """Bit-identical columns; the same meta but for the loop that ran."""
    assert a.names == b.names and a.data.shape == b.data.shape
    for name in a.names:
        assert np.array_equal(a[name], b[name]), name
    assert a.data.tobytes() == b.data.tobytes()
    assert {**a.meta, "loop": None} == {**b.meta, "loop": None}


def both(system, **kwargs):
    python = simulate(system, loop="python", **kwargs)
    compiled = simulate(system, loop="compiled", **kwargs)
    assert (python.meta["loop"], compiled.meta["loop"]) == ("python", "compiled")
    return python, compiled


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_every_shipped_scenario_is_the_python_loop_bit_for_bit(fmus, name):
    same_run(*both(get(name).ssd))


def _multirate(fmus, tmp_path):
    scenario = get("scan_pitch").system.copy()
    for name in ("PitchManeuverController", "CmgSteering"):
        scenario.set_step(name, 0.1)
    path = tmp_path / "multirate.ssd"
    path.write_bytes(scenario.ssd({n: str(fmus[n]) for n in scenario.components}))
    return path


@pytest.mark.slow
@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
@pytest.mark.parametrize("rates", ["single", "multi"])
def test_both_algorithms_single_and_multi_rate_are_the_python_loop_bit_for_bit(
    fmus, tmp_path, algorithm, rates
):
    system = get("scan_pitch").ssd if rates == "single" else _multirate(fmus, tmp_path)
    step = 0.05 if rates == "single" else 0.025
    python, compiled = both(system, algorithm=algorithm, step=step, stop=30.0)
    same_run(python, compiled)
    if rates == "multi":
        assert compiled.meta["component_steps"] == {
            "PitchManeuverController": 0.1,
            "CmgSteering": 0.1,
        }


def _unwired(**kwargs):
    """scan_pitch without the ḣ wires: CmgCluster's h feeds the hub with its derivative."""
    system = read_system(get("scan_pitch").ssd)
    system.connections = [c for c in system.connections if not c.end_connector.startswith("hdot_")]
    return system


@pytest.mark.slow
@pytest.mark.parametrize(
    "algorithm, how", [("jacobi", "extrapolated"), ("gauss-seidel", "interpolated")]
)
def test_derivative_links_run_in_the_compiled_loop_bit_for_bit(fmus, algorithm, how):
    python, compiled = both(_unwired(), algorithm=algorithm, stop=20.0)
    assert compiled.meta["derivatives"] == [
        f"CmgCluster.h[{i}] -> SatelliteDynamics.h_cmg[{i}] ({how})" for i in (1, 2, 3)
    ]
    same_run(python, compiled)  # the Python loop passes the derivatives:
    if algorithm == "jacobi":  # without them, another run (Gauss-Seidel: none, it fails)
        plain = simulate(_unwired(), algorithm=algorithm, stop=20.0, derivatives=False)
        assert plain.data.tobytes() != compiled.data.tobytes()


@pytest.mark.slow
@pytest.mark.parametrize("call", ["fmi2GetRealOutputDerivatives", "fmi2SetRealInputDerivatives"])
def test_a_failing_derivative_call_gives_the_same_error_and_rows_with_both_loops(
    fmus, monkeypatch, call
):
    """The 30th call of CmgCluster's fmi2GetRealOutputDerivatives (or of the hub's
    fmi2SetRealInputDerivatives) returns fmi2Error, put in the FMU's library in place of
    the real one (both loops call the library's)."""
    prototype = ctypes.CFUNCTYPE(
        ctypes.c_int,
        ctypes.c_void_p,
        ctypes.POINTER(ctypes.c_uint),
        ctypes.c_size_t,
        ctypes.POINTER(ctypes.c_int),
        ctypes.POINTER(ctypes.c_double),
    )
    owner = "CmgCluster" if call.startswith("fmi2Get") else "SatelliteDynamics"
    real_init = derivatives.Derivatives.__init__

    def init(self, nodes, *args):
        real_init(self, nodes, *args)
        dll = nodes[owner].instance.slave.dll
        real, calls = getattr(dll, call), [0]

        def failing(component, vrs, n, orders, values):
            calls[0] += 1
            return 3 if calls[0] == 30 else real(component, vrs, n, orders, values)

        patch.setattr(dll, call, prototype(failing))

    outcome = []
    for which in ("python", "compiled"):
        with monkeypatch.context() as patch:
            patch.setattr(derivatives.Derivatives, "__init__", init)
            with pytest.raises(SimulationError) as error:
                simulate(_unwired(), algorithm="jacobi", stop=20.0, loop=which)
        outcome.append((str(error.value), error.value.results))
    (message, python), (message_c, compiled) = outcome
    assert f"{owner}: {call} at t=" in message
    assert message_c == message
    assert 2 < len(python) < 401
    same_run(python, compiled)


# -- failures ---------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_a_failing_step_gives_the_same_error_and_rows_with_both_loops(fmus, tmp_path, algorithm):
    """A hub with an absurd inertia: its fmi2DoStep returns fmi2Error mid-run (its
    message says the state is unphysical); rows written to files in both cases."""
    outcome = {}
    for which in ("python", "compiled"):
        (tmp_path / which).mkdir()
        with pytest.raises(SimulationError) as error:
            simulate(
                get("scan_pitch").ssd,
                parameters={"SatelliteDynamics.inertia[1,1]": 1e-4},
                algorithm=algorithm,
                out_dir=tmp_path / which,
                loop=which,
            )
        message = str(error.value).replace(str(tmp_path / which), "OUT")
        outcome[which] = (message, error.value.results, (tmp_path / which / "results.csv"))
    (message, python, csv), (message_c, compiled, csv_c) = outcome.values()
    assert "SatelliteDynamics: fmi2DoStep at t=" in message and "unphysical" in message
    assert message_c == message
    assert 2 < len(python) < 3001
    same_run(python, compiled)
    assert csv.read_text() == csv_c.read_text()


@pytest.mark.slow
@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_a_failing_set_gives_the_same_error_and_rows_with_both_loops(fmus, monkeypatch, algorithm):
    """CmgSteering's 40th fmi2SetReal (initialisation included) returns fmi2Error: an FMI
    function that fails, put in the port in place of fmpy's (both loops call the port's)."""
    prototype = ctypes.CFUNCTYPE(
        ctypes.c_int,
        ctypes.c_void_p,
        ctypes.POINTER(ctypes.c_uint),
        ctypes.c_size_t,
        ctypes.POINTER(ctypes.c_double),
    )
    real_init = master._Port.__init__

    def init(self, instance, type_, names, direction, index):
        real_init(self, instance, type_, names, direction, index)
        if instance.name == "CmgSteering" and self.call == "fmi2SetReal":
            real, calls = self.function, [0]

            def failing(component, vrs, n, values):
                calls[0] += 1
                return 3 if calls[0] == 40 else real(component, vrs, n, values)

            self.function = prototype(failing)

    monkeypatch.setattr(master._Port, "__init__", init)
    outcome = []
    for which in ("python", "compiled"):
        with pytest.raises(SimulationError) as error:
            simulate(get("scan_pitch").ssd, algorithm=algorithm, loop=which)
        outcome.append((str(error.value), error.value.results))
    assert "CmgSteering: fmi2SetReal at t=" in outcome[0][0]
    assert outcome[0][0] == outcome[1][0]
    assert 10 < len(outcome[0][1]) < 45  # mid-run
    same_run(outcome[0][1], outcome[1][1])


# -- interrupts -------------------------------------------------------------------------
@pytest.mark.slow
def test_a_signal_between_chunks_keeps_the_same_rows_with_both_loops(fmus):
    """SIGINT from the progress report at 30 % of the run: both loops stop right there."""

    def progress(done, total):
        if done == 30 * (total // 100):
            os.kill(os.getpid(), signal.SIGINT)

    kept = []
    for which in ("python", "compiled"):
        with pytest.raises(Interrupted, match="interrupted by SIGINT") as error:
            simulate(get("scan_pitch").ssd, progress=progress, loop=which)
        kept.append(error.value.results)
    assert len(kept[0]) == 30 * 30 + 1
    same_run(*kept)


@pytest.mark.slow
def test_a_signal_during_a_compiled_chunk_stops_the_run_and_keeps_its_rows(fmus, tmp_path):
    """SIGINT 50 ms after the first progress report (the run is going: no race with its
    start), inside a chunk of the C loop."""
    timer = threading.Timer(0.05, os.kill, (os.getpid(), signal.SIGINT))

    def progress(done, total):
        if not timer.is_alive() and not timer.finished.is_set():
            timer.start()

    try:
        with pytest.raises(Interrupted) as error:
            # 120,000 steps: seconds even with the kernels compiled (~30 µs a step)
            simulate(
                get("scan_pitch").ssd,
                stop=6000.0,
                out_dir=tmp_path,
                loop="compiled",
                progress=progress,
            )
    finally:
        timer.cancel()
    kept = error.value.results
    assert error.value.signal == signal.SIGINT and 1 < len(kept) < 120001
    assert kept.meta["loop"] == "compiled"
    assert len((tmp_path / "results.csv").read_text().splitlines()) == len(kept) + 1
    again = simulate(get("scan_pitch").ssd, stop=float(kept.time[-1]), loop="python")
    assert again.data.tobytes() == np.asarray(kept.data).tobytes()


def test_the_operations_are_numbered_as_in_loop_c():
    """loop.py builds the program, loop.c and Python run it: one numbering of the
    operations and of when they are due."""
    source = loop.SOURCE.read_text()
    enums = [
        [name.strip().split("=")[0].strip() for name in body.split(",")]
        for body in re.findall(r"enum \{([^}]*)\};", source)
    ]
    kinds, whens = enums
    assert [getattr(loop, name) for name in kinds] == list(range(len(kinds)))
    assert re.search(r"AT_STEP = 1, AT_READ = 2, AT_START = 4", source)
    assert (loop.AT_STEP, loop.AT_READ, loop.AT_START) == (1, 2, 4)
    assert whens == ["AT_STEP", "AT_READ", "AT_START"]


class _Instance:
    """What a program's operation holds of an FMU instance, without one."""

    def __init__(self, name):
        self.name, self.component, self.fmi2DoStep = name, None, None


def _jacobi(sources_of_b: list[int]):
    """A Jacobi program of FMUs a (output at place 0) and b (feedthrough: input from
    ``sources_of_b``, output at place 1), b read after a: b's step-phase set."""
    a, b = _Instance("a"), _Instance("b")
    vrs = (ctypes.c_uint * len(sources_of_b))(*range(len(sources_of_b)))
    a_out, b_out = (ctypes.c_uint * 1)(0), (ctypes.c_uint * 1)(0)

    class Node:
        def __init__(self, instance, inputs, outputs):
            self.instance, self.inputs, self.outputs, self.every = instance, inputs, outputs, 1

    def p(instance, call, vrs, index):  # a port (master._Port) of the operations' fields
        fields = dict(instance=instance, call=call, function=None, vrs=vrs, buffer=None)
        return type("Port", (), {**fields, "index": np.array(index)})()

    node_a = Node(a, [], [p(a, "fmi2GetReal", a_out, [0])])
    node_b = Node(b, [p(b, "fmi2SetReal", vrs, sources_of_b)], [p(b, "fmi2GetReal", b_out, [1])])
    reads = [(node_a, node_a.outputs, False), (node_b, node_b.outputs, True)]
    program = loop.Program.macro_step("jacobi", {"a": node_a, "b": node_b}, [], reads, 0.1)
    return [op for op in program.steps if op.instance is b and op.kind == loop.SET_REAL]


def test_jacobi_sets_a_feedthrough_fmus_inputs_again_only_where_they_may_have_changed():
    """b's inputs set for its read at t_{n+1} are still the newest at its next step when
    its sources are read before it (a): that set runs at the first step only; fed by its
    own output (read after the set), it runs at every step."""
    before, after = _jacobi([0])
    assert (before.when, after.when) == (loop.AT_START, loop.AT_READ)
    assert [before.due(n) for n in range(3)] == [True, False, False]
    before, after = _jacobi([0, 1])
    assert (before.when, after.when) == (loop.AT_STEP, loop.AT_READ)
    assert [before.due(n) for n in range(3)] == [True, True, True]


# -- building the loop ------------------------------------------------------------------
def test_without_a_compiler_or_a_writable_cache_the_loop_is_unavailable(tmp_path, monkeypatch):
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    with pytest.raises(loop.LoopUnavailable, match=r"cannot compile .*no-such-cc"):
        loop.library()
    monkeypatch.delenv("CC")
    (tmp_path / "file").write_text("")
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path / "file" / "cache"))
    with pytest.raises(loop.LoopUnavailable, match=r"cannot compile .* into .*file/cache"):
        loop.library()
    broken = tmp_path / "loop.c"
    broken.write_text(loop.SOURCE.read_text() + "\nthis is not C\n")
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path / "cache"))
    with pytest.raises(loop.LoopUnavailable, match=r"compiling .*loop.c with .* failed: "):
        loop.library(broken)


def test_the_loop_is_chosen_by_argument_or_environment(monkeypatch):
    monkeypatch.delenv("AGILESAT_LOOP", raising=False)
    assert loop.choose(None) == "auto" and loop.choose("python") == "python"
    monkeypatch.setenv("AGILESAT_LOOP", "python")
    assert loop.choose(None) == "python" and loop.choose("compiled") == "compiled"
    monkeypatch.setenv("AGILESAT_LOOP", "fast")
    with pytest.raises(
        ValueError, match=r"AGILESAT_LOOP='fast': expected auto, compiled or python"
    ):
        loop.choose(None)


@pytest.mark.slow
def test_without_a_compiler_the_python_loop_runs_with_a_note_and_the_same_results(
    fmus, tmp_path, monkeypatch
):
    compiled = simulate(get("scan_pitch").ssd, stop=10.0, loop="compiled")
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    fallback = simulate(get("scan_pitch").ssd, stop=10.0)
    assert fallback.meta["loop"] == "python"
    notes = [e for e in fallback.meta["log"] if e.instance == "master"]
    assert len(notes) == 1 and notes[0].status == 0
    assert notes[0].message.startswith("the Python loop runs this: cannot compile ")
    fallback.meta["log"].remove(notes[0])
    same_run(fallback, compiled)
    with pytest.raises(loop.LoopUnavailable, match="no-such-cc"):
        simulate(get("scan_pitch").ssd, stop=10.0, loop="compiled")
    monkeypatch.setenv("AGILESAT_LOOP", "python")  # asked for: no note
    chosen = simulate(get("scan_pitch").ssd, stop=1.0)
    assert chosen.meta["loop"] == "python"
    assert not [e for e in chosen.meta["log"] if e.instance == "master"]


@pytest.mark.slow
def test_the_cache_is_keyed_by_the_source(tmp_path, monkeypatch):
    monkeypatch.setenv("AGILESAT_CACHE_DIR", str(tmp_path))
    first = loop.library()
    changed = tmp_path / "loop.c"
    changed.write_text(loop.SOURCE.read_text() + "\n/* changed */\n")
    second = loop.library(changed)
    assert first is not second and first._name != second._name
    assert loop.library() is first
    names = sorted(os.path.basename(d._name) for d in (first, second))
    assert sorted(p.name for p in (tmp_path / "loop").iterdir()) == sorted(
        names + [f"{name}.sha256" for name in names]  # each checked before it is loaded
    )


@pytest.mark.slow
def test_processes_compiling_at_once_share_one_entry(tmp_path):
    script = (
        "import sys, time\n"
        "from agilesat.orchestration.cosim import loop\n"
        "time.sleep(max(0.0, float(sys.argv[1]) - time.time()))\n"
        "print(loop.library()._name)\n"
    )
    environment = {**os.environ, "AGILESAT_CACHE_DIR": str(tmp_path)}
    start = str(time.time() + 3.0)
    processes = [
        subprocess.Popen(
            [sys.executable, "-c", script, start],
            env=environment,
            stdout=subprocess.PIPE,
            text=True,
        )
        for _ in range(4)
    ]
    names = {p.communicate(timeout=120)[0].strip() for p in processes}
    assert all(p.returncode == 0 for p in processes)
    assert len(names) == 1
    name = os.path.basename(names.pop())
    assert sorted(p.name for p in (tmp_path / "loop").iterdir()) == [name, f"{name}.sha256"]


def test_the_csv_lines_formatted_in_c_are_what_the_recorder_writes_in_python():
    special = [0.0, -0.0, 1.0, -1.5, 1e-5, 1e-4, 1e15, 1e16, 5e-324, 2.2250738585072014e-308]
    special += [1.7976931348623157e308, float("inf"), -float("inf"), float("nan"), 0.1, 1 / 3]
    rng = np.random.default_rng(7)
    rows = rng.normal(size=(50, len(special))) * 10.0 ** rng.integers(-30, 30, (50, len(special)))
    rows = np.ascontiguousarray(np.vstack([special, rows]))
    expected = "".join(",".join(map(repr, row)) + "\n" for row in rows.tolist()).encode()
    dll = loop.library()
    assert loop.csv_text(dll, rows, ctypes.create_string_buffer(rows.size * 25)) == expected
    assert loop.csv_text(dll, rows, ctypes.create_string_buffer(100)) is None  # too small


# -- recording a chunk --------------------------------------------------------------------
def test_a_block_is_recorded_as_its_rows_one_by_one(tmp_path):
    rows = np.arange(400.0).reshape(100, 4) / 7
    for name in ("one", "block"):
        (tmp_path / name).mkdir()
    one = recorder.Recorder(list("tabc"), tmp_path / "one")
    for row in rows:
        one.append(row)
    for out in (tmp_path / "block", None):
        block = recorder.Recorder(list("tabc"), out)
        for k in range(0, 100, 30):
            block.append_block(rows[k : k + 30])
        assert block.rows == 100
        results, problems = block.close({})
        assert problems == [] and results.data.tobytes() == rows.tobytes()
    one.close({})
    assert (tmp_path / "one" / "results.csv").read_bytes() == (
        tmp_path / "block" / "results.csv"
    ).read_bytes()


def test_a_short_write_in_a_block_keeps_every_whole_row_that_fits(tmp_path, monkeypatch):
    rec = recorder.Recorder(["time", "a"], tmp_path)
    rows = np.array([[0.0, 1.0], [0.05, 2.0], [0.1, 3.0], [0.15, 4.0]])
    limit = len("time,a\n0.0,1.0\n0.05,2.0\n") + 3  # the disk fills inside the third row
    real_write = os.write

    def full(fd, data):
        room = limit - os.lseek(fd, 0, os.SEEK_CUR)
        if fd != rec.csv.fd or len(data) <= room:
            return real_write(fd, data)
        real_write(fd, bytes(data[:room]))
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(recorder.os, "write", full)
    with pytest.raises(OSError, match=r"results.csv: No space left on device; kept the 2 "):
        rec.append_block(rows)
    monkeypatch.undo()
    results, _ = rec.close({})
    assert (tmp_path / "results.csv").read_text() == "time,a\n0.0,1.0\n0.05,2.0\n"
    assert results.data.tobytes() == rows[:2].tobytes()
