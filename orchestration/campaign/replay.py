"""The ``agilesat run`` commands that make a campaign's runs again: each failure's replay in
campaign.json, the nominal run's command, and what it was made with (``versions``)."""

from __future__ import annotations

import platform
import shlex
from importlib import metadata

from .plan import Plan


def replay_arguments(plan: Plan, index: int) -> list[str]:
    """``agilesat run`` arguments that make run ``index`` again, exactly."""
    return run_arguments(plan, plan.parameters(index))


def run_arguments(plan: Plan, parameters: dict) -> list[str]:
    """``agilesat run`` arguments of a run of the campaign's target and settings with
    ``parameters`` set."""
    args = ["agilesat", "run", plan.spec.target]
    for option, value in (
        ("--step", plan.spec.step),
        ("--stop", plan.spec.stop),
        ("--algorithm", plan.spec.algorithm),
    ):
        if value is not None:
            args += [option, repr(value) if isinstance(value, float) else str(value)]
    for key, value in parameters.items():
        args += ["--set", f"{key}={value!r}" if isinstance(value, float) else f"{key}={value}"]
    return args


def replay_template(plan: Plan) -> str:
    return (
        shlex.join(replay_arguments(plan, 0)[:3]) + " [--step/--stop/--algorithm as "
        "the spec] --set KEY=VALUE for every --set of the spec and every dispersed "
        "column of the run's row in runs.csv"
    )


def versions() -> dict:
    result = {"python": platform.python_version(), "platform": platform.platform()}
    for package in ("agilesat", "numpy", "fmpy", "pythonfmu", "dask", "distributed", "scipy"):
        try:
            result[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            result[package] = None
    return result
