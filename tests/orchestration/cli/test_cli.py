"""The command line as an engineer uses it every day: list, info, --set with arrays, the
summary, plot, build, --version and exit codes.  Numbers are read from summary.json."""

import json
import struct

import numpy as np
import pytest

from agilesat.orchestration.output.results import Results
from agilesat.orchestration.scenarios import get
from agilesat.orchestration.system.description import Description
from agilesat.orchestration.system.parameters import typed_parameters, variables
from agilesat.orchestration.system.ssp import SystemFileError
from helpers import agilesat

IDENTITY_900 = "[[900,0,0],[0,900,0],[0,0,900]]"


@pytest.fixture(scope="module")
def described(fmus):
    return {name: Description(name, fmus[name]) for name in ("SatelliteDynamics", "Flywheel")}


def test_arrays_are_grouped_with_their_shape(described):
    table = variables(described["SatelliteDynamics"])
    assert table["inertia"].shape == (3, 3) and table["inertia"].first.unit == "kg.m2"
    assert table["inertia"].start() == [[956.0, 0.0, 0.0], [0.0, 956.0, 0.0], [0.0, 0.0, 956.0]]
    assert table["gravity_gradient"].shape == ()
    assert variables(described["Flywheel"])["axis"].shape == (4, 3)


def test_a_whole_array_splits_into_its_elements_each_typed_by_its_variable(described):
    typed = typed_parameters(
        described,
        {
            "SatelliteDynamics.inertia": IDENTITY_900,
            "SatelliteDynamics.rate0[2]": "0.01",
            "Flywheel.speed0": [1, 2, 3, 4],
            "SatelliteDynamics.gravity_gradient": "TRUE",
        },
    )
    values = {key: (p.component, p.name, p.type, p.value) for key, p in typed.items()}
    element = values["SatelliteDynamics.inertia[2,2]"]
    assert element == ("SatelliteDynamics", "inertia[2,2]", "Real", 900.0)
    assert values["SatelliteDynamics.inertia[2,3]"][2:] == ("Real", 0.0)
    assert values["SatelliteDynamics.rate0[2]"][2:] == ("Real", 0.01)
    assert [values[f"Flywheel.speed0[{i}]"][3] for i in range(1, 5)] == [1.0, 2.0, 3.0, 4.0]
    assert all(type(p.value) is float for key, p in typed.items() if p.type == "Real")
    assert values["SatelliteDynamics.gravity_gradient"][2:] == ("Boolean", True)
    assert {p.origin for p in typed.values()} == {f"--set {key}" for key in typed}
    assert len(values) == 9 + 1 + 4 + 1


@pytest.mark.parametrize(
    "key, value, message",
    [
        (
            "SatelliteDynamics.inertia",
            "900",
            r"array of shape 3×3 \[kg·m²\]; give it whole, e.g. "
            r"inertia=\[\[956.0,0.0,0.0\],.*or one element, e.g. inertia\[1,1\]=956.0 .*not spread",
        ),
        ("SatelliteDynamics.inertia", "[900, 900, 900]", "array of shape 3×3"),
        ("SatelliteDynamics.inerta", "1", "has no variable 'inerta'; did you mean inertia"),
        ("SateliteDynamics.inertia", "1", "did you mean SatelliteDynamics"),
        (
            "SatelliteDynamics.inertia[4,4]",
            "1",
            r"inertia\[4,4\]: index out of range \(3×3\); the elements are inertia\[1,1\] "
            r"\.\. inertia\[3,3\]",
        ),
        ("SatelliteDynamics.attitude0[2]", "100deg", None),
        ("SatelliteDynamics.mu", "[1, 2]", "is a scalar"),
        ("SatelliteDynamics.inertia", "[[1,0", "cannot read"),
        ("SatelliteDynamics.gravity_gradient", "flase", "=flase: expected a Boolean: true, false"),
        ("SatelliteDynamics.gravity_gradient", "2", "expected a Boolean"),
        ("SatelliteDynamics.gravity_gradient", "on", "expected a Boolean"),
        ("SatelliteDynamics.gravity_gradient", "yes", "expected a Boolean"),
        ("SatelliteDynamics.rate0[2]", "1_000", "rate0\\[2\\]=1_000: expected a finite Real"),
        ("SatelliteDynamics.mu", "inf", "expected a finite Real"),
        ("SatelliteDynamics.mu", "nan", "expected a finite Real"),
        ("SatelliteDynamics.mu", "0x10", "expected a finite Real"),
    ],
)
def test_a_wrong_override_says_what_is_expected(described, key, value, message):
    if message is None:  # accepted
        [typed] = typed_parameters(described, {key: value}).values()
        assert typed.value == pytest.approx(np.radians(100))
        return
    with pytest.raises(SystemFileError, match=message):
        typed_parameters(described, {key: value})


