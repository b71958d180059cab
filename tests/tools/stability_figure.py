"""The imaging window's stability of the shipped satellite, rigid and with its wings and
rotors (the ``flexible`` variants): the figure of docs/jitter.md (not a test).

    python tests/tools/stability_figure.py [--out docs/images/jitter-stability.png]

scan_pitch: the pitch error from the plan over the imaging phase, its |RPE| and |PDE|
(Δt = Δt_s = 1 s); video_sar: the radar's line-of-sight error over the stare and its |RPE|;
each rigid and flexible, in arcseconds (orchestration/scenarios/flexible.py).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from PIL import Image

from agilesat.orchestration import simulate
from agilesat.orchestration.mission import panels
from agilesat.orchestration.scenarios import flexible, get, scan_pitch, video_sar

ROOT = Path(__file__).resolve().parents[2]


def histories(name: str, error, window) -> dict:
    """{variant: (t, |e|, {index: (t, |index|)})} of the scenario rigid and flexible."""
    out = {}
    scenario = get(name)
    for variant in (None, "flexible"):
        results = simulate(scenario.system_file(variant))
        e = error(results)
        t = results.time
        inside = (t >= window[0] - 1e-9) & (t <= window[1] + 1e-9)
        size = np.linalg.norm(e.values[0], axis=-1)
        out[variant or "rigid"] = (t[inside], size[inside], flexible.stability(e, *window))
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs/images/jitter-stability.png")
    args = parser.parse_args(argv)
    arcsec = flexible.ARCSEC
    rows = []
    for name, error, window, what in (
        ("scan_pitch", scan_pitch.imaging_error, scan_pitch.IMAGING, "scan_pitch: pitch"),
        ("video_sar", video_sar.beam_error, video_sar.STARE, "video_sar: line of sight"),
    ):
        runs = histories(name, error, window)
        rows.append(
            (
                runs["rigid"][0],
                {v: e / arcsec for v, (_, e, _) in runs.items()},
                f"{what} error [arcsec]",
            )  # fmt: skip
        )
        for index in ("RPE", "PDE") if name == "scan_pitch" else ("RPE",):
            t = runs["rigid"][2][index][0]
            rows.append(
                (
                    t,
                    {v: s[index][1] / arcsec for v, (_, _, s) in runs.items()},
                    f"|{index}| [arcsec]",
                )  # fmt: skip
            )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    print(panels(args.out, "Imaging stability, rigid and flexible (Δt = 1 s)", rows))
    # 64 colours are every shade the lines and text have: a third of the bytes
    image = Image.open(args.out).convert("RGB")
    image.quantize(colors=64, method=Image.Quantize.MEDIANCUT).save(args.out, optimize=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
