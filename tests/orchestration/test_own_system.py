"""The "Your own mission" guide (docs/own-mission.md), run as it stands: the user's pythonfmu
FMU with two of ours, the .ssd written from Python, run, plot, and the example's pytest file
(with the plugin), which the page includes as it is."""

import os
import shlex
import subprocess
import sys

import pytest

from helpers import ROOT

GUIDE = (ROOT / "docs" / "own-mission.md").read_text(encoding="utf-8")


def commands():
    block = GUIDE.split("<!-- own-system commands -->\n```\n", 1)[1].split("```", 1)[0]
    return [line for line in block.splitlines() if line.strip()]


def test_the_guide_includes_the_example_tests_as_they_are():
    assert '--8<-- "examples/own_system/test_detumble.py"' in GUIDE


@pytest.mark.slow
@pytest.mark.integration
def test_the_guide_runs_as_written(fmus, tmp_path):
    bindir = os.path.dirname(sys.executable)
    for line in commands():
        line = line.replace("out/own_system", str(tmp_path)).replace(".venv/bin/", bindir + "/")
        result = subprocess.run(
            ["bash", "-c", line], cwd=ROOT, capture_output=True, text=True, timeout=600
        )
        assert result.returncode == 0, f"{line}\n{result.stdout}\n{result.stderr}"
        if "-m pytest" in line:
            assert "3 passed" in result.stdout
    assert (tmp_path / "detumble.png").exists() and (tmp_path / "detumble.svg").exists()
    assert (tmp_path / "run" / "overview_RateDamper.png").exists()
    assert shlex.split(commands()[0])[1] == "examples/own_system/make_system.py"
