"""What keeps `agilesat run` quick to start (issue 10, first-run latency; measured by
tests/tools/benchmark_latency.py): nothing heavy imported before a command needs it, figures
drawn once per format, the same figures as before."""

import json
import os
import time
import warnings
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


@pytest.mark.slow  # fresh interpreters: over 1 s
def test_campaign_is_named_in_help_as_the_campaign_package_says():
    code = (
        "import argparse\n"
        "from agilesat.orchestration import cli\n"
        "from agilesat.orchestration.campaign import cli as campaign_cli\n"
        "commands = argparse.ArgumentParser().add_subparsers()\n"
        "campaign_cli.add_parser(commands)\n"
        "action = commands._choices_actions[0]\n"
        "assert action.help == cli.CAMPAIGN_HELP, (action.help, cli.CAMPAIGN_HELP)\n"
    )
    result = run_python(code)
    assert result.returncode == 0, result.stderr


@pytest.mark.slow
@pytest.mark.integration
def test_a_run_without_figures_loads_no_matplotlib(fmus, tmp_path):
    code = (
        "from agilesat.orchestration.cli import main\n"
        f"assert main(['run', 'scan_pitch', '--stop', '1', '-q', '--no-figures', "
        f"'--out', {str(tmp_path)!r}]) == 0\n"
    )
    assert "matplotlib" not in _imported_by(code)


@pytest.mark.slow  # imports matplotlib
def test_each_format_is_drawn_once(tmp_path, monkeypatch):
    """A figure is laid out once, then drawn once per file (savefig with a layout engine
    left on the figure would draw it once more per file just to lay it out)."""
    import numpy as np
    from matplotlib.figure import Figure

    from agilesat.orchestration.output import plots

    draws = []
    draw = Figure.draw
    monkeypatch.setattr(
        Figure, "draw", lambda self, renderer: draws.append(1) or draw(self, renderer)
    )
    t = np.linspace(0.0, 10.0, 3001)
    path = plots.lines(tmp_path / "f.png", "title", t, {"a": np.sin(t), "b": np.cos(t)}, "y")
    assert [p.exists() for p in plots.formats(path)] == [True, True]
    assert len(draws) == len(plots.FORMATS)


def _figures(results, out_dir):
    """Four figures through plots (a module-level function: it pickles by name)."""
    import numpy as np

    from agilesat.orchestration.output import plots

    t = np.linspace(0.0, 1.0, 50)
    return [
        plots.lines(out_dir / f"f{k}.png", f"figure {k}", t, {"y": t**k}, "y") for k in range(4)
    ]


def _failing(results, out_dir):
    from agilesat.orchestration.output import plots

    plots.lines(out_dir / "ok.png", "fine", [0.0, 1.0], {"y": [0.0, 1.0]}, "y")
    raise ValueError("figure code failed here")


def _note(path, panels: int, log: Path, fail: bool = False) -> Path:
    """A stand-in figure of ``panels`` panels: notes (process, figure) in ``log``."""
    with open(log, "a") as f:
        f.write(f"{os.getpid()} {Path(path).name}\n")
    time.sleep(0.1)
    if fail:
        raise ValueError(f"could not draw {Path(path).name}")
    return Path(path)


_noted = plots._shared(lambda a: (a["panels"], 0))(_note)
PANELS = (1, 3, 2, 3, 1)
HEAVIEST_FIRST = ["f1.png", "f3.png", "f2.png", "f0.png", "f4.png"]


def _noting(results, out_dir, fail=()):
    """Figures of PANELS panels, noted in out_dir/log (those in ``fail`` fail), and one
    line it writes itself in out_dir/itself."""
    with open(out_dir / "itself", "a") as f:
        f.write(f"{os.getpid()}\n")
    return [
        _noted(out_dir / f"f{k}.png", n, out_dir / "log", fail=k in fail)
        for k, n in enumerate(PANELS)
    ]


