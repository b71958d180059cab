"""ECSS indices of recorded run and campaign directories after the fact: ``agilesat
pointing DIR`` and ``assert_pointing``, on synthetic records of known error."""

import json
import math

import numpy as np
import pytest

from agilesat.orchestration import assert_pointing
from agilesat.orchestration.cli import main
from agilesat.orchestration.output.results import Results

DT, PERIOD, BIAS, AMPLITUDE = 0.05, 10.0, 3e-5, 1e-5  # s, s, rad, rad
T = np.arange(1201) * DT  # 60 s
IDENTITY = np.tile([1.0, 0.0, 0.0, 0.0], (T.size, 1))


def about_z(angle):
    """Quaternions (..., 4) of rotations by ``angle`` (rad) about z."""
    angle = np.asarray(angle)
    zero = np.zeros_like(angle)
    return np.stack((np.cos(angle / 2), zero, zero, np.sin(angle / 2)), axis=-1)


def columns(q_BI, q_OI):
    names = [
        f"{base}[{i}]"
        for base in ("SatelliteDynamics.q_BI", "OrbitEnvironment.q_OI")
        for i in range(1, 5)
    ]
    return names, np.hstack((q_BI, q_OI))


@pytest.fixture
def run_dir(tmp_path):
    """A run whose body is off the orbit frame about z by b + A sin(2π t/P)."""
    tmp_path = tmp_path / "run"
    tmp_path.mkdir()
    names, data = columns(about_z(BIAS + AMPLITUDE * np.sin(2 * math.pi * T / PERIOD)), IDENTITY)
    Results(["time", *names], np.column_stack((T, data))).to_csv(tmp_path / "results.csv")
    return tmp_path


@pytest.fixture
def campaign_dir(tmp_path):
    """30 runs of white angle noise about z (σ 1e-5 rad, one run stopped early)."""
    tmp_path = tmp_path / "campaign"
    tmp_path.mkdir()
    rng = np.random.default_rng(3)
    angles = rng.normal(size=(31, T.size)) * 1e-5
    names, _ = columns(IDENTITY, IDENTITY)
    signals = np.empty((31, len(names), T.size))
    signals[:, :4] = about_z(angles).transpose(0, 2, 1)
    signals[:, 4:] = IDENTITY.T
    signals[30, :, 600:] = np.nan  # stopped at 30 s
    np.save(tmp_path / "signals.npy", signals)
    summary = {
        "spec": {"target": "video_sar"},
        "runs": {"planned": 31},
        "kept": {"signals": names, "start": 0.0, "step": DT, "points": T.size},
    }
    (tmp_path / "campaign.json").write_text(json.dumps(summary))
    return tmp_path, angles[:30]


def pointing(directory, *options, capsys):
    argv = ["pointing", str(directory), "--reference", "OrbitEnvironment.q_OI", *map(str, options)]
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.out + captured.err


def test_indices_of_a_run_directory_against_their_closed_forms(run_dir, tmp_path, capsys):
    """Over a whole period the mean of b + A sin is b (the trapezoid rule is exact for a
    sampled sinusoid over whole periods); at the window's end the RPE is A sin, whose
    median magnitude is A sin(π/4) (the arcsine law: |sin| of a uniform phase)."""
    out = tmp_path / "records.json"
    code, text = pointing(
        run_dir,
        "--index",
        "MPE",
        "--window",
        "10",
        "--level",
        "0.5",
        "--axis",
        "0",
        "0",
        "1",
        "--json",
        out,
        capsys=capsys,
    )
    assert code == 0 and "MPE(10 s) about (0, 0, 1) at 50 % (temporal): 0.001719°" in text
    assert json.loads(out.read_text())[0]["value"] == pytest.approx(BIAS, rel=1e-9)
    code, text = pointing(
        run_dir,
        "--index",
        "RPE",
        "--window",
        "10",
        "--level",
        "0.5",
        "--axis",
        "0",
        "0",
        "1",
        "--bound",
        "1e-5",
        "--json",
        out,
        capsys=capsys,
    )
    value = json.loads(out.read_text())[0]["value"]
    assert value == pytest.approx(AMPLITUDE * math.sin(math.pi / 4), rel=0.01)
    assert code == 0 and text.rstrip().endswith("(requirement 0.000573°): met")
    code, text = pointing(
        run_dir, "--index", "APE", "--bound", "0.002deg", "--unit", "arcsec", capsys=capsys
    )
    assert code == 3 and "APE at 99.73 % (temporal)" in text and text.rstrip().endswith("not met")


