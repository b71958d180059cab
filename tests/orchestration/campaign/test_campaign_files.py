"""A campaign's own files read back (``campaign/files.py``, ``engine.py``): damaged ones
named with their line, the system's content hash, kept signals never shrunk.  Whole
campaigns on damaged files: ``tests/tools/fault_cases_campaign.py``."""

import json
import signal

import numpy as np
import pytest

from agilesat.orchestration.campaign import engine
from agilesat.orchestration.campaign.files import (
    CampaignFileError,
    changed,
    read_object,
    system_content,
)
from agilesat.orchestration.campaign.plan import Plan, Spec

RECORD = {"index": 0, "status": "ok", "metrics": {}}


def test_the_journal_names_a_line_that_is_not_a_run_record(tmp_path):
    journal = tmp_path / "runs.jsonl"
    good = [json.dumps({**RECORD, "index": k}) + "\n" for k in range(3)]
    journal.write_text("".join(good) + '{"index": 3, "sta')  # cut short by a kill: dropped
    assert sorted(engine.read_journal(journal)) == [0, 1, 2]
    for k, bad in enumerate(
        ["not json\n", '{"index": "1", "metrics": {}}\n', '{"index": -1}\n', "[1]\n", "{}\n"]
    ):
        journal.write_text(good[0] + bad + good[2])
        with pytest.raises(CampaignFileError, match=rf"{journal}:2: not a run record"):
            engine.read_journal(journal)


@pytest.mark.parametrize(
    "text, message",
    [
        ("[]", "expected a campaign's summary with spec, got a list"),
        ('{"status": "running"}', "with spec, got a dict with \\['status'\\]"),
        ('{"spec": ', "not JSON"),
    ],
)
def test_a_damaged_summary_is_named(tmp_path, text, message):
    (tmp_path / "campaign.json").write_text(text)
    with pytest.raises(CampaignFileError, match=message):
        read_object(tmp_path / "campaign.json", "a campaign's summary", ("spec",))


def test_the_content_of_the_system_and_its_fmus_is_recorded(fmus, tmp_path):
    plan = Plan(Spec("scan_pitch"))
    content = system_content(plan)
    assert len(content) == 1 + len(plan.system.components)
    assert str(plan.system.path) in content
    assert "the FMU of CmgCluster (CmgCluster.fmu)" in content
    edited = dict(content, **{str(plan.system.path): "0" * 64})
    assert changed(content, edited) == [str(plan.system.path)] and changed(content, content) == []


def test_kept_signals_grow_with_the_campaign_and_never_shrink(fmus, tmp_path):
    spec = Spec("scan_pitch", runs=4, keep=["SatelliteDynamics.w_BO_B[2]"], stop=1.0)
    memory = engine.signals_file(Plan(spec), tmp_path)
    memory[:] = np.arange(memory.size, dtype=float).reshape(memory.shape)
    memory.flush()
    kept = np.array(memory)
    del memory
    fewer = engine.signals_file(Plan(Spec(**{**spec.to_dict(), "runs": 2})), tmp_path)
    assert np.array_equal(fewer, kept)  # runs 2 and 3 keep theirs
    del fewer
    more = engine.signals_file(Plan(Spec(**{**spec.to_dict(), "runs": 6})), tmp_path)
    assert more.shape[0] == 6 and np.array_equal(more[:4], kept) and np.isnan(more[4:]).all()


def test_kept_signals_start_as_nan_to_the_last_byte_written_a_block_at_a_time(
    fmus, tmp_path, monkeypatch
):
    """Blocks of 64 bytes (eight values) that do not divide the file: every value NaN."""
    monkeypatch.setattr(engine, "FILL_CHUNK", 64)
    spec = Spec("scan_pitch", runs=3, keep=["SatelliteDynamics.w_BO_B[2]"], stop=1.0)
    memory = engine.signals_file(Plan(spec), tmp_path)
    assert memory.size % 8 and np.isnan(memory).all()
    assert np.isnan(np.load(tmp_path / "signals.npy")).all()