def _failing_figures(results, out_dir):
    return _noting(results, out_dir, fail=(0, 1))


def _noted_lines(out_dir: Path) -> list[list[str]]:
    return [line.split() for line in (out_dir / "log").read_text().splitlines()]


def test_figures_are_recorded_with_their_cost_and_drawn_heaviest_first(monkeypatch):
    from agilesat.orchestration.output.figure_pool import heaviest_first

    monkeypatch.setattr(plots, "recording", [])
    t = [0.0, 1.0]
    returned = [
        plots.lines("a.png", "a", t, {"y": t, "z": t}, "y"),
        plots.panels("b.png", "b", [(t, {"y": t}, "y"), (t, {"y": t, "z": t}, "z", {})]),
        plots.lines("c.png", "c", t, {"y": t, "z": t, "w": t}, "y"),
        plots.panels("d.png", "d", [(t, {"y": t, "z": t}, "y")], xlabel="x"),
    ]
    assert returned == [Path(p) for p in ("a.png", "b.png", "c.png", "d.png")]
    drawings = plots.recording
    assert [d.cost for d in drawings] == [(1, 2), (2, 3), (1, 3), (1, 2)]
    assert [drawings[k].path.name for k in heaviest_first(drawings)] == [
        "b.png",
        "c.png",
        "a.png",  # ties in the order made
        "d.png",
    ]
    assert drawings[3].kwargs == {"xlabel": "x"}


def test_claims_give_each_figure_to_one_process_as_they_go():
    import os

    from agilesat.orchestration.output.figure_pool import Claims

    claims = Claims()
    other = Claims.__new__(Claims)  # a second process: the same pipe, its own walk
    other.__dict__.update(claims.__dict__)
    taken = []
    for k in range(6):  # both walk every figure; one takes it, the other skips it
        first, second = (claims, other) if k % 2 else (other, claims)
        taken.append((first(), second()))
    assert taken == [(True, False)] * 6
    os.close(claims._read), os.close(claims._write)


@pytest.fixture
def importable(monkeypatch):
    """This module importable in a worker (it pickles its figure functions by name), and
    any fall-back to drawing in the calling process an error."""

    monkeypatch.setenv("PYTHONPATH", str(Path(__file__).parent))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


@pytest.mark.slow
def test_a_pool_writes_the_figures_one_process_writes(tmp_path, importable):
    import numpy as np
    from PIL import Image

    from agilesat.orchestration.output.figure_pool import FigurePool

    (tmp_path / "here").mkdir(), (tmp_path / "pool").mkdir()
    here = _figures(None, tmp_path / "here")
    with FigurePool(3, (__name__,)) as pool:
        drawn = pool.draw(_figures, None, tmp_path / "pool")
    assert [p.name for p in drawn] == [p.name for p in here]
    for path in here:
        for twin in (path, path.with_suffix(".svg")):
            assert (tmp_path / "pool" / twin.name).exists()
        pixels = [
            np.asarray(Image.open(d / path.name)) for d in (tmp_path / "here", tmp_path / "pool")
        ]
        assert np.array_equal(*pixels)


@pytest.mark.slow
def test_a_pool_writes_the_formats_of_its_caller(tmp_path, importable):
    from agilesat.orchestration.output.figure_pool import FigurePool

    with FigurePool(2, (__name__,)) as pool:
        with plots.written_as((".png",)):
            drawn = pool.draw(_figures, None, tmp_path)
    assert sorted(p.name for p in tmp_path.glob("*.*")) == sorted(p.name for p in drawn)


