"""The index magnitudes the workers keep for the verdicts over a campaign
(orchestration/campaign/magnitudes.py): those of runs computed together are the ones
computed run by run, bit for bit, for every index; the store gives them only where every
run that reached the end has its row; a real campaign's verdicts over the campaign are the
same with them as computed again from signals.npy, without computing any error history;
a campaign resumed with fewer runs judges those runs only."""

import errno
import itertools
import os
import shutil
from dataclasses import replace

import numpy as np
import pytest

from agilesat.orchestration.campaign import summary
from agilesat.orchestration.campaign.magnitudes import FOLDER, Store, key, run_rows
from agilesat.orchestration.campaign.plan import Plan, Spec
from agilesat.orchestration.mission.requirements import Pointing
from agilesat.orchestration.pointing import PointingRequirement
from agilesat.orchestration.pointing.errors import ErrorHistory
from helpers import agilesat

INDICES = [
    ("APE", {}),
    ("RPE", {"window": 1.0}),
    ("MPE", {"window": 2.0}),
    ("PDE", {"window": 1.0, "separation": 10.0}),
    ("PRE", {"window": 1.0, "separation": 5.0}),
]


@pytest.mark.parametrize(
    ("index", "geometry"),
    list(itertools.product(INDICES, [{}, {"axis": (0, 0, 1)}, {"boresight": (0, 0, 1)}])),
)
def test_runs_computed_together_are_the_runs_computed_one_by_one(index, geometry):
    name, window = index
    rng = np.random.default_rng(0)
    t = np.arange(801) * 0.05
    values = np.cumsum(rng.normal(size=(37, t.size, 3)), axis=1) * 1e-5 + 1e-4
    r = PointingRequirement(name, 1e-3, 0.99, "ensemble", **window, **geometry)
    times, together = r.magnitudes(ErrorHistory(values, t))
    alone = [r.magnitudes(ErrorHistory(run, t)) for run in values]
    assert all(np.array_equal(times, t_run) for t_run, _ in alone)
    assert np.array_equal(together, np.concatenate([m for _, m in alone]))


def pointing(name="ape", **options):
    r = PointingRequirement("APE", 1e-3, 0.99, "ensemble", **options)
    return Pointing(name, r, reference="OrbitEnvironment.q_OI")


def test_the_store_gives_the_rows_only_where_every_complete_run_has_one(tmp_path):
    r = pointing()
    store = Store(tmp_path, [r], 4)
    store.put(0, {"ape": np.array([1.0, 2.0])})
    store.put(2, {"ape": np.array([3.0, 4.0])})
    store.flush()
    again = Store(tmp_path, [r], 4)  # another process: from the file
    np.testing.assert_array_equal(
        again.stacked("ape", np.array([True, False, True, False])), [[1, 2], [3, 4]]
    )
    assert again.stacked("ape", np.array([True, True, True, False])) is None  # run 1: none
    assert again.stacked("other", np.array([True, False, False, False])) is None
    longer = Store(tmp_path, [r], 6)  # the campaign extended: the rows made stay
    longer.put(5, {"ape": np.array([5.0, 6.0])})
    np.testing.assert_array_equal(
        longer.stacked("ape", np.array([True, False, True, False, False, True])),
        [[1, 2], [3, 4], [5, 6]],
    )
    changed = Store(tmp_path, [pointing(axis=(0, 0, 1))], 6)  # a changed definition
    assert changed.stacked("ape", np.array([True, False, False, False, False, False])) is None


def test_a_full_disk_is_an_error_naming_the_file_not_a_crash(tmp_path, monkeypatch):
    """The file's blocks are taken when it is made: no disk, an OSError naming it (a write
    through the memory map into a sparse file would kill the process with SIGBUS)."""

    def full(fd, offset, size):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "posix_fallocate", full)
    with pytest.raises(OSError, match=r"magnitudes/ape-\w+\.npy: No space left on device"):
        Store(tmp_path, [pointing()], 4).put(0, {"ape": np.array([1.0, 2.0])})


def test_a_run_whose_magnitudes_raise_keeps_none_and_its_record_is_made():
    class Raising(Pointing):
        def run_magnitudes(self, results):
            raise ValueError("a non-finite error")

    r = pointing()
    bad = Raising("bad", r.requirement, reference="OrbitEnvironment.q_OI")
    good = {"ape": (np.arange(3.0), np.ones((1, 3)))}
    object.__setattr__(r, "run_magnitudes", lambda results: good["ape"])
    assert list(run_rows([bad, r], results=None)) == ["ape"]


def test_the_key_follows_the_definition_and_nothing_else():
    assert key(pointing()) == key(pointing())
    assert key(pointing()) != key(pointing(axis=(0, 0, 1)))
    assert key(pointing()) != key(replace(pointing(), start=1.0))
    assert key(pointing()) == key(replace(pointing(), origin="elsewhere.py:1"))


@pytest.mark.slow
def test_a_campaigns_verdicts_are_the_same_from_the_workers_magnitudes(tmp_path, monkeypatch):
    """video_sar:sensed, 4 runs: the summary judges the workers' magnitudes (no error
    history computed, but the first run's, to check its row), and its verdicts are those
    computed again from signals.npy with the magnitudes gone."""
    vary = ["SatelliteDynamics.rate0[1]=+normal(0, 0.01deg)"]
    out = tmp_path / "c"
    arguments = ["--runs", "4", "--stop", "10", "--workers", "1", "--no-report", "--out", out]
    made = agilesat("campaign", "video_sar:sensed", "--vary", vary[0], "--no-progress", *arguments)
    assert made.returncode in (0, 3, 4), made.stdout + made.stderr
    assert len(list((out / FOLDER).glob("*.npy"))) == 2  # pointing_ape, pointing_rpe
    plan = Plan(Spec("video_sar:sensed", runs=4, vary=vary, stop=10.0))
    runs = []  # of each error history computed
    error = Pointing.error
    monkeypatch.setattr(
        Pointing,
        "error",
        lambda self, c, t: runs.append(len(next(iter(c.values())))) or error(self, c, t),
    )
    stored, _ = summary._ensemble(plan, out, 4)
    assert runs == [1, 1]  # each requirement's first run, checked against its row
    runs.clear()
    shutil.rmtree(out / FOLDER)
    again, _ = summary._ensemble(plan, out, 4)
    assert runs == [4, 4]
    assert stored == again
    assert {e["details"]["runs"] for e in stored.values()} == {4}
    fewer = Plan(Spec("video_sar:sensed", runs=3, vary=vary, stop=10.0))  # --resume --runs 3
    judged, _ = summary._ensemble(fewer, out, 3)  # the fourth run's signals are kept
    assert {e["details"]["runs"] for e in judged.values()} == {3}
