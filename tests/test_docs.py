"""The numbers in README.md and docs/ are a run's, not a copy left to age.

A table right after a line that is a command in backticks and a colon
(`` `agilesat run TARGET [OPTIONS]`: ``) has a row per metric, its ``summary.json`` name
in backticks in the first cell; the "ours" (and "paper") cell is
checked against that run's ``summary.json`` in the metric's display unit, to the digits
printed (``0 (exactly)``: zero; ``≤ x``: a bound).  A fenced block whose first line is
``$ agilesat COMMAND`` holds lines the command prints, in order.
"""

import json
import re
import shlex
from pathlib import Path

import pytest

from agilesat.components.variables import UNITS
from agilesat.fmus import FMUS
from agilesat.orchestration.system.units import display_factor
from helpers import ROOT, agilesat

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
CHECKED = re.compile(r"^`agilesat (run [^`]+)`:\n\n((?:\|.*\n)+)", re.M)
OUTPUT = re.compile(r"^```\w*\n\$ agilesat ([^\n]+)\n(.*?)```", re.M | re.S)
NUMBER = re.compile(r"([≤<]\s*)?([+−-]?\d+(?:\.(\d+))?(?:e([+−-]?\d+))?)\s*([^\s(]*)")
PRETTY = {"°": "deg", "·": ".", "²": "2", "³": "3"}


def marked(pattern):
    """{command: [(page, match), ...]} over every page."""
    found = {}
    for page in PAGES:
        for match in pattern.finditer(page.read_text(encoding="utf-8")):
            found.setdefault(match.group(1), []).append((page.relative_to(ROOT), match))
    return found


TABLES, OUTPUTS = marked(CHECKED), marked(OUTPUT)


def cells(line: str) -> list[str]:
    return [c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]]


def check_cell(text: str, value: float, unit: str, where: str) -> None:
    """``text`` (a table cell) states ``value`` in ``unit`` to the digits it prints."""
    match = NUMBER.search(text)
    assert match, f"{where}: no number in {text!r}"
    bound, number, decimals, exponent, stated_unit = match.groups()
    stated = float(number.replace("−", "-"))
    assert "".join(PRETTY.get(c, c) for c in stated_unit) == (unit if unit != "1" else ""), (
        f"{where}: unit {stated_unit!r}, the metric's display unit is {unit!r}"
    )
    if bound:
        assert value <= stated, f"{where}: {value} is not {bound}{stated}"
    elif "exactly" in text:
        assert value == stated, f"{where}: {value}, not exactly {stated}"
    else:
        half = 0.5 * 10.0 ** (-len(decimals or "") + int((exponent or "0").replace("−", "-")))
        assert abs(value - stated) <= half * (1 + 1e-9), f"{where}: the run gives {value:.6g}"


def run_summary(command: str, tmp_path: Path) -> dict:
    result = agilesat(*shlex.split(command), "--out", tmp_path, "--no-figures", "--no-report", "-q")
    assert result.returncode in (0, 3), result.stderr  # 3: ran, requirement not met
    return json.loads((tmp_path / "summary.json").read_text())


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("command", sorted(TABLES))
def test_each_checked_table_states_its_runs_numbers(command, fmus, tmp_path):
    metrics = run_summary(command, tmp_path)["metrics"]
    for page, match in TABLES[command]:
        header, _, *rows = match.group(2).splitlines()
        columns = [c.lower() for c in cells(header)]
        for row in rows:
            row = cells(row)
            name = re.search(r"`(\w+)`", row[0])
            assert name and name.group(1) in metrics, f"{page}: no metric in {row[0]!r}"
            metric = metrics[name.group(1)]
            unit = metric.get("display_unit") or metric["unit"]
            scale = UNITS.get(metric["unit"], ({}, {}))[1].get(unit) or (
                display_factor(metric["unit"], unit) or 1.0
            )  # as the summary shows it (arcsec too)
            for column, key in (("ours", "value"), ("paper", "paper")):
                if column in columns and key in metric:  # no paper value: the paper's words
                    where = f"{page}: {command}: {name.group(1)} ({column})"
                    check_cell(row[columns.index(column)], metric[key] * scale, unit, where)


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.parametrize("command", sorted(OUTPUTS))
def test_each_quoted_output_is_what_the_command_prints(command, fmus, tmp_path):
    printed = agilesat(*shlex.split(command), cwd=tmp_path)
    assert printed.returncode == 0, printed.stderr
    lines = [line.rstrip() for line in printed.stdout.splitlines()]
    for page, match in OUTPUTS[command]:
        at = 0
        for line in match.group(2).rstrip("\n").splitlines():
            assert line.rstrip() in lines[at:], f"{page}: {line!r} not in\n{printed.stdout}"
            at = lines.index(line.rstrip(), at) + 1


def test_the_readme_lists_every_fmu_with_its_interface():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    listed = re.findall(r"^\| \[(\w+)\]\(fmus/INTERFACES\.md#(\w+)\) \|", readme, re.M)
    assert listed == [(name, name.lower()) for name in sorted(FMUS)]


def test_no_page_but_the_performance_log_keeps_a_diary():
    """No timings, test counts, machine states or commit baselines in the user documents:
    measurements go to the performance log, with their command and date."""
    diary = re.compile(
        r"this machine|last session|until this release|load average (?:of )?\d|\b\d+ tests\b"
        r"|\d ?(?:ms|µs) per (?:step|run)|\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}\b"
    )
    for page in PAGES:
        if page.name != "performance-log.md":
            text = page.read_text(encoding="utf-8")
            assert not diary.search(text), f"{page}: {diary.search(text).group(0)!r}"


def test_every_file_and_test_the_pages_name_exists():
    """A file moved or a test renamed is a page to update, not a dead pointer: every
    repository path and test name in a page's code spans exists (but the build's output)."""
    tests = "\n".join(p.read_text(encoding="utf-8") for p in (ROOT / "tests").rglob("*.py"))
    folders = "tests|examples|components|fmus|orchestration|docs"
    for page in PAGES:
        code = " ".join(re.findall(r"`([^`\n]+)`", page.read_text(encoding="utf-8")))
        for path in re.findall(rf"(?<![\w/.])((?:{folders})/[\w/.]*\w)", code):
            assert path == "fmus/build" or (ROOT / path).exists(), f"{page}: no {path}"
        for name in re.findall(r"\b(test_\w+)\b(?!\.py)", code):
            assert f"def {name}(" in tests, f"{page}: no test {name}"


def test_every_table_of_ours_against_the_paper_is_checked():
    """A slip in the line naming the command would leave a table unchecked, silently."""
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        tables = re.findall(r"^\|[^\n]*\| ours \|", text, re.M)
        assert len(tables) == len(CHECKED.findall(text)), f"{page}: a table without its command"
