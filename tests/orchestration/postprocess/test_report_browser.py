"""``agilesat report`` as a person sees it: the pages ``agilesat run`` and ``agilesat
campaign`` write by default, opened from disk in headless Chromium (tests/tools/browser.py):
every plot drew its lines, nothing went to the console as an error, the 3-D view is not
blank and dragging its time slider moves the spacecraft (in plotly's data and on the
screen), the campaign's table sorts by a click on a column's header."""

import io

import browser
import numpy as np
import pytest

from helpers import agilesat

pytestmark = [pytest.mark.slow, pytest.mark.integration]

SPACECRAFT = """(div) => {
  const trace = div._fullData.find((t) => t.name === "spacecraft");
  return [trace.x[0], trace.y[0], trace.z[0]];
}"""


def pixels(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def lines_drawn(page) -> list[int]:
    """Per figure drawn: the number of its 2-D lines with points (SVG 'd' longer than a
    move) and bars."""
    return page.evaluate(
        """Array.from(document.querySelectorAll('div.figure[data-state=drawn]'))
             .map((d) => Array.from(d.querySelectorAll(
                 '.scatterlayer path.js-line, .barlayer .point path'))
               .filter((p) => (p.getAttribute('d') || '').length > 20).length)"""
    )


def test_a_run_s_report_draws_and_its_slider_moves_the_spacecraft(scan_pitch_run):
    out = scan_pitch_run[0]
    with browser.opened(out / "report.html") as (page, problems):
        assert page.evaluate("document.body.dataset.failed") == ""
        assert int(page.evaluate("document.body.dataset.drawn")) >= 3
        browser.open_section(page)  # an instance's outputs, drawn on opening
        assert (
            page.evaluate("document.querySelectorAll('div.figure[data-state=drawn]').length") >= 4
        )
        assert (
            page.evaluate("document.querySelectorAll('div.figure[data-state=failed]').length") == 0
        )
        assert all(n >= 1 for n in lines_drawn(page)), lines_drawn(page)
        view = page.locator("div.figure").filter(has=page.locator(".gl-container")).first
        view.scroll_into_view_if_needed()
        before, shown = pixels(view.screenshot()), view.evaluate(SPACECRAFT)
        scenes = slice(0, int(0.6 * len(before)))  # the 3-D panels, above the actuators'
        assert len(np.unique(before[scenes].reshape(-1, 3), axis=0)) > 200  # drawn, not blank
        rail = view.locator(".slider-rail-rect").bounding_box()
        grip = view.locator(".slider-grip-rect").bounding_box()
        y = grip["y"] + grip["height"] / 2
        page.mouse.move(grip["x"] + grip["width"] / 2, y)
        page.mouse.down()
        page.mouse.move(rail["x"] + 0.8 * rail["width"], y, steps=2)
        page.mouse.up()
        page.wait_for_function(
            f"(() => {{ const d = document.querySelector("
            f"'div.figure[data-state=drawn] .gl-container').closest('div.figure');"
            f" return ({SPACECRAFT})(d)[0] !== {shown[0]}; }})()"
        )
        moved = view.evaluate(SPACECRAFT)
        after = pixels(view.screenshot())
        assert np.linalg.norm(np.subtract(moved, shown)) > 100  # km along the orbit
        changed = (np.abs(after - before).sum(-1) > 60)[scenes]
        assert changed.sum() > 500  # the scene was drawn again where it moved
    assert not problems, problems


def test_a_campaign_s_report_draws_and_sorts(tmp_path):
    out = tmp_path / "c"
    made = agilesat(
        "campaign",
        "scan_pitch",
        "--runs",
        "3",
        "--stop",
        "40",
        "--seed",
        "1",
        "--keep",
        "SatelliteDynamics.w_BO_B",
        "--workers",
        "1",
        "--out",
        out,
        "-q",
    )
    assert made.returncode in (0, 3), made.stderr
    with browser.opened(out / "report.html") as (page, problems):
        assert page.evaluate("document.body.dataset.failed") == ""
        assert all(n >= 1 for n in lines_drawn(page)), lines_drawn(page)
        table = page.locator("table[data-table]").first
        headers = table.locator("th").all_inner_texts()
        column = headers.index("seconds")
        cells = f"td:nth-child({column + 1})"

        def seconds():
            return [float(x) for x in table.locator(f"tbody tr {cells}").all_inner_texts()]

        assert len(seconds()) == 3
        table.locator("th").nth(column).click()
        assert seconds() == sorted(seconds())
        table.locator("th").nth(column).click()
        assert seconds() == sorted(seconds(), reverse=True)
    assert not problems, problems


def test_no_report_leaves_none_of_an_earlier_run(tmp_path):
    """``--no-report`` writes no report.html and removes the one an earlier run left
    (it would show that run as this one); the report is written by default."""
    first = agilesat("run", "scan_pitch", "--stop", "2", "--no-figures", "--out", tmp_path, "-q")
    assert first.returncode == 0, first.stderr
    assert (tmp_path / "report.html").exists()
    second = agilesat(
        "run", "scan_pitch", "--stop", "1", "--no-figures", "--no-report", "--out", tmp_path, "-q"
    )
    assert second.returncode == 0, second.stderr
    assert not (tmp_path / "report.html").exists()
