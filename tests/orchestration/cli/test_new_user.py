"""What a new user tripped over (issue #28): `info` of a variant, `validate` by name, and
the other places where the command line was wrong or misleading."""

import re

import pytest

from agilesat.orchestration import cli
from agilesat.orchestration.info import info


def test_info_of_a_variant_shows_its_values_marked_with_degrees_and_the_outputs(fmus):
    text = info("video_sar:no_yaw_compensation")
    header = text.split("metrics (")[0]
    # 0.446370651122 rad = 25.5752°, 0.804885764925 rad = 46.1166°
    assert "SatelliteDynamics.attitude0 = [-0.446371,0.804886,0] rad ([-25.5752,46.1166,0]°)" in (
        header
    )
    assert "StaringGuidance.yaw_compensation = false" in header
    rows = [line for line in text.splitlines() if line.startswith(" !")]
    assert [row.split()[0] for row in rows] == [
        "!StaringGuidance.yaw_compensation",
        "!SatelliteDynamics.attitude0[3]",
        "!SatelliteDynamics.rate0[3]",
    ]
    assert "outputs (recorded" in text and "SatelliteDynamics.q_BI[4]" in text
    assert "array(" not in info("scan_pitch:literal_spin")


def test_info_refuses_a_misspelt_variant_with_the_closest_name(fmus):
    with pytest.raises(KeyError, match="no variant 'literal'; did you mean literal_spin"):
        info("scan_pitch:literal")


def test_validate_takes_our_fmus_by_name(fmus, capsys):
    assert cli.main(["validate", "CmgCluster"]) == 0
    assert capsys.readouterr().out.strip() == f"{fmus['CmgCluster']}: OK"
    assert cli.main(["validate", "CmgClustr"]) == 1
    assert "did you mean CmgCluster" in capsys.readouterr().err


def test_stare_takes_a_date_alone_and_reports_degree_inputs_in_degrees(tmp_path, capsys):
    import datetime

    from agilesat.orchestration.studies.stare import search_start
    from helpers import ISS_TLE

    assert search_start(*ISS_TLE, "2030-01-01") == datetime.datetime(2030, 1, 1)
    (tmp_path / "iss.tle").write_text("\n".join(ISS_TLE) + "\n")
    tle = str(tmp_path / "iss.tle")
    assert cli.main(["stare", "--tle", tle, "--target", "100", "0"]) == 1
    assert "--target LAT must be in [-90°, 90°], got 100°" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.integration
def test_a_reused_out_drops_the_previous_runs_figures_only(fmus, tmp_path):
    import datetime
    import json

    from helpers import agilesat

    (tmp_path / "overview_Other.png").write_bytes(b"an earlier run's figure")
    (tmp_path / "notes.txt").write_text("the user's own file")
    earlier = {"status": "ok", "figures": [str(tmp_path / "overview_Other.png")]}
    (tmp_path / "summary.json").write_text(json.dumps(earlier))
    result = agilesat("run", "Flywheel", "--stop", 1, "--step", 0.1, "-q", "--out", tmp_path)
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["overview_Flywheel.png"]
    assert (tmp_path / "notes.txt").exists()
    # what made it, and when: summary.json and the head of log.txt
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["version"].startswith("agilesat ") and "fmpy" in summary["version"]
    assert summary["command"].endswith(f"run Flywheel --stop 1 --step 0.1 -q --out {tmp_path}")
    made = datetime.datetime.fromisoformat(summary["date"])
    assert abs((datetime.datetime.now(datetime.timezone.utc) - made).total_seconds()) < 600
    head = (tmp_path / "log.txt").read_text().splitlines()[:3]
    assert head == [f"# {k}: {summary[k]}" for k in ("version", "command", "date")]


def _options(parser, path=()):
    """(command path, action) of every argument of the command line, and each command's
    (path, parser)."""
    import argparse

    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*path, name), sub
                yield from _options(sub, (*path, name))
        elif not isinstance(action, (argparse._HelpAction, argparse._VersionAction)):
            yield path, action