@pytest.mark.slow
def test_a_pool_raises_the_figure_codes_error_and_draws_a_closure_here(tmp_path, importable):
    from agilesat.orchestration.output.figure_pool import FigurePool

    with FigurePool(2, (__name__,)) as pool:
        with pytest.raises(ValueError, match="figure code failed here"):
            pool.draw(_failing, None, tmp_path)
    assert (tmp_path / "ok.png").exists()  # made before the error: drawn, as in one process
    with FigurePool(2) as pool:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            drawn = pool.draw(lambda r, out: _figures(r, out), None, tmp_path)
    assert pool.worker.returncode is not None  # sent nothing: stopped, not left waiting
    assert len(caught) == 1 and str(caught[0].message).startswith(
        "figures drawn in this process: the figure worker failed: the figure call cannot be "
        "sent to it"
    )
    assert all(p.exists() for p in drawn)


@pytest.mark.slow
def test_a_pool_draws_each_recorded_figure_once_heaviest_first(tmp_path, importable):
    from agilesat.orchestration.output.figure_pool import FigurePool

    for processes in (1, 3):
        out = tmp_path / str(processes)
        out.mkdir()
        with FigurePool(processes, (__name__,)) as pool:
            drawn = pool.draw(_noting, None, out)
        assert drawn == [out / f"f{k}.png" for k in range(len(PANELS))]
        noted = _noted_lines(out)
        # the figure function ran once (what it writes itself is written once)
        assert len((out / "itself").read_text().splitlines()) == 1
        if processes == 1:
            assert [name for _, name in noted] == HEAVIEST_FIRST
        else:  # each figure once, shared out among the processes
            assert sorted(name for _, name in noted) == sorted(HEAVIEST_FIRST)
            assert len({pid for pid, _ in noted}) > 1


@pytest.mark.slow
def test_a_pool_raises_the_error_of_the_first_figure_that_failed(tmp_path, importable):
    from agilesat.orchestration.output.figure_pool import FigurePool

    with FigurePool(2, (__name__,)) as pool:
        with pytest.raises(ValueError, match="could not draw f0.png"):  # f1 failed first
            pool.draw(_failing_figures, None, tmp_path)
    assert sorted(name for _, name in _noted_lines(tmp_path)) == sorted(HEAVIEST_FIRST)


def test_a_fork_refused_leaves_the_figures_to_the_processes_there_are(tmp_path, monkeypatch):
    """``os.fork`` failing (EAGAIN at a process limit) used to stop the worker, and the run
    drew every figure again beside the children already forked."""
    import errno

    from agilesat.orchestration.output import figure_pool

    def refused():
        raise OSError(errno.EAGAIN, "Resource temporarily unavailable")

    monkeypatch.setattr(figure_pool.os, "fork", refused)
    status, drawn = figure_pool._draw(3, _noting, (None, tmp_path))
    assert status == "ok" and drawn == [tmp_path / f"f{k}.png" for k in range(len(PANELS))]
    assert [name for _, name in _noted_lines(tmp_path)] == HEAVIEST_FIRST  # here, in order


@pytest.mark.slow
def test_a_long_runs_figures_are_drawn_here_not_sent(tmp_path, importable, monkeypatch):
    """Rows past MAX_SENT_BYTES are not pickled to the worker (twice their memory)."""
    import numpy as np

    from agilesat.orchestration.output import figure_pool
    from agilesat.orchestration.output.results import Results

    rows = Results(["time", "y"], np.zeros((1000, 2)))
    monkeypatch.setattr(figure_pool, "MAX_SENT_BYTES", rows.data.nbytes - 1)
    monkeypatch.setattr(figure_pool.pickle, "dumps", None)  # nothing may be sent
    with figure_pool.FigurePool(2, (__name__,)) as pool:
        drawn = pool.draw(_noting, rows, tmp_path)
    assert pool.worker.returncode is not None  # sent nothing: stopped
    assert {int(pid) for pid, _ in _noted_lines(tmp_path)} == {os.getpid()}
    assert drawn == [tmp_path / f"f{k}.png" for k in range(len(PANELS))]


class _TwoArguments(Exception):
    def __init__(self, what, where):
        super().__init__(f"{what} at {where}")


def _failing_oddly(results, out_dir):
    raise _TwoArguments("an error pickle cannot rebuild", "figure 0")


