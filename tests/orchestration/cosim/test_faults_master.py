"""Faults of the master and its files: open inputs, bad settings, signals, kill -9, fatal,
disk full, parallel builds, hostile .ssp packages.

The cases of ``fault_cases_master.CASES`` run the CLI in fresh processes (slow); the rest
checks the pieces in this process without loading any FMU.
"""

import os
import re
import signal
import threading
from pathlib import Path

import fault_cases_master
import numpy as np
import pytest

from agilesat.orchestration.cosim import master
from agilesat.orchestration.cosim.plan import MAX_STEPS
from agilesat.orchestration.cosim.signals import at_step, signal_at, stop_on_signals
from agilesat.orchestration.output import recorder
from agilesat.orchestration.output.results import Results
from agilesat.orchestration.system.description import Description
from agilesat.orchestration.system.ssp import SystemFileError, read_system
from agilesat.orchestration.system.validation import check_system
from helpers import ROOT

SYSTEMS = sorted((ROOT / "orchestration" / "systems").glob("*.ssd"))


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("case", fault_cases_master.CASES, ids=lambda c: c.__name__)
def test_fault_case(fmus, case):
    result = case()
    if "skipped" in result:
        pytest.skip(result["skipped"])
    assert result["ok"], result


def _without(ssd: Path, index: int, directory: Path) -> Path:
    """A copy of ssd in directory without its index-th connection, FMU sources relative."""
    text = ssd.read_text()
    lines = text.splitlines(keepends=True)
    connections = [i for i, line in enumerate(lines) if "<ssd:Connection " in line]
    del lines[connections[index]]
    build = (ssd.parent / "../../fmus/build").resolve()
    text = "".join(lines).replace(
        'source="../../fmus/build/', f'source="{os.path.relpath(build, directory)}/'
    )
    path = directory / ssd.name
    path.write_text(text)
    return path


@pytest.mark.slow
@pytest.mark.parametrize("ssd", SYSTEMS, ids=lambda p: p.stem)
def test_removing_any_connection_is_an_error_or_a_listed_open_input(fmus, ssd, tmp_path):
    """Never silent: each single connection removed from each shipped system either makes
    the check (the run makes it before instantiating any FMU) fail naming file, component
    and input, or leaves an open optional input that the run lists with its meaning."""
    system = read_system(ssd)
    descriptions = {c.name: Description(c.name, c.source) for c in system.components}
    assert check_system(system, descriptions, system.parameters).open_inputs is not None
    baseline = {
        e["input"] for e in check_system(system, descriptions, system.parameters).open_inputs
    }
    outcomes = {"error": 0, "listed": 0}
    for index, c in enumerate(system.connections):
        path = _without(ssd, index, tmp_path)
        edited = read_system(path)
        variable = f"{c.end_element}.{c.end_connector.partition('[')[0]}"
        try:
            plan = check_system(edited, descriptions, edited.parameters)
        except SystemFileError as error:
            assert str(path) in str(error) and f"component {c.end_element}" in str(error)
            assert variable in str(error), (c, str(error))
            outcomes["error"] += 1
        else:
            listed = {e["input"]: e for e in plan.open_inputs}
            assert variable in listed and variable not in baseline, c
            assert listed[variable]["declared"] and listed[variable]["meaning"]
            outcomes["listed"] += 1
    assert sum(outcomes.values()) == len(system.connections) > 0


def test_simulate_rejects_a_zero_step_and_absurd_stop_times_before_loading_anything():
    ssd = ROOT / "orchestration" / "systems" / "scan_pitch.ssd"
    with pytest.raises(ValueError, match="macro step must be a positive, finite"):
        master.simulate(ssd, step=0)
    for stop in (float("inf"), float("nan"), -1.0):
        with pytest.raises(ValueError, match="stop time must be finite and after the start"):
            master.simulate(ssd, stop=stop)
    for step, stop in ((None, 1e9), (1e-320, None)):
        with pytest.raises(ValueError, match=f"more than the {MAX_STEPS}"):
            master.simulate(ssd, step=step, stop=stop)