def test_a_named_choice_is_set_by_its_name_or_its_number(fmus):
    described = {"CmgSteering": Description("CmgSteering", fmus["CmgSteering"])}
    for text, value in (("SR_INVERSE", 1), ("sr_inverse", 1), ("PSEUDO_INVERSE", 0), ("1", 1)):
        [typed] = typed_parameters(described, {"CmgSteering.law": text}).values()
        assert (typed.type, typed.value) == ("Integer", value)
    for bad in ("FOO", "2"):
        with pytest.raises(
            SystemFileError,
            match=rf"--set CmgSteering.law={bad}: law must be one of 0 \(PSEUDO_INVERSE\), "
            rf"1 \(SR_INVERSE\), got '{bad}'",
        ):
            typed_parameters(described, {"CmgSteering.law": bad})


@pytest.mark.slow
@pytest.mark.integration
def test_set_a_named_choice_on_the_command_line(fmus, tmp_path):
    result = agilesat(
        "run", "scan_pitch", "--stop", 0.5, "--out", tmp_path, "--no-figures", "--no-report",
        "--set", "CmgSteering.law=SR_INVERSE",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "summary.json").read_text(encoding="utf-8"))
    assert summary["parameters"]["CmgSteering.law"] == {"value": 1, "type": "Integer"}
    result = agilesat("run", "scan_pitch", "--out", tmp_path, "--set", "CmgSteering.law=SR")
    assert result.returncode != 0
    assert "law must be one of 0 (PSEUDO_INVERSE), 1 (SR_INVERSE), got 'SR'" in result.stderr


@pytest.mark.slow
@pytest.mark.integration
def test_list_and_info_show_scenarios_variants_and_array_parameters(fmus):
    listing = agilesat("list")
    assert listing.returncode == 0
    for name in ("scan_pitch", "payload_sweep", "video_sar"):
        assert name in listing.stdout
        assert all(f":{v}" in listing.stdout for v in get(name).variants)
    info = agilesat("info", "scan_pitch")
    assert info.returncode == 0, info.stderr
    row = next(
        line for line in info.stdout.splitlines() if "SatelliteDynamics.inertia[3×3]" in line
    )
    assert "kg·m²" in row and "[[956,0,0],[0,956,0],[0,0,956]]" in row and row.startswith(" *")
    assert "CmgCluster.h -> SatelliteDynamics.h_cmg" in info.stdout
    fmu = agilesat("info", "Flywheel")
    assert "axis[4×3]" in fmu.stdout and "outputs:" in fmu.stdout
    wrong = agilesat("info", "Flywhel")
    assert wrong.returncode == 1 and "did you mean Flywheel?" in wrong.stderr


@pytest.mark.slow
@pytest.mark.integration
def test_misspelt_scenario_variant_and_usage_errors(fmus):
    scenario = agilesat("run", "scan_pich")
    assert scenario.returncode == 1 and "did you mean scan_pitch?" in scenario.stderr
    assert 'error: "' not in scenario.stderr  # not a KeyError's repr
    variant = agilesat("run", "payload_sweep:no_contrl")
    assert variant.returncode == 1 and "did you mean no_control," in variant.stderr
    usage = agilesat("run", "scan_pitch", "--stpo", "1")
    assert usage.returncode == 2
    version = agilesat("--version")
    assert version.returncode == 0 and version.stdout.startswith("agilesat 0.")
    helptext = agilesat("--help").stdout
    assert all(
        code in helptext
        for code in (
            "0 success",
            "1 bad input",
            "2 a usage error",
            "3 a scenario",
            "130 interrupted",
            "143",
        )
    )


