"""The screenshots of docs/running.md and docs/campaigns.md: reports opened in headless
Chromium (browser.py), parts of them photographed, made small (900 px wide, 96 colours).

    python tests/tools/report_screenshots.py --run out/scan_pitch --view out/video_sar \\
        --campaign out/campaign-video_sar --out docs/images

``--run``: a run's directory (the top of its report and its bounded signals); ``--view``:
a run whose 3-D view is shown at three times (10 %, 50 %, 90 % of the slider); ``--campaign``:
a campaign's directory (pass rates and an envelope).  Each report is written first if the
directory has none (``agilesat report``).
"""

from __future__ import annotations

import argparse
import io
import sys
from pathlib import Path

from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent))
import browser  # noqa: E402

WIDTH, COLOURS = 900, 96


def save(png: bytes, path: Path) -> Path:
    image = Image.open(io.BytesIO(png)).convert("RGB")
    image = image.resize((WIDTH, round(image.height * WIDTH / image.width)), Image.LANCZOS)
    image.quantize(COLOURS, dither=Image.Dither.NONE).save(path, optimize=True)
    print(f"{path} ({path.stat().st_size / 1e3:.0f} kB)")
    return path


def report(directory: Path) -> Path:
    from agilesat.orchestration.postprocess.report import write_report

    page = directory / "report.html"
    return page if page.exists() else write_report(directory)


def section(page, heading: str, until: str | None = None) -> bytes:
    """A screenshot from the heading ``heading`` to the next one (or to ``until``)."""
    top = page.locator(f"h2:text-is('{heading}')").bounding_box()
    following = page.locator(f"h2:text-is('{until}')" if until else f"h2:text-is('{heading}') ~ h2")
    bottom = following.first.bounding_box()
    return page.screenshot(
        full_page=True,
        clip={"x": 0, "y": top["y"] - 8, "width": 1300, "height": bottom["y"] - top["y"]},
    )


def run_shots(directory: Path, out: Path) -> None:
    with browser.opened(report(directory)) as (page, _):
        first = page.locator("h2").first.bounding_box()
        page.set_viewport_size({"width": 1300, "height": 1000})
        save(
            page.screenshot(
                full_page=True, clip={"x": 0, "y": 0, "width": 1300, "height": first["y"] + 560}
            ),
            out / "report-run-top.png",
        )
        save(section(page, "Signals and their bounds"), out / "report-run-bounds.png")


def view_shots(directory: Path, out: Path) -> None:
    with browser.opened(report(directory)) as (page, _):
        view = page.locator("div.figure").filter(has=page.locator(".gl-container")).first
        view.scroll_into_view_if_needed()
        rail = view.locator(".slider-rail-rect").bounding_box()
        for k, fraction in enumerate((0.1, 0.5, 0.9), 1):
            grip = view.locator(".slider-grip-rect").bounding_box()
            y = grip["y"] + grip["height"] / 2
            page.mouse.move(grip["x"] + grip["width"] / 2, y)
            page.mouse.down()
            page.mouse.move(rail["x"] + fraction * rail["width"], y, steps=2)
            page.mouse.up()
            page.wait_for_timeout(1500)
            save(view.screenshot(), out / f"report-view-{k}.png")


def campaign_shots(directory: Path, out: Path) -> None:
    with browser.opened(report(directory)) as (page, _):
        save(
            section(page, "Pass rates", "Metrics over the runs"), out / "report-campaign-rates.png"
        )
        envelope = page.locator("h2:text-is('Envelopes of the kept signals') ~ div.figure").first
        envelope.scroll_into_view_if_needed()
        save(envelope.screenshot(), out / "report-campaign-envelope.png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--run", type=Path)
    parser.add_argument("--view", type=Path)
    parser.add_argument("--campaign", type=Path)
    parser.add_argument("--out", type=Path, default=Path("docs/images"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.run:
        run_shots(args.run, args.out)
    if args.view:
        view_shots(args.view, args.out)
    if args.campaign:
        campaign_shots(args.campaign, args.out)


if __name__ == "__main__":
    main()