CONNECTOR = '<ssd:Connector name="r_I[1]" kind="input">\n            <ssc:Real unit="m"/>'


@pytest.mark.slow
@pytest.mark.parametrize(
    "new, message",
    [
        (CONNECTOR.replace('"m"', '"km"'), "declared unit 'km', the FMU's variable has 'm'"),
        (
            CONNECTOR.replace('kind="input"', 'kind="output"'),
            "declared output, the FMU's variable is an input",
        ),
        (
            CONNECTOR.replace('<ssc:Real unit="m"/>', "<ssc:Integer/>"),
            "declared Integer, the FMU's variable is Real",
        ),
        (
            CONNECTOR.replace("r_I[1]", "r_I[9]"),
            "SatelliteDynamics (SatelliteDynamics.fmu) has no variable 'r_I[9]'",
        ),
    ],
)
def test_a_connector_that_disagrees_with_the_fmu_is_refused(fmus, tmp_path, new, message):
    ssd = ROOT / "orchestration" / "systems" / "scan_pitch.ssd"
    path = fault_cases_master.system_copy(tmp_path, lambda s: s.replace(CONNECTOR, new, 1))
    system = read_system(path)
    descriptions = {c.name: Description(c.name, c.source) for c in system.components}
    with pytest.raises(
        SystemFileError,
        match=r"scan_pitch.ssd:\d+: connector "
        r"SatelliteDynamics.r_I\[[19]\]: .*" + re.escape(message),
    ):
        check_system(system, descriptions, system.parameters)
    assert ssd.read_text().count(CONNECTOR) == 1


def test_a_connector_unit_is_read_from_the_ssd():
    system = read_system(ROOT / "orchestration" / "systems" / "scan_pitch.ssd")
    dynamics = system.component("SatelliteDynamics")
    declared = {c.name: c for c in dynamics.connectors}
    assert (declared["r_I[1]"].kind, declared["r_I[1]"].type, declared["r_I[1]"].unit) == (
        "input",
        "Real",
        "m",
    )


# ---------------------------------------------------------------------------------------
# signals


def test_signals_set_a_flag_while_inside_and_the_old_handlers_come_back():
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    with stop_on_signals() as stop:
        with stop_on_signals() as inner:
            assert inner is stop  # nested: one flag
        os.kill(os.getpid(), signal.SIGTERM)  # would end this process otherwise
        os.kill(os.getpid(), signal.SIGINT)  # would raise KeyboardInterrupt
        assert stop.signal == signal.SIGTERM  # the first: what stopped the run
    assert {s: signal.getsignal(s) for s in before} == before


def test_signal_handlers_are_left_alone_outside_the_main_thread():
    seen = []

    def worker():
        with stop_on_signals() as stop:
            seen.append((stop.signal, signal.getsignal(signal.SIGINT)))

    thread = threading.Thread(target=worker)
    thread.start()
    thread.join()
    assert seen == [(None, signal.default_int_handler)]


def test_a_test_signal_comes_once_at_the_first_report_at_or_after_its_step(monkeypatch):
    """$AGILESAT_TEST_SIGNAL=SIGNAL@step:K (the interruption tests' hook): the progress
    callback sends the signal at the first report >= K, once; the run's own callback
    still sees every report; other points (run, worker) are not a run's."""
    sent, seen = [], []
    monkeypatch.setattr(os, "kill", lambda pid, signum: sent.append((pid, signum)))
    monkeypatch.setenv("AGILESAT_TEST_SIGNAL", "SIGTERM@step:95")
    progress = at_step(lambda done, total: seen.append(done))
    for done in range(30, 300, 30):
        progress(done, 3000)
        assert len(sent) == (done >= 95)
    assert sent == [(os.getpid(), signal.SIGTERM)] and seen == list(range(30, 300, 30))
    monkeypatch.setenv("AGILESAT_TEST_SIGNAL", "SIGKILL@run:2")
    assert at_step(None) is None and signal_at("run") == (signal.SIGKILL, 2)
    for bad in ("SIGFOO@step:3", "SIGINT@step:x", "SIGINT@minute:3", "SIGINT"):
        monkeypatch.setenv("AGILESAT_TEST_SIGNAL", bad)
        with pytest.raises(ValueError, match="AGILESAT_TEST_SIGNAL"):
            signal_at("step")