@pytest.mark.slow
@pytest.mark.integration
def test_build_with_nothing_to_do_says_so(fmus):
    result = agilesat("build")
    assert result.returncode == 0
    assert (
        result.stdout.strip().splitlines() == [result.stdout.strip()]
        and "up to date" in result.stdout
    )


def _png_width(path):
    with open(path, "rb") as stream:
        header = stream.read(24)
    return struct.unpack(">I", header[16:20])[0]


@pytest.fixture(scope="module")
def short_run(fmus, tmp_path_factory):
    """scan_pitch over 20 s with the inertia set as a whole matrix, SVG twins too."""
    out = tmp_path_factory.mktemp("short")
    result = agilesat(
        "run",
        "scan_pitch",
        "--stop",
        20,
        "--out",
        out,
        "--mat",
        "--svg",
        "--set",
        f"SatelliteDynamics.inertia={IDENTITY_900}",
        "--set",
        "SatelliteDynamics.gravity_gradient=false",
    )
    assert result.returncode == 0, result.stderr
    return out, result, json.loads((out / "summary.json").read_text(encoding="utf-8"))


@pytest.mark.slow
@pytest.mark.integration
def test_set_a_whole_array_and_record_it_typed(short_run):
    out, _, summary = short_run
    parameters = summary["parameters"]
    assert parameters["SatelliteDynamics.inertia[1,1]"] == {"value": 900.0, "type": "Real"}
    assert parameters["SatelliteDynamics.inertia[1,2]"] == {"value": 0.0, "type": "Real"}
    assert parameters["SatelliteDynamics.gravity_gradient"] == {"value": False, "type": "Boolean"}
    # the dynamics FMU got the matrix: its H_I = C_BIᵀ (J w + h) with J = 900 I
    from agilesat.orchestration.scenarios.payload_sweep import inertial_momentum

    results = Results.load(out)
    H = results["SatelliteDynamics.H_I"]
    for J, close in ((900.0, True), (956.0, False)):
        H_J = inertial_momentum(results, J * np.eye(3), "CmgCluster.h")
        assert np.allclose(H_J, H, rtol=1e-9, atol=1e-9) == close


@pytest.mark.slow
@pytest.mark.integration
def test_summary_is_readable_text_with_units_requirements_and_figures(short_run):
    out, result, summary = short_run
    text = (out / "summary.json").read_text(encoding="utf-8")
    assert "\\u" not in text and "−" in text
    assert summary["wall_time"] > 0 and summary["real_time_factor"] > 0
    assert summary["metrics"]["max_gimbal_accel"]["unit"] == "rad/s2"
    assert "rad/s²" in result.stdout and "rad/s2" not in result.stdout
    line = next(x for x in result.stdout.splitlines() if "imaging_pitch_rate_mean" in x)
    assert "required in [-0.82, -0.78] °/s" in line
    figures = summary["figures"]
    assert {p.rsplit(".", 1)[1] for p in figures} == {"png", "svg"} and len(figures) == 16
    assert any(p.endswith("fig08_initial_gimbal_rates.png") for p in figures)
    assert all(_png_width(p) >= 8 * 200 for p in figures if p.endswith(".png"))
    units = json.loads((out / "results.units.json").read_text())
    assert units["CmgCluster.delta_dot[1]"] == "rad/s"


@pytest.mark.slow
@pytest.mark.integration
def test_results_mat_and_fmpy_csv(short_run):
    from fmpy.util import read_csv
    from scipy.io import loadmat

    out = short_run[0]
    results = Results.load(out)
    mat = loadmat(out / "results.mat", squeeze_me=False, struct_as_record=False)
    assert np.array_equal(mat["CmgCluster"][0, 0].delta, results["CmgCluster.delta"])
    table = read_csv(str(out / "results.csv"))
    assert np.array_equal(table["CmgCluster.delta[3]"], results["CmgCluster.delta[3]"])


