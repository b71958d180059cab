"""The ``agilesat`` pytest plugin (entry point ``pytest11``, registered by ``pip install
agilesat``; active where pytest is installed too: ``pip install agilesat pytest``).

Fixtures:

* ``agilesat_run`` (session): ``agilesat_run(target, **options)`` runs a scenario[:variant],
  a mission file ``path/to/mission.py[:variant]`` or an ``.ssd``/``.ssp`` file once per
  session for each distinct set of options (those of :func:`agilesat.orchestration.run`:
  ``step``, ``stop``, ``parameters``, ``figures``, ...) and returns ``(results, summary)``;
  the run's files are in ``summary["out_dir"]``.  A run that fails (or bad input) fails
  the test with its message, as ``agilesat run`` prints it.

Assertions (:mod:`agilesat.orchestration.postprocess.checks`, re-exported here): ``assert_within``,
``assert_settles``, ``assert_momentum_conserved``, ``assert_requirements_met``,
``assert_pointing`` (an ECSS index of a run or a campaign).
"""

from __future__ import annotations

import json

import pytest

from ..postprocess.checks import (  # noqa: F401
    assert_momentum_conserved,
    assert_pointing,
    assert_requirements_met,
    assert_settles,
    assert_within,
)


@pytest.fixture(scope="session")
def agilesat_run(tmp_path_factory):
    from ..runner import run

    cache = {}

    def run_once(target, **options):
        __tracebackhide__ = True  # a failure is the test's line and the message
        key = json.dumps([str(target), options], sort_keys=True, default=repr)
        if key not in cache:
            out = tmp_path_factory.mktemp(str(target).replace(":", "-").replace("/", "_")[-40:])
            options = {"figures": False, **options}
            failure = None
            try:
                results, summary = run(target, out_dir=out, **options)
            except (KeyError, ValueError, RuntimeError, OSError) as exc:  # as `agilesat run`
                failure = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
            if failure is not None:
                pytest.fail(f"agilesat_run({target!r}): {failure}", pytrace=False)
            summary["out_dir"] = str(out)
            cache[key] = results, summary
        return cache[key]

    return run_once