def test_every_command_and_option_says_what_it_does_and_its_default():
    import argparse

    problems = []
    for path, item in _options(cli._parser(campaign=True)):
        if isinstance(item, argparse.ArgumentParser):
            if not item.description:
                problems.append(f"{' '.join(path)}: no description in its --help")
            continue
        name = f"{' '.join(path)} {'/'.join(item.option_strings) or item.dest}"
        trivial = item.default in (None, False, [], ()) or (  # --no-figures: figures=True
            isinstance(item, argparse._StoreFalseAction) and item.default is True
        )
        if not item.help:
            problems.append(f"{name}: no help")
        elif not trivial and "default" not in item.help:
            problems.append(f"{name}: default {item.default!r} not said")
    assert problems == []


def test_generate_is_a_developers_command_and_version_names_what_results_depend_on(capsys):
    helptext = cli._parser().format_help()
    assert "generate" not in helptext and "campaign" in helptext
    with pytest.raises(SystemExit):
        cli.main(["--version"])
    version = capsys.readouterr().out
    assert all(re.search(rf"\b{name} \d", version) for name in ("fmpy", "pythonfmu", "numpy"))
    assert "FMI 2.0" in version


def test_generate_check_in_an_installed_package_checks_what_it_ships(tmp_path, monkeypatch):
    """An installed (non-editable) package has no fmus/INTERFACES.md: not out of date."""
    from agilesat.fmus import build

    monkeypatch.setattr(build, "generated_files", lambda: {tmp_path / "INTERFACES.md": bytes})
    assert cli.main(["generate", "--check"]) == 1  # a source checkout: missing is stale
    monkeypatch.setattr(cli.system, "source_checkout", lambda: False)
    assert cli.main(["generate", "--check"]) == 0
    assert cli.main(["generate"]) == 1  # writes into a checkout only


def test_plot_usage_errors_exit_2_and_a_missing_directory_or_variable_is_named(tmp_path, capsys):
    assert cli.main(["plot", str(tmp_path)]) == 2
    assert "expected RESULTS_DIR... VARIABLE..." in capsys.readouterr().err
    assert cli.main(["plot", str(tmp_path / "gone"), "A.x"]) == 1
    assert f"no such run directory: {tmp_path / 'gone'}" in capsys.readouterr().err


def test_one_quiet_flag_everywhere():
    parser = cli._parser(campaign=True)
    for command in ("run", "build", "stare", "size-flywheel", "campaign"):
        assert parser.parse_args([command, "-q", *ARGS.get(command, [])]).quiet is True
    assert parser.parse_args(["campaign", "x", "--no-progress"]).quiet is True


ARGS = {"run": ["x"], "stare": ["--tle", "f"], "campaign": ["x"]}


def test_the_degree_sign_is_spaced_alike_by_every_printer(tmp_path):
    """No space before a degree sign standing alone (as the unit printer writes '2.1°'),
    one before every other unit, '°/s' included: in summaries, requirement statements,
    pointing verdicts, the pytest plugin's assertions and `info`."""
    import math

    import numpy as np

    from agilesat.orchestration.output.results import Results
    from agilesat.orchestration.output.summary import format_value
    from agilesat.orchestration.pointing.requirement import format_angle
    from agilesat.orchestration.postprocess.checks import assert_settles, assert_within
    from agilesat.orchestration.system.units import join

    deg = math.pi / 180
    assert format_value(0.05 * deg, "rad", "deg") == "0.05°"
    assert format_value(0.05 * deg, "rad/s", "deg/s") == "0.05 °/s"
    assert format_angle(0.05 * deg) == "0.05°"
    assert join("3", "N·m") == "3 N·m" and join("0.57", "") == "0.57"
    t = np.linspace(0.0, 1.0, 11)
    results = Results(
        ["time", "A.angle"], np.column_stack((t, t * deg)), {"units": {"A.angle": "rad"}}
    )
    with pytest.raises(AssertionError, match=r"above 0\.5° at 5 of 11 points.*\(0\.6°\); worst 1°"):
        assert_within(results, "A.angle", high=0.5, deg=True)
    with pytest.raises(AssertionError, match=r"within ±0\.05° after t = 0 s: max 1°"):
        assert_settles(results, "A.angle", 0.05, 0.0, deg=True)


def test_the_papers_value_keeps_its_unit_beside_a_metric_without_a_value():
    from agilesat.orchestration.output.summary import format_summary

    metrics = {
        "settling_time": {
            "value": None,
            "unit": "s",
            "display_unit": "s",
            "paper": 105.0,
            "reason": "not settled",
        }
    }
    assert "no value   paper 105 s" in format_summary({"metrics": metrics})
