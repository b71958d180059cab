"""A campaign's own files read back (``campaign/files.py``, ``engine.py``): damaged ones
named with their line, the system's content hash, kept signals never shrunk.  Whole
campaigns on damaged files: ``tests/tools/fault_cases_campaign.py``."""

import json

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