@pytest.mark.slow
@pytest.mark.integration
def test_plot_overlays_runs_by_base_name_in_degrees(short_run, tmp_path):
    out = short_run[0]
    figure = tmp_path / "delta.png"
    result = agilesat(
        "plot",
        out,
        out,
        "CmgCluster.delta",
        "SatelliteDynamics.euler_BO[2]",
        "--deg",
        "--out",
        figure,
    )
    assert result.returncode == 0, result.stderr
    assert figure.exists() and figure.with_suffix(".svg").exists()
    svg = figure.with_suffix(".svg").read_text()
    assert "CmgCluster.delta [°]" in svg or "CmgCluster.delta [°]" in svg.replace("&#176;", "°")
    wrong = agilesat("plot", out, "CmgCluster.delt")
    assert wrong.returncode == 1 and "did you mean CmgCluster.delta" in wrong.stderr


@pytest.mark.slow
@pytest.mark.integration
def test_own_system_gets_a_generic_summary_and_figures(fmus, tmp_path):
    result = agilesat("run", get("scan_pitch").ssd, "--stop", 5, "--out", tmp_path)
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["scenario"] is None
    rate = summary["outputs"]["CmgCluster.delta_dot[1]"]
    results = Results.load(tmp_path)
    assert rate["max"] == results["CmgCluster.delta_dot[1]"].max()
    assert rate["final"] == results["CmgCluster.delta_dot[1]"][-1] and rate["unit"] == "rad/s"
    drift = summary["metrics"]["SatelliteDynamics.momentum_drift"]["value"]
    H = results["SatelliteDynamics.H_I"]
    assert drift == pytest.approx(np.abs(H - H[0]).max() / np.linalg.norm(H[0]))
    assert (tmp_path / "overview_CmgCluster.png").exists()
    assert str(tmp_path / "overview_SatelliteDynamics.png") in summary["figures"]


@pytest.mark.slow
@pytest.mark.integration
def test_set_a_whole_array_on_an_ssp_package(fmus, tmp_path):
    package = tmp_path / "scan_pitch.ssp"
    assert agilesat("export", "scan_pitch", "--out", package).returncode == 0
    result = agilesat(
        "run",
        package,
        "--stop",
        1,
        "--no-figures",
        "--no-report",
        "--out",
        tmp_path / "run",
        "--set",
        "SatelliteDynamics.rate0=[0.001,0,0]",
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["parameters"]["SatelliteDynamics.rate0[1]"] == {"value": 0.001, "type": "Real"}
    assert Results.load(tmp_path / "run")["SatelliteDynamics.w_BO_B[1]"][0] == pytest.approx(
        0.001, rel=1e-12
    )


@pytest.mark.slow
def test_no_derivatives_reaches_the_master(fmus, tmp_path, monkeypatch):
    """`agilesat run --no-derivatives` plans the run with derivatives=False (what it does
    there is in tests/orchestration/cosim/test_derivatives.py); without the flag, True."""
    from agilesat.orchestration import cli, runner

    seen = []

    def execute(plan):
        seen.append(plan.derivatives)
        raise ValueError("stopped before anything runs")

    monkeypatch.setattr(runner, "execute", execute)
    ssd = get("scan_pitch").ssd
    for flag in (["--no-derivatives"], []):
        assert cli.main(["run", str(ssd), "--out", str(tmp_path), "--quiet", *flag]) != 0
    assert seen == [False, True]


def test_integers_are_whole_digits_in_fmi2integers_range(fmus):
    """fmi2Integer is 32 bits: 2^32 would wrap to 0 in the FMU."""
    described = {"Gyro": Description("Gyro", fmus["Gyro"])}
    for good, value in (("7", 7), ("-2147483648", -(2**31)), ("2147483647", 2**31 - 1), (3.0, 3)):
        [typed] = typed_parameters(described, {"Gyro.seed": good}).values()
        assert (typed.type, typed.value) == ("Integer", value)
    for bad in ("2147483648", "4294967296", "-2147483649", "1_000", "1.5", "1e3", 2.5):
        with pytest.raises(SystemFileError, match=r"Gyro.seed=.*: expected an Integer from "):
            typed_parameters(described, {"Gyro.seed": bad})
