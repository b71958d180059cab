"""``agilesat stare``: video_sar over a pass of a real satellite ([Liang 2019]).

:func:`tle_pass` finds, for a real satellite's two-line elements, a target and a search
window, the zero-Doppler passes (SGP4 inside OrbitEnvironment), and :func:`pass_scenario`
makes the ``video_sar`` scenario for one of them: 200 s centred on zero Doppler, the
satellite starting on the reference.
"""

from __future__ import annotations

import datetime
import math
import re
from pathlib import Path

from ...components.ephemeris import J2000, format_epoch, load_tle, parse_epoch, tle_epoch
from ..mission import Scenario
from ..scenarios.video_sar import GUIDANCE, HALF_STARE, SCENARIO, TARGET, make_system
from .passes import find_passes

DEG = math.pi / 180


def tle_pass(
    line1: str,
    line2: str,
    target=TARGET,
    epoch=None,
    hours: float = 24.0,
    look_angle: float | None = None,
    max_look_angle: float = 60 * DEG,
):
    """(OrbitEnvironment parameters of the stare, the chosen pass, every pass found).

    Searches ``hours`` from ``epoch`` (default: the TLE's epoch) for zero-Doppler passes
    with the target visible and at most ``max_look_angle`` off nadir; takes the one whose
    look angle is closest to ``look_angle``, or the first.  The parameters date t = 0 at
    zero Doppler − 100 s.  ValueError if there is no such pass.
    """
    search = {
        "tle_line1": line1,
        "tle_line2": line2,
        "epoch": "" if epoch is None else format_epoch(search_start(line1, line2, epoch)),
        **dict(zip(("target_lat", "target_lon", "target_alt"), target)),
    }
    start = search_start(line1, line2, epoch)
    passes = [
        g
        for g in find_passes(search, 0.0, hours * 3600.0)
        if g.look_angle <= max_look_angle and g.time >= HALF_STARE
    ]
    if not passes:
        raise ValueError(
            f"no pass within {math.degrees(max_look_angle):g}° off nadir in "
            f"{hours:g} h from {format_epoch(start)}"
        )
    chosen = (
        passes[0]
        if look_angle is None
        else min(passes, key=lambda g: abs(g.look_angle - look_angle))
    )
    orbit = dict(
        search, epoch=format_epoch(start + datetime.timedelta(seconds=chosen.time - HALF_STARE))
    )
    return orbit, chosen, passes


def search_start(line1: str, line2: str, epoch=None) -> datetime.datetime:
    """The UTC start of a pass search: ``epoch`` (ISO 8601; a date alone is its 00:00),
    else the TLE's epoch.  A pass's ``time`` counts seconds from it."""
    if epoch is None:
        days, seconds = tle_epoch(load_tle(line1, line2))
        return J2000 + datetime.timedelta(days=days, seconds=seconds)
    if isinstance(epoch, str) and re.fullmatch(r"\d{4}-\d{2}-\d{2}", epoch.strip()):
        epoch = epoch.strip() + "T00:00:00"
    return parse_epoch(epoch)


def pass_scenario(orbit: dict, out_dir: Path, yaw_compensation: bool = True) -> Scenario:
    """This scenario for another pass (``orbit``: OrbitEnvironment parameters, t = 0 at the
    start of the stare), its system also written to ``out_dir/video_sar.ssd`` (its
    ``ssd``; the FMUs of fmus/build)."""
    system = make_system(orbit, dict(GUIDANCE, yaw_compensation=yaw_compensation))
    scenario = Scenario(
        SCENARIO.name,
        SCENARIO.title,
        system,
        metrics=SCENARIO.metrics,
        requirements=SCENARIO.requirements,
        figures=SCENARIO.figures,
        diagnose=SCENARIO.diagnose,
        systems_dir=out_dir,
    )
    system.write(scenario.ssd)
    return scenario
