"""What is computed from a run's records is computed once per Results and kept by it
(:meth:`Results.derived`, :func:`per_results`): never another Results' value, its arrays
read-only, and a reads probe computes it again for every reader."""

import numpy as np
import pytest

from agilesat.orchestration.mission.reads import Probe, _read
from agilesat.orchestration.output.results import Results, per_results


def make(scale: float) -> Results:
    t = np.arange(5) * 0.1
    return Results(["time", "Sat.x"], np.column_stack([t, scale * t]))


def test_computed_once_per_results_and_arguments():
    calls = []

    @per_results
    def doubled(results, factor=2.0):
        calls.append(factor)
        return factor * results["Sat.x"]

    results = make(1.0)
    first = doubled(results)
    assert doubled(results) is first
    assert doubled(results, 3.0) is not first
    assert calls == [2.0, 3.0]
    assert first.tolist() == [0.0, 0.2, 0.4, 0.6000000000000001, 0.8]


def test_another_results_never_gets_its_value_even_at_the_same_address():
    @per_results
    def peak(results):
        return float(results["Sat.x"].max())

    seen = []
    for scale in (1.0, 2.0, 3.0, 4.0):  # each freed before the next: addresses are reused
        seen.append(peak(make(scale)))
    assert seen == [0.4, 0.8, 1.2000000000000002, 1.6]


def test_arrays_kept_are_read_only_and_a_failure_is_not_kept():
    results = make(1.0)
    kept = results.derived("x", lambda: (results["Sat.x"] * 2, {"y": np.ones(2)}))
    with pytest.raises(ValueError, match="read-only"):
        kept[0][0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        kept[1]["y"][0] = 1.0

    def fails():
        raise ZeroDivisionError("no")

    for _ in range(2):  # raised each time: nothing kept
        with pytest.raises(ZeroDivisionError):
            results.derived("fails", fails)


def test_columns_that_are_no_results_are_computed_each_call():
    calls = []

    @per_results
    def first(columns):
        calls.append(1)
        return columns["Sat.x"][0]

    columns = {"Sat.x": np.array([1.0, 2.0])}
    assert first(columns) == first(columns) == 1.0
    assert calls == [1, 1]


def test_a_reads_probe_sees_what_every_reader_asks():
    """The probe computes a derived value again for each metric or requirement that reads
    it: each is told the names it reads that are no output (kept, the second would not)."""

    @per_results
    def beam(results):
        return results["Sat.beam"]

    probe = Probe({}, 0.0, 10.0)
    assert _read(probe, lambda: beam(probe)) == ["Sat.beam"]
    assert _read(probe, lambda: beam(probe)) == ["Sat.beam"]


def test_a_copy_or_a_pickle_computes_again():
    """What was derived stays with the object (its keys may be functions of a scenario that
    do not pickle): a copy or an unpickled one starts without it."""
    import copy
    import pickle

    results = make(1.0)
    results.derived(("peak", lambda: None), lambda: 1.0)
    for other in (copy.copy(results), pickle.loads(pickle.dumps(results))):
        assert other.derived("x", lambda: 2.0) == 2.0
        assert np.array_equal(other.data, results.data)
    assert results.derived("x", lambda: 3.0) == 3.0
