"""What a new user tripped over (issue #28): `info` of a variant, `validate` by name, and
the other places where the command line was wrong or misleading."""

import pytest

from agilesat.orchestration import cli
from agilesat.orchestration.info import info


def test_info_of_a_variant_shows_its_values_marked_with_degrees_and_the_outputs(fmus):
    text = info("video_sar:no_yaw_compensation")
    header = text.split("metrics (")[0]
    # 0.446370651122 rad = 25.5752°, 0.804885764925 rad = 46.1166°
    assert "SatelliteDynamics.attitude0 = [-0.446371,0.804886,0] rad ([-25.5752,46.1166,0] °)" in (
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