# ---------------------------------------------------------------------------------------
# recorder


def test_each_row_is_in_the_file_once_appended_and_npz_matches(tmp_path):
    rec = recorder.Recorder(["time", "a", "b"], tmp_path)
    rows = np.arange(30.0).reshape(10, 3) / 7
    for k, row in enumerate(rows):
        rec.append(row)
        on_disk = (tmp_path / "results.csv").read_text().splitlines()
        assert len(on_disk) == k + 2 and on_disk[-1] == ",".join(map(repr, row.tolist()))
    results, problems = rec.close({"x": 1})
    assert problems == [] and np.array_equal(results.data, rows) and results.meta == {"x": 1}
    assert np.array_equal(Results.from_npz(tmp_path / "results.npz").data, rows)
    assert np.array_equal(Results.from_csv(tmp_path / "results.csv").data, rows)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.csv", "results.npz"]
    results.data[0, 0] = 99.0  # the caller's copy may be changed


def test_a_short_write_is_cut_back_to_the_last_whole_row(tmp_path, monkeypatch):
    rec = recorder.Recorder(["time", "a"], tmp_path)
    rec.append(np.array([0.0, 1.0]))
    real_write = os.write

    def full(fd, data):  # the disk fills mid-row
        if len(data) > 16 and fd == rec.csv.fd:
            real_write(fd, bytes(data[:5]))
            raise OSError(28, "No space left on device")
        return real_write(fd, data)

    monkeypatch.setattr(recorder.os, "write", full)
    with pytest.raises(OSError, match=r"results.csv: No space left on device; kept the 1 "):
        rec.append(np.array([0.1, 2.0 / 3.0]))
    monkeypatch.undo()
    results, _ = rec.close({})
    assert (tmp_path / "results.csv").read_text() == "time,a\n0.0,1.0\n"
    assert len(results) == 1 and np.array_equal(
        Results.from_npz(tmp_path / "results.npz").data, [[0.0, 1.0]]
    )


def test_without_an_output_directory_rows_stay_in_memory():
    rec = recorder.Recorder(["time", "a"])
    for k in range(200):
        rec.append(np.array([k, -k]))
    results, problems = rec.close({})
    assert problems == [] and results.data.shape == (200, 2) and results["a"][-1] == -199


@pytest.mark.parametrize("expected", [64, 7])
def test_in_memory_some_columns_kept_row_by_row_and_in_blocks(expected):
    # the buffer is as wide as the columns kept, not as all offered (was a broadcast error)
    rows = np.arange(40.0).reshape(8, 5)
    one = recorder.Recorder(list("tabcd"), keep=[0, 2, 3], every=2, expected=expected)
    for row in rows:
        one.append(row)
    block = recorder.Recorder(list("tabcd"), keep=[0, 2, 3], every=2, expected=expected)
    block.append_block(rows[:3])
    block.append_block(rows[3:])
    for rec in (one, block):
        results, problems = rec.close({})
        assert problems == [] and results.names == ["t", "b", "c"]
        assert np.array_equal(results.data, rows[::2][:, [0, 2, 3]])


def test_a_failed_npz_leaves_no_file_under_either_name(tmp_path):
    raw = tmp_path / "raw"
    raw.write_bytes(np.zeros(3).tobytes())
    with pytest.raises(OSError, match=r"results.npz: .*shorter than 2 rows; not written"):
        recorder.write_npz(tmp_path / "results.npz", ["time", "a", "b"], raw, 2, ["s", "", ""])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["raw"]


# ---------------------------------------------------------------------------------------
# .ssp packages (read only: nothing is loaded)


def _package(path, members):
    import zipfile

    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return path


