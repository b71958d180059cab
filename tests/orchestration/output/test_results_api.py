"""Results as a user handles it: units, selection, degrees, names, pandas, MATLAB, CSV."""

import math

import numpy as np
import pytest

from agilesat.orchestration.output.results import ColumnError, Results, units_path

NAMES = [
    "time",
    "Sat.w_BI_B[1]",
    "Sat.w_BI_B[2]",
    "Sat.w_BI_B[3]",
    "Sat.inertia[1,1]",
    "Sat.inertia[1,2]",
    "Sat.inertia[2,1]",
    "Sat.inertia[2,2]",
    "Sat.angle",
    "Sat.mode",
]
UNITS = {
    "Sat.w_BI_B[1]": "rad/s",
    "Sat.w_BI_B[2]": "rad/s",
    "Sat.w_BI_B[3]": "rad/s",
    "Sat.inertia[1,1]": "kg.m2",
    "Sat.inertia[1,2]": "kg.m2",
    "Sat.inertia[2,1]": "kg.m2",
    "Sat.inertia[2,2]": "kg.m2",
    "Sat.angle": "rad",
    "Sat.mode": "1",
}


@pytest.fixture
def results():
    t = np.arange(11) * 0.5
    data = np.column_stack(
        [
            t,
            np.sin(t),
            np.cos(t),
            t / 10,
            *[np.full_like(t, v) for v in (10, 1, 1, 20)],
            math.pi / 2 * np.ones_like(t),
            np.round(t) % 2,
        ]
    )
    return Results(NAMES, data, {"units": UNITS, "step": 0.5})


def test_a_whole_array_by_its_base_name(results):
    assert results["Sat.w_BI_B"].shape == (11, 3)
    assert np.array_equal(results["Sat.w_BI_B"], results.vector("Sat.w_BI_B"))
    assert results.columns("Sat.inertia") == NAMES[4:8]
    assert np.array_equal(results["Sat.w_BI_B"][:, 1], results["Sat.w_BI_B[2]"])


def test_units_per_column_and_per_variable(results):
    assert results.unit("Sat.w_BI_B") == "rad/s"
    assert results.unit("Sat.inertia[2,1]") == "kg.m2"
    assert results.units["time"] == "s"


def test_degrees_on_request_only_for_angles(results):
    assert results.get("Sat.angle", deg=True)[0] == pytest.approx(90.0)
    assert np.allclose(results.get("Sat.w_BI_B", deg=True), np.degrees(results["Sat.w_BI_B"]))
    assert np.array_equal(results.get("Sat.inertia", deg=True), results["Sat.inertia"])


def test_selection_by_name_and_time_window(results):
    part = results.select("Sat.w_BI_B", "Sat.angle", start=1.0, stop=3.0)
    assert part.names == ["time", *NAMES[1:4], "Sat.angle"]
    assert list(part.time) == [1.0, 1.5, 2.0, 2.5, 3.0]
    assert part.unit("Sat.w_BI_B") == "rad/s"
    assert len(results.select(start=4.5)) == 2


def test_a_wrong_name_says_what_was_meant(results):
    with pytest.raises(ColumnError, match=r"did you mean Sat\.w_BI_B") as error:
        results["Sat.w_BI"]
    assert "np.str_" not in str(error.value)
    assert isinstance(error.value, KeyError)  # code catching KeyError still works
    with pytest.raises(KeyError, match="did you mean Sat.angle"):
        results.vector("Sat.angel")


def test_repr_reads(results):
    assert repr(results) == ("<Results: 11 rows, t = 0 … 5 s, step 0.5 s; 9 columns of Sat>")


def test_csv_keeps_units_in_a_sidecar_and_stays_readable_by_fmpy(results, tmp_path):
    from fmpy.util import read_csv

    path = results.to_csv(tmp_path / "results.csv")
    assert units_path(path).exists()
    back = Results.from_csv(path)
    assert back.unit("Sat.w_BI_B") == "rad/s" and np.array_equal(back.data, results.data)
    # fmpy splits the header at every comma, quoted or not: fine for vectors, not for a
    # matrix element's name such as PayloadGimbals.los_B[1,2]
    vectors = results.select("Sat.w_BI_B", "Sat.angle").to_csv(tmp_path / "vectors.csv")
    table = read_csv(str(vectors))
    assert np.array_equal(table["Sat.w_BI_B[2]"], results["Sat.w_BI_B[2]"])


def test_npz_keeps_units(results, tmp_path):
    back = Results.from_npz(results.to_npz(tmp_path / "r.npz"))
    assert back.units == results.units and back.names == NAMES


def test_pandas_frame_indexed_by_time_with_units(results):
    frame = results.to_pandas()
    assert list(frame.index) == list(results.time)
    assert frame.attrs["units"]["Sat.angle"] == "rad"
    assert results.to_pandas(deg=True)["Sat.angle"].iloc[0] == pytest.approx(90.0)
    assert results.to_pandas(deg=True).attrs["units"]["Sat.angle"] == "deg"


def test_matlab_file_has_one_struct_per_instance(results, tmp_path):
    from scipy.io import loadmat

    mat = loadmat(results.to_mat(tmp_path / "r.mat"), squeeze_me=False, struct_as_record=False)
    sat = mat["Sat"][0, 0]
    assert np.array_equal(sat.w_BI_B, results["Sat.w_BI_B"])
    assert np.array_equal(sat.inertia, results["Sat.inertia"])
    assert np.array_equal(mat["time"][:, 0], results.time)
    assert str(mat["units"][0, 0].Sat[0, 0].w_BI_B[0]) == "rad/s"


def test_display_units_are_those_the_model_descriptions_define(fmus, monkeypatch):
    """A metric shown in a display unit is converted by the factor its FMU's model
    description gives (any FMU's: here a gyro noise density, and a third party's "mm"),
    never by our variable tables; one that does not convert is shown in its SI unit."""
    from types import SimpleNamespace

    from agilesat.orchestration.output.summary import format_value
    from agilesat.orchestration.system import units
    from agilesat.orchestration.system.description import Description

    monkeypatch.setattr(units, "DECLARED", {})
    shown = format_value(1e-4, "rad/s0.5", "deg/h0.5")
    assert shown == "0.0001 " + units.pretty("rad/s0.5")  # no model description read yet
    Description("Gyro", fmus["Gyro"])
    shown = format_value(1e-4, "rad/s0.5", "deg/h0.5")
    assert shown == "0.3438 " + units.pretty("deg/h0.5")
    millimetre = SimpleNamespace(name="mm", factor=1000.0, offset=0.0)
    celsius = SimpleNamespace(name="degC", factor=1.0, offset=-273.15)
    units.declare([SimpleNamespace(name="m", displayUnits=[millimetre])])
    units.declare([SimpleNamespace(name="K", displayUnits=[celsius])])
    assert format_value(0.0021, "m", "mm") == "2.1 mm"
    assert format_value(300.0, "K", "degC") == "300 K"  # an offset: not a factor