def test_a_variant_s_exempt_requirements_are_not_judged(run_dir, capsys):
    """payload_sweep:no_control does not judge the pointing requirements (the wheel motors
    are off): ``agilesat pointing`` says so, as the run's summary does, and judges none of
    them."""
    (run_dir / "summary.json").write_text(
        json.dumps({"scenario": "payload_sweep", "variant": "no_control"})
    )
    code = main(["pointing", str(run_dir)])
    text = capsys.readouterr().out
    assert code == 0 and "payload_sweep:no_control" in text
    assert "pointing_ape: not judged (the wheel motors are off" in text
    assert "stability_pde: not judged" in text and "APE" not in text
    (run_dir / "summary.json").write_text(json.dumps({"scenario": "payload_sweep"}))
    code = main(["pointing", str(run_dir)])
    assert "pointing_ape: APE" in capsys.readouterr().out  # judged by the nominal


def test_indices_of_a_campaign_directory(campaign_dir, capsys):
    """The ensemble statistic is, at each time, the ⌈P n⌉-th smallest of the n runs'
    magnitudes, worst over time; the run that stopped early is left out, and said."""
    directory, angles = campaign_dir
    code, text = pointing(
        directory, "--index", "APE", "--level", "0.9", "--unit", "urad", capsys=capsys
    )
    expected = np.sort(np.abs(angles), axis=0)[26].max()  # ⌈0.9 × 30⌉ = 27th of 30
    assert code == 0 and "video_sar, 30 run(s), 1 that stopped early left out" in text
    assert f"APE at 90 % (ensemble): {expected / 1e-6:.4g} urad" in text
    code, text = pointing(
        directory, "--index", "APE", "--confidence", "0.95", "--bound", "1e-4", capsys=capsys
    )
    assert code == 4 and "undecided (none of the 30 run(s) above it at any time" in text
    assert "about 1109 runs would settle it" in text  # ⌈ln 0.05 / ln 0.9973⌉
    code, text = pointing(
        directory, "--index", "APE", "--confidence", "0.95", "--bound", "1e-6", capsys=capsys
    )
    assert code == 3 and "not met (30 of 30 run(s) above it at worst" in text
    code, text = pointing(
        directory, "--index", "APE", "--figure", directory / "a.png", capsys=capsys
    )
    assert (directory / "a.png").stat().st_size > 10_000
    code, text = pointing(
        directory, "--index", "APE", "--interpretation", "mixed", "--figure", directory / "b",
        capsys=capsys,
    )  # fmt: skip
    assert code == 1 and "a mixed statistic has none" in text


def test_assert_pointing_on_runs_and_campaigns(run_dir, campaign_dir):
    results = Results.load(run_dir)
    common = dict(reference="OrbitEnvironment.q_OI", axis=(0, 0, 1))
    result = assert_pointing(results, "MPE", window=10.0, level=0.5, bound=1.01 * BIAS, **common)
    assert result.value == pytest.approx(BIAS, rel=1e-9)
    with pytest.raises(AssertionError, match=r"MPE\(10 s\) about \(0, 0, 1\) .*: not met"):
        assert_pointing(run_dir, "MPE", window=10.0, level=0.5, bound=0.99 * BIAS, **common)
    directory = campaign_dir[0]
    ensemble = dict(interpretation="ensemble", confidence=0.95, **common)
    with pytest.raises(AssertionError, match=r"^undecided \(accept_undecided=True accepts it\)"):
        assert_pointing(directory, "APE", bound=1.0, **ensemble)
    result = assert_pointing(directory, "APE", bound=1.0, accept_undecided=True, **ensemble)
    assert result.status == "undecided" and result.runs_to_decide == 1109
    with pytest.raises(AssertionError, match=r"^not met: APE about \(0, 0, 1\)"):
        assert_pointing(directory, "APE", bound=1e-6, accept_undecided=True, **ensemble)
    with pytest.raises(KeyError, match="run it again with --keep AttitudeEstimator.q_BI_est"):
        assert_pointing(directory, "AKE", bound=1.0)
    with pytest.raises(ValueError, match="RPE is a performance index: name the reference"):
        assert_pointing(results, "RPE", window=1.0, bound=1.0)