@pytest.mark.parametrize(
    "held,why",
    [
        ({"command": "c", "metrics": {"m": 1.5}}, None),
        ({"command": "c", "reason": "the run stopped"}, "has no metrics (the run stopped)"),
        ({"command": "c"}, "has no metrics"),
        ("a text", "has no metrics"),
        ({"command": "c", "metrics": [1.5]}, "has no metrics"),
        ({"command": "c", "metrics": {"m": "1.5", "n": True, "k": 2}}, "not numbers (m, n)"),
        ({"command": "c", "metrics": {"m": float("nan")}}, "not numbers (m)"),
        ({"command": "d", "metrics": {"m": 1.5}}, "was another command (d)"),
    ],
)
def test_a_nominal_run_in_campaign_json_is_kept_only_if_it_is_this_one(held, why):
    from agilesat.orchestration.campaign.nominal import _not_this_nominal_run
    from agilesat.orchestration.campaign.replay import versions

    said = _not_this_nominal_run(held, "c", versions())
    assert said is None if why is None else why in said
    if why is None:
        assert "(numpy)" in _not_this_nominal_run(held, "c", {**versions(), "numpy": "0"})


def test_a_run_journaled_twice_is_named_with_both_lines(tmp_path):
    """Two outcomes of one run (two campaigns that wrote one journal): which is it?"""
    journal = tmp_path / "runs.jsonl"
    lines = [json.dumps({**RECORD, "index": k}) + "\n" for k in (0, 1, 0)]
    journal.write_text("".join(lines))
    with pytest.raises(
        CampaignFileError, match=rf"{journal}:3: run 0 is recorded again \(first on line 1\)"
    ):
        engine.read_journal(journal)