@pytest.mark.parametrize(
    "members, kwargs, message",
    [
        (
            {"SystemStructure.ssd": b"x", "big": bytes(5000)},
            {"max_unpacked": 4000},
            "more than the limit of 4000",
        ),
        ({"SystemStructure.ssd": b"x", "/etc/x": b"x"}, {}, "member '/etc/x' would unpack outside"),
        ({"SystemStructure.ssd": b"x", "a/../../x": b"x"}, {}, "would unpack outside"),
    ],
)
def test_an_ssp_is_unpacked_within_bounds_or_refused(tmp_path, members, kwargs, message):
    with pytest.raises(SystemFileError, match=message):
        read_system(_package(tmp_path / "p.ssp", members), **kwargs)


def test_the_ssp_limit_has_a_documented_default_and_an_environment_override(tmp_path, monkeypatch):
    from agilesat.orchestration.system import ssp

    assert ssp.MAX_UNPACKED_BYTES == 256 * 2**20
    monkeypatch.setenv("AGILESAT_SSP_MAX_BYTES", "100")
    with pytest.raises(SystemFileError, match="more than the limit of 100 "):
        read_system(_package(tmp_path / "p.ssp", {"SystemStructure.ssd": bytes(200)}))


def test_ssp_sources_outside_the_package_are_refused(tmp_path):
    ssd = (ROOT / "orchestration" / "systems" / "scan_pitch.ssd").read_text()
    with pytest.raises(
        SystemFileError,
        match=r"component 'OrbitEnvironment': FMU source "
        r"'../../fmus/build/OrbitEnvironment.fmu' "
        "resolves outside the package",
    ):
        read_system(_package(tmp_path / "p.ssp", {"SystemStructure.ssd": ssd}))


def test_a_text_file_as_ssp_is_a_message(tmp_path):
    (tmp_path / "p.ssp").write_text("hello")
    with pytest.raises(SystemFileError, match="not an SSP package"):
        read_system(tmp_path / "p.ssp")


def test_a_long_problem_report_is_bounded(fmus):
    """30 copies of one connection: 30 problems counted, 20 printed, then how many more."""
    from agilesat.orchestration.system.validation import MAX_PROBLEMS_SHOWN

    system = read_system(ROOT / "orchestration" / "systems" / "scan_pitch.ssd")
    system.connections += [system.connections[0]] * 30
    descriptions = {c.name: Description(c.name, c.source) for c in system.components}
    with pytest.raises(SystemFileError) as error:
        check_system(system, descriptions, system.parameters)
    text = str(error.value)
    assert "30 problem(s)" in text and text.count("is already driven by") == MAX_PROBLEMS_SHOWN
    assert text.endswith(f"... and {30 - MAX_PROBLEMS_SHOWN} more of these kinds")


def test_a_file_that_cannot_be_written_is_named_and_no_temporary_is_left(tmp_path, monkeypatch):
    """A full disk or a read-only directory while a file is written under its temporary
    name: the error names the file (not the .partial), the temporary is gone and an older
    file of that name is untouched; an output directory that cannot be made is named."""
    target = tmp_path / "summary.json"
    target.write_text("old")

    def full(*args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(recorder.os, "replace", full)
    with pytest.raises(OSError, match=rf"^{target}: No space left on device; not written$"):
        recorder.write_text(target, "new")
    monkeypatch.undo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["summary.json"]
    assert target.read_text() == "old"
    (tmp_path / "a-file").write_text("")
    with pytest.raises(OSError, match=r"a-file/out: Not a directory \(the output directory"):
        recorder.make_directory(tmp_path / "a-file" / "out")


def test_a_journal_that_cannot_be_written_is_named(tmp_path):
    from agilesat.orchestration.campaign import engine

    class Full:
        name = str(tmp_path / "runs.jsonl")

        def write(self, line):
            raise OSError(28, "No space left on device")

    with pytest.raises(
        OSError, match=rf"{tmp_path / 'runs.jsonl'}: No space left on device; the runs"
    ):
        engine.journaled(Full(), "{}\n")
