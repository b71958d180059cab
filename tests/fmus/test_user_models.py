"""A user's model outside the repository becomes an FMU as ours do (fmus/user_models.py,
``agilesat build path/to/model.py``): validated, with its dependencies and InitialUnknowns,
rebuilt only when its source changes; what cannot be packed is refused with file and line;
the stochastic pattern (components/noise.py) is reproducible from the seed and restored
with the FMU state, checked in a fresh process as a host uses it."""

import json
import math
import shutil
import zipfile

import pytest
from fmpy import read_model_description

from agilesat.fmus.build import BuildError
from agilesat.fmus.user_models import build_model
from helpers import ROOT, agilesat, run_python

EXAMPLE = ROOT / "examples" / "own_mission" / "mode_controller.py"


@pytest.fixture(scope="module")
def built(tmp_path_factory, fmus):
    """The example's controller copied out of the repository and built there."""
    folder = tmp_path_factory.mktemp("user_model")
    model = shutil.copy(EXAMPLE, folder / "mode_controller.py")
    (fmu,) = build_model(model)
    return folder, fmu


def test_the_fmu_declares_what_its_table_says(built):
    _, fmu = built
    assert fmu.name == "ModeController.fmu" and fmu.parent.name == "build"
    md = read_model_description(fmu, validate=True)  # fmpy's own checks of the XML
    variables = {v.name: v for v in md.modelVariables}
    depends = {u.variable.name: sorted(d.name for d in u.dependencies or []) for u in md.outputs}
    assert depends["tau_cmd[1]"] == [
        *(f"q_BI[{i}]" for i in range(1, 5)),
        *(f"w_BI_B[{i}]" for i in range(1, 4)),
    ]
    assert depends["mode"] == [] and depends["w_meas[2]"] == ["w_BI_B[1]", "w_BI_B[2]", "w_BI_B[3]"]
    initial = {u.variable.name for u in md.initialUnknowns}
    assert {"tau_cmd[1]", "mode", "q_ref[4]"} <= initial
    assert variables["slew_rate"].unit == "rad/s" and variables["slew_rate"].displayUnit == "deg/s"
    assert variables["seed"].type == "Integer"
    with zipfile.ZipFile(fmu) as archive:
        packed = archive.namelist()
    assert any(n.endswith("/user/mode_controller.py") for n in packed)
    assert any(n.endswith("/components/noise.py") for n in packed)  # what it imports


def test_rebuilt_only_when_its_source_changes(built):
    folder, fmu = built
    before = fmu.stat().st_mtime_ns
    assert build_model(folder / "mode_controller.py") == [fmu]
    assert fmu.stat().st_mtime_ns == before
    source = folder / "mode_controller.py"
    source.write_text(source.read_text().replace("0.56,", "0.57,"))
    build_model(source)
    assert fmu.stat().st_mtime_ns != before
    kp = next(v for v in read_model_description(fmu).modelVariables if v.name == "kp")
    assert float(kp.start) == 0.57


@pytest.mark.parametrize(
    "line, message",
    [
        ("from . import helpers", "a relative import: a model file is packed alone"),
        (
            "from agilesat.orchestration import run",
            "imports agilesat.orchestration: a model imports only agilesat.components",
        ),
        ("import agilesat.components.noise", "write `from agilesat.components.noise import"),
        ("import helper_beside", "imports helper_beside, a module beside the model"),
    ],
)
def test_an_import_that_cannot_be_packed_is_named_with_its_line(tmp_path, line, message):
    (tmp_path / "helper_beside.py").write_text("X = 1\n")
    source = EXAMPLE.read_text().replace("import math\n", f"import math\n{line}\n", 1)
    model = tmp_path / "model.py"
    model.write_text(source)
    where = source.splitlines().index(line) + 1
    with pytest.raises(BuildError, match=f"{model}:{where}: {message}".replace("(", r"\(")):
        build_model(model)


def test_a_file_without_a_model_and_a_class_it_does_not_have(tmp_path):
    empty = tmp_path / "empty.py"
    empty.write_text("X = 1\n")
    with pytest.raises(BuildError, match="no model class"):
        build_model(empty)
    with pytest.raises(BuildError, match="has no model class 'Other'; it defines ModeController"):
        build_model(EXAMPLE, "Other", out_dir=tmp_path)


@pytest.mark.slow
@pytest.mark.integration
def test_agilesat_build_takes_a_model_file(tmp_path, fmus):
    model = shutil.copy(EXAMPLE, tmp_path / "mode_controller.py")
    result = agilesat("build", model, "--out", tmp_path / "out", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"{tmp_path / 'out' / 'ModeController.fmu'} (validated)"


NOISE = """
import ctypes, json, sys
import numpy as np
sys.path.insert(0, sys.argv[2])
from fmi_host import Fmu

RATE = {"w_BI_B[1]": 0.01, "w_BI_B[2]": -0.02, "w_BI_B[3]": 0.0}
MEASURED = ["w_meas[1]", "w_meas[2]", "w_meas[3]"]

def run(seed, steps=400, h=0.1, restore_at=None):
    fmu = Fmu(sys.argv[1], f"seed{seed}")
    assert fmu.dll.fmi2SetupExperiment(fmu.c, 0, 0.0, 0.0, 0, 0.0) == 0
    vr = (ctypes.c_uint * 1)(fmu.vr["seed"])
    assert fmu.dll.fmi2SetInteger(fmu.c, vr, 1, (ctypes.c_int * 1)(seed)) == 0
    assert fmu.dll.fmi2EnterInitializationMode(fmu.c) == 0
    assert fmu.set_real(RATE) == 0
    assert fmu.dll.fmi2ExitInitializationMode(fmu.c) == 0
    rows, saved = [], ctypes.c_void_p()
    for k in range(steps):
        if k == restore_at:
            assert fmu.dll.fmi2GetFMUstate(fmu.c, ctypes.byref(saved)) == 0
        assert fmu.step(k * h, h) == 0
        rows.append(fmu.get_real(MEASURED)[1])
    again = []
    if restore_at is not None:
        assert fmu.dll.fmi2SetFMUstate(fmu.c, saved) == 0
        for k in range(restore_at, steps):
            assert fmu.step(k * h, h) == 0
            again.append(fmu.get_real(MEASURED)[1])
    return rows, again

a, again = run(7, restore_at=200)
b, _ = run(7)
c, _ = run(8)
noise = np.array(a) - list(RATE.values())
print(json.dumps({"same": a == b, "other": a != c, "restored": again == a[200:],
                  "sd": noise.std(ddof=1, axis=0).tolist()}))
"""


@pytest.mark.slow
@pytest.mark.integration
def test_the_noise_is_seeded_reproducible_and_restored_with_the_state(built):
    """Same seed, same noise; another seed, other noise; a state taken at sample 200 and
    restored continues the same noise bit for bit; the noise's sample standard deviation is
    the parameter's (0.001 °/s) within the χ² 99.9 % band of 400 samples (about ±11 %)."""
    from scipy.stats import chi2

    from helpers import TOOLS

    _, fmu = built
    result = run_python(NOISE, fmu, TOOLS)  # a fresh interpreter, as a host
    assert result.returncode == 0, result.stderr
    found = json.loads(result.stdout.splitlines()[-1])
    assert found["same"] and found["other"] and found["restored"]
    sigma, dof = 0.001 * math.pi / 180, 399
    low, high = (sigma * math.sqrt(chi2.ppf(q, dof) / dof) for q in (0.0005, 0.9995))
    assert all(low < sd < high for sd in found["sd"]), (found["sd"], low, high)