@pytest.mark.slow
def test_a_pool_raises_the_text_of_an_error_that_does_not_unpickle(tmp_path, importable):
    """Pickled, such an error raised TypeError (its __init__'s arguments) in the caller."""
    from agilesat.orchestration.output.figure_pool import FigurePool

    with FigurePool(2, (__name__,)) as pool:
        with pytest.raises(RuntimeError, match="an error pickle cannot rebuild at figure 0"):
            pool.draw(_failing_oddly, None, tmp_path)


@pytest.mark.slow
def test_a_module_that_prints_as_it_is_imported_leaves_the_reply_whole(
    tmp_path, importable, monkeypatch
):
    """The worker's stdout is its reply: a preloaded module's print went into it and the
    figures were drawn a second time in the run's process (a warning, an error here)."""
    from agilesat.orchestration.output.figure_pool import FigurePool

    (tmp_path / "noisy_figures.py").write_text("print('imported' * 1000)\n")
    monkeypatch.setenv("PYTHONPATH", f"{Path(__file__).parent}{os.pathsep}{tmp_path}")
    with FigurePool(2, (__name__, "noisy_figures")) as pool:
        drawn = pool.draw(_figures, None, tmp_path)
    assert all(p.exists() for p in drawn)


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
    from pathlib import Path

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
    from pathlib import Path

    (tmp_path / "a_file").write_text("not a directory")
    result = run_python(_LOAD, fmus["SatelliteDynamics"], tmp_path / "a_file")
    assert result.returncode == 0, result.stderr
    folder = json.loads(result.stdout.splitlines()[-1])["folder"]
    assert not folder.startswith(str(tmp_path)) and not Path(folder).exists()  # removed at exit


@pytest.mark.slow
@pytest.mark.integration
def test_an_interrupted_run_stops_its_figure_worker_at_once(fmus, tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    process = subprocess.Popen(
        [sys.executable, "-m", "agilesat.orchestration", "run", "scan_pitch", "-q"]
        + ["--out", str(tmp_path)],
        env={**os.environ, "AGILESAT_FIGURE_PROCESSES": "2"},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    children = Path(f"/proc/{process.pid}/task/{process.pid}/children")
    deadline = time.monotonic() + 120
    while (
        not (tmp_path / "results.csv").exists()
        or len((tmp_path / "results.csv").read_text().splitlines()) < 50
    ):
        assert time.monotonic() < deadline and process.poll() is None
        time.sleep(0.05)
    workers = children.read_text().split()
    assert len(workers) == 1  # the figure worker, started with the run
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130 and "Traceback" not in stderr, stderr
    assert not Path(f"/proc/{workers[0]}").exists()  # stopped and reaped
    assert json.loads((tmp_path / "summary.json").read_text())["status"] == "interrupted"
    assert not list(tmp_path.glob("*.png"))


@pytest.mark.parametrize(
    ("cores", "load", "env", "expected"),
    [
        (2, 0.2, None, 2),  # a free core: a worker
        (2, 1.5, None, 2),
        (2, 1.6, None, 0),  # saturated: drawn in the command
        (1, 0.0, None, 0),  # one core
        (16, 0.0, None, 8),  # at most 8
        (2, 3.0, "3", 3),  # $AGILESAT_FIGURE_PROCESSES decides
        (8, 0.0, "0", 0),
    ],
)
def test_a_figure_worker_only_where_a_core_is_free(monkeypatch, cores, load, env, expected):
    import os

    from agilesat.orchestration.output import figure_pool

    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(cores)))
    monkeypatch.setattr(os, "getloadavg", lambda: (load, load, load))
    if env is None:
        monkeypatch.delenv("AGILESAT_FIGURE_PROCESSES", raising=False)
    else:
        monkeypatch.setenv("AGILESAT_FIGURE_PROCESSES", env)
    assert figure_pool.processes_for_figures() == expected