def test_the_code_a_campaign_runs_is_recorded_and_a_change_named(tmp_path, monkeypatch):
    """A module loaded from outside the Python installation and the toolkit (a mission's
    constants beside it) is in the content; editing it, or the toolkit's sources, is named;
    modules loaded since are not compared (the process's doing, not the campaign's)."""
    import importlib
    import sys

    from agilesat.orchestration.campaign import files

    (tmp_path / "probe_constants.py").write_text("RATE = 0.01\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.import_module("probe_constants")
    try:
        content = files.code_content()
        module = str((tmp_path / "probe_constants.py").resolve())
        assert content[module] and files.TOOLKIT in content
        assert not any("site-packages" in k or "/lib/python" in k for k in content)
        assert not any(k.startswith(str(files._toolkit_dirs()[0])) for k in content)
        assert files.code_changed(content) == []
        (tmp_path / "probe_constants.py").write_text("RATE = 0.02\n")
        assert files.code_changed(content) == [module]
        monkeypatch.setattr(files, "toolkit_digest", lambda: "0.1.0 edited")
        assert files.code_changed({files.TOOLKIT: content[files.TOOLKIT]}) == [files.TOOLKIT]
    finally:
        sys.modules.pop("probe_constants", None)


def test_a_directory_holding_a_campaign_is_opened_only_to_resume_it(fmus, tmp_path):
    """campaign.json without a journal (a campaign killed before its first run) is a
    campaign too: without --resume another one would have overwritten it."""
    plan = Plan(Spec("scan_pitch", runs=2, stop=1.0))
    assert engine.open_directory(plan, tmp_path, resume=False) == {}
    first = (tmp_path / "campaign.json").read_text()
    with pytest.raises(
        engine.CampaignExistsError, match=r"already holds a campaign \(campaign.json\)"
    ):
        engine.open_directory(plan, tmp_path, resume=False)
    assert (tmp_path / "campaign.json").read_text() == first
    assert engine.open_directory(plan, tmp_path, resume=True) == {}


def test_a_campaign_on_a_held_directory_is_refused_before_it_writes(fmus, tmp_path):
    """Another process (a run, a campaign) holds the directory: the campaign is refused,
    naming it and its command, and writes nothing there."""
    import subprocess
    import sys

    from agilesat.orchestration.campaign import run_campaign
    from agilesat.orchestration.output.lock import OutputInUse

    holder = "import sys, time\nfrom agilesat.orchestration.output.lock import holding\n"
    holder += "with holding(sys.argv[1]):\n    print('held', flush=True)\n    time.sleep(60)\n"
    process = subprocess.Popen(
        [sys.executable, "-c", holder, str(tmp_path / "c")], stdout=subprocess.PIPE, text=True
    )
    try:
        assert process.stdout.readline() == "held\n"
        with pytest.raises(OutputInUse, match=rf"process {process.pid}: .*holding"):
            run_campaign(Spec("scan_pitch", runs=2, stop=1.0), tmp_path / "c", progress=False)
        assert list((tmp_path / "c").iterdir()) == []
    finally:
        process.kill()
        process.wait()


@pytest.mark.parametrize(
    "vary, hint",
    [
        ("SatelliteDynamics.inertia=normal(1, 0.01)", "a leading \\* multiplies the nominal"),
        ("SatelliteDynamics.inertia=*normal(1, 0.01)", "inertia\\(sd_rel, sd_angle\\)"),
    ],
)
def test_a_draw_per_element_of_an_inertia_is_refused_with_what_disperses_one(fmus, vary, hint):
    with pytest.raises(ValueError, match=rf"no run's matrix would be symmetric.*{hint}|{hint}.*"):
        Plan(Spec("scan_pitch", runs=2, vary=[vary]))


def test_set_values_are_typed_before_anything_runs(fmus, tmp_path):
    """A dispersion file's nan (TOML has it), or a --set value the variable cannot take,
    failed every run; now the campaign is refused at once, naming it."""
    from agilesat.orchestration.campaign import dispersion

    file = tmp_path / "nan.toml"
    file.write_text(
        '[vary]\n"CmgCluster.h_rotor" = "*normal(1, 0.01)"\n[set]\n"SatelliteDynamics.mu" = nan\n'
    )
    with pytest.raises(
        ValueError, match=r"nan.toml: set.SatelliteDynamics.mu = nan: a value must be a finite"
    ):
        dispersion.load(file)
    with pytest.raises(ValueError, match=r"--set SatelliteDynamics.mu=nan: expected a finite Real"):
        Plan(Spec("scan_pitch", set={"SatelliteDynamics.mu": "nan"}))


def test_a_crash_of_the_process_of_an_isolated_run_is_said(monkeypatch):
    """The nominal run's process killed by a signal (an FMU's segfault): RunFailed naming
    it, the campaign's process goes on."""
    from agilesat.orchestration.campaign import isolated

    monkeypatch.setattr(
        isolated, "CHILD", "import os, signal; os.kill(os.getpid(), signal.SIGSEGV)"
    )
    with pytest.raises(isolated.RunFailed, match="its process was killed by SIGSEGV"):
        isolated.run("scan_pitch", None)


def test_an_isolated_run_goes_on_while_the_campaign_works_and_is_killed_if_not_wanted(
    monkeypatch, tmp_path
):
    """start() returns while the run's process waits (here for a file this test writes
    only afterwards: had start() waited for it, the test would hang); result() then has
    its summary.  cancel() kills a process whose answer is no longer wanted."""
    from agilesat.orchestration.campaign import isolated

    go = tmp_path / "go"
    monkeypatch.setattr(
        isolated,
        "CHILD",
        "import json, os, pickle, sys, time\n"
        "target, options = pickle.load(sys.stdin.buffer)\n"
        f"while not os.path.exists({str(go)!r}): time.sleep(0.01)\n"
        "print(json.dumps({'summary': {'target': target, 'options': options}}))\n",
    )
    started = isolated.start("scan_pitch", {"stop": 3})
    assert started.child.poll() is None  # still waiting
    go.write_text("")
    assert started.result() == {"target": "scan_pitch", "options": {"stop": 3}}
    go.unlink()
    waiting = isolated.start("scan_pitch", None)
    waiting.cancel()
    waiting.thread.join()
    assert waiting.child.returncode == -signal.SIGKILL


def test_a_campaign_until_decided_holds_its_directory_between_its_looks(fmus, tmp_path):
    """Each look holds --out (run_campaign); between two, the summary is written: the
    directory stays held through them, so no other campaign takes it meanwhile."""
    from types import SimpleNamespace

    from agilesat.orchestration.campaign.sequential import run_until_decided
    from agilesat.orchestration.output import lock

    out, held = tmp_path / "c", []

    def look(spec, resume):
        held.append(out.resolve() in lock._held)
        verdict = "undecided" if len(held) == 1 else "met"
        ensemble = {"pde": {"verdict": verdict, "details": {"runs_to_decide": 4}}}
        return SimpleNamespace(summary={"status": "complete", "ensemble": ensemble})

    run_until_decided(Spec("scan_pitch", runs=2), 10, out, False, look)
    assert held == [True, True]
    assert json.loads((out / "campaign.json").read_text())["until_decided"]["runs"] > 2
