"""What keeps `agilesat run` quick to start (issue 10, first-run latency; measured by
tests/tools/benchmark_latency.py): nothing heavy imported before a command needs it, figures
drawn once per format, the same figures as before."""

import json
from pathlib import Path

import pytest

from agilesat.orchestration.output import plots
from helpers import run_python

HEAVY = ("matplotlib", "fmpy", "numpy", "lxml", "dask", "scipy")


def _imported_by(code: str) -> set[str]:
    """The top-level packages of HEAVY that ``code`` leaves in sys.modules, in a clean
    interpreter."""
    result = run_python(
        code
        + "\nimport json, sys\n"
        + f"print(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}} & {set(HEAVY)!r})))"
    )
    assert result.returncode == 0, result.stderr
    return set(json.loads(result.stdout.splitlines()[-1]))


@pytest.mark.slow  # fresh interpreters: over 1 s
def test_help_imports_nothing_heavy():
    code = (
        "from agilesat.orchestration.cli import main\n"
        "for argv in (['--help'], ['run', '--help'], ['campaign', '--help']):\n"
        "    try:\n"
        "        main(argv)\n"
        "    except SystemExit:\n"
        "        pass\n"
    )
    # `campaign --help` needs the campaign package (and so NumPy and the master)
    assert _imported_by(code.replace(", ['campaign', '--help']", "")) == set()
    assert "matplotlib" not in _imported_by(code)


@pytest.mark.slow  # fresh interpreters: over 1 s
def test_the_package_names_are_imported_on_first_use():
    assert _imported_by("import agilesat.orchestration") == set()
    assert "fmpy" in _imported_by("from agilesat.orchestration import simulate")


@pytest.mark.slow
@pytest.mark.integration
def test_a_run_without_figures_loads_no_matplotlib(fmus, tmp_path):
    code = (
        "from agilesat.orchestration.cli import main\n"
        f"assert main(['run', 'scan_pitch', '--stop', '1', '-q', '--no-figures', "
        f"'--out', {str(tmp_path)!r}]) == 0\n"
    )
    assert "matplotlib" not in _imported_by(code)


_RUN_PATH = """
import json, sys
from agilesat.orchestration.cli import main
from agilesat.orchestration.campaign.worker import run_batch
from agilesat.orchestration.cosim.options import RunOptions
options = ["--stop", "1", "-q", "--no-figures", "--no-report", "--out", sys.argv[1]]
assert main(["run", "video_sar", *options]) == 0
after_run = "scipy.stats" in sys.modules
(record,) = run_batch([(0, {})], "video_sar", RunOptions(step=0.05, stop=1.0), [], 21, share=1109)
print(json.dumps([after_run, "scipy.stats" in sys.modules, record["status"]]))
"""


@pytest.mark.slow
@pytest.mark.integration
def test_a_run_and_a_campaign_worker_load_no_scipy_stats(fmus, tmp_path):
    """SciPy's statistics package (a large part of a worker's start, issue 29) is not on a
    run's path: the pointing statistics and the pass rates use scipy.special."""
    result = run_python(_RUN_PATH, tmp_path)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout.splitlines()[-1]) == [False, False, "ok"]


@pytest.mark.slow  # imports matplotlib
def test_each_format_is_drawn_once(tmp_path, monkeypatch):
    """A figure is laid out once, then drawn once per file (savefig with a layout engine
    left on the figure would draw it once more per file just to lay it out)."""
    import numpy as np
    from matplotlib.figure import Figure

    draws = []
    draw = Figure.draw
    monkeypatch.setattr(
        Figure, "draw", lambda self, renderer: draws.append(1) or draw(self, renderer)
    )
    t = np.linspace(0.0, 10.0, 3001)
    path = plots.lines(tmp_path / "f.png", "title", t, {"a": np.sin(t), "b": np.cos(t)}, "y")
    assert [p.exists() for p in plots.formats(path)] == [True, True]
    assert len(draws) == len(plots.FORMATS)


_LOAD = """
import json, os, sys
os.environ["AGILESAT_CACHE_DIR"] = sys.argv[2]
from agilesat.orchestration.cosim.fmu import Instance, Log
instance = Instance("SatelliteDynamics", sys.argv[1], Log())
instance.instantiate()
modules = [m.__cached__ for n, m in sys.modules.items() if n.startswith("agilesat_")]
instance.free()
print(json.dumps({"folder": instance.unzip_dir, "compiled": modules}))
"""


@pytest.mark.slow
@pytest.mark.integration
def test_an_fmu_is_unpacked_and_compiled_once_per_content(fmus, tmp_path):

    cache = tmp_path / "cache"
    loads = []
    for _ in range(2):
        result = run_python(_LOAD, fmus["SatelliteDynamics"], cache)
        assert result.returncode == 0, result.stderr
        loads.append(json.loads(result.stdout.splitlines()[-1]))
    first, second = loads
    assert first["folder"] == second["folder"] and Path(first["folder"]).parent == cache / "fmus"
    assert Path(first["folder"], "modelDescription.xml").is_file()  # kept after exit
    assert [p.name for p in (cache / "fmus").iterdir()] == [Path(first["folder"]).name]
    # the FMU's code (its packed agilesat_<hash> package) loaded from compiled files
    assert first["compiled"] and all(Path(p).is_file() for p in first["compiled"])


@pytest.mark.slow
@pytest.mark.integration
def test_an_unwritable_cache_unpacks_to_a_temporary_folder(fmus, tmp_path):

    (tmp_path / "a_file").write_text("not a directory")
    result = run_python(_LOAD, fmus["SatelliteDynamics"], tmp_path / "a_file")
    assert result.returncode == 0, result.stderr
    folder = json.loads(result.stdout.splitlines()[-1])["folder"]
    assert not folder.startswith(str(tmp_path)) and not Path(folder).exists()  # removed at exit
