"""A run's progress counts simulated seconds, and an FMU's warnings are printed above the
bar, not into it (issue #28)."""

import pytest

from agilesat.orchestration.output.progress import Progress
from helpers import Stream


def test_a_runs_progress_counts_simulated_seconds_in_lines_and_in_the_bar():
    plain = Stream(False)
    with Progress("scan_pitch", stream=plain, interval=0.0) as progress:
        progress.simulating(0.05)
        progress(1000, 3000)
    assert plain.getvalue().startswith("scan_pitch: 50/150 s simulated (33 %)")
    tty = Stream(True)
    with Progress("scan_pitch", stream=tty) as progress:
        progress.simulating(0.05)
        progress(1000, 3000)
        assert "50/150 s simulated" in str(progress.bar)  # as drawn now


def test_a_message_while_the_bar_is_shown_gets_a_line_of_its_own():
    tty = Stream(True)
    with Progress("scan_pitch", stream=tty) as progress:
        progress(10, 100)
        progress.write("  FMU: t=0.5 s CmgCluster [Warning] rate limit")
        progress(20, 100)
    lines = tty.getvalue().replace("\r", "\n").split("\n")
    said = [line for line in lines if "FMU:" in line]
    assert said == ["  FMU: t=0.5 s CmgCluster [Warning] rate limit"]  # nothing of the bar


@pytest.mark.slow
def test_the_runner_makes_a_progress_count_simulated_seconds(fmus):
    from agilesat.orchestration.runner import run

    plain = Stream(False)
    with Progress("scan_pitch", stream=plain, interval=0.0) as progress:
        run("scan_pitch", stop=2.0, figures=False, progress=progress)
    assert "2/2 s simulated (100 %)" in plain.getvalue()
