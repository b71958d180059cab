"""The README's "Your own system" guide, run as it stands: the user's pythonfmu FMU with two
of ours, the .ssd written from Python, run, plot, and the example's pytest file (with the
plugin).  Also checks that the README quotes the example's tests as they are."""

import os
import shlex
import subprocess
import sys

import pytest

from helpers import ROOT

README = (ROOT / "README.md").read_text()
GUIDE = README[README.index("## Your own system") :]


def commands():
    block = GUIDE.split("<!-- own-system commands -->\n```\n", 1)[1].split("```", 1)[0]
    return [line for line in block.splitlines() if line.strip()]


def test_readme_quotes_the_example_tests_verbatim():
    example = (ROOT / "examples/own_system/test_detumble.py").read_text()
    quoted = GUIDE.split("```python\n", 1)[1].split("```", 1)[0]
    assert quoted.strip() in example


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
