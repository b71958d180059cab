"""What keeps `agilesat run` quick to start (issue 10, first-run latency; measured by
tests/benchmark_latency.py): nothing heavy imported before a command needs it, figures
drawn once per format, the same figures as before."""

import json

import pytest

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


def test_the_package_names_are_imported_on_first_use():
    assert _imported_by("import agilesat.orchestration") == set()
    assert "fmpy" in _imported_by("from agilesat.orchestration import simulate")


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


def test_each_format_is_drawn_once(tmp_path, monkeypatch):
    """A figure is laid out once, then drawn once per file (savefig with a layout engine
    left on the figure would draw it once more per file just to lay it out)."""
    import numpy as np
    from matplotlib.figure import Figure

    from agilesat.orchestration import plots

    draws = []
    draw = Figure.draw
    monkeypatch.setattr(
        Figure, "draw", lambda self, renderer: draws.append(1) or draw(self, renderer)
    )
    t = np.linspace(0.0, 10.0, 3001)
    path = plots.lines(tmp_path / "f.png", "title", t, {"a": np.sin(t), "b": np.cos(t)}, "y")
    assert [p.exists() for p in plots.formats(path)] == [True, True]
    assert len(draws) == len(plots.FORMATS)
