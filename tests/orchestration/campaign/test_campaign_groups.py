"""Pass rates per group of runs (``agilesat campaign --group-by``): by each value of a
dispersed column, or by intervals of it, a fault time "never" (inf) its own group, each
group's rate with its Clopper-Pearson interval."""

import math

import numpy as np
import pytest

from agilesat.orchestration.campaign.report import clopper_pearson, group_pass_rates

CATALOG = {"requirements": {"pointing": {}, "slew": {}}}


def runs(fail_times, pointing_met):
    dtype = [("CmgCluster.fail_time[3]", "f8"), ("verdict_pointing", "U13"),
             ("verdict_slew", "U13")]  # fmt: skip
    rows = [(t, "met" if ok else "not met", "met") for t, ok in zip(fail_times, pointing_met)]
    return np.array(rows, dtype=dtype)


def test_runs_grouped_by_value_with_never_last():
    table = runs([math.inf, 15.0, 50.0, math.inf, 15.0, 15.0], [1, 0, 1, 1, 1, 0])
    groups = group_pass_rates(table, CATALOG, "CmgCluster.fail_time[3]")
    assert [(g["group"], g["runs"]) for g in groups] == [("15", 3), ("50", 1), ("inf", 2)]
    during = groups[0]["pass_rates"]["pointing"]
    assert (during["met"], during["runs"], during["not_met"]) == (1, 3, 2)
    assert during["ci95"] == pytest.approx(list(clopper_pearson(1, 3)))
    assert groups[0]["pass_rates"]["all"]["met"] == 1  # both requirements met


def test_runs_grouped_by_intervals():
    table = runs([5.0, 12.0, 27.9, 28.0, 400.0, math.inf], [1, 0, 0, 1, 1, 1])
    groups = group_pass_rates(table, CATALOG, "CmgCluster.fail_time[3]", [10.0, 28.0, 100.0])
    assert [(g["group"], g["runs"]) for g in groups] == [
        ("< 10", 1), ("[10, 28)", 2), ("[28, 100)", 1), (">= 100", 1), ("inf", 1),
    ]  # fmt: skip
    assert groups[1]["pass_rates"]["pointing"]["met"] == 0


def test_a_column_the_table_has_not_is_named():
    with pytest.raises(ValueError, match=r"--group-by Gyro.bias_step_time: not a column"):
        group_pass_rates(runs([1.0], [1]), CATALOG, "Gyro.bias_step_time")


def test_the_option_is_read_before_any_run():
    from agilesat.orchestration.cli.campaign import _grouping

    assert _grouping("CmgCluster.fail_time[3]=10,27.5,40") == (
        "CmgCluster.fail_time[3]",
        [10.0, 27.5, 40.0],
    )
    assert _grouping("Flywheel.fail_time") == ("Flywheel.fail_time", [])
    with pytest.raises(ValueError, match="the edges must increase"):
        _grouping("Gyro.bias_step_time=5,5")
    with pytest.raises(ValueError, match="the edges are numbers"):
        _grouping("Gyro.bias_step_time=5,never")
