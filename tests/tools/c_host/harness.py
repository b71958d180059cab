"""The C host (``fmi2_host.c``) compiled and run, and the master's results to compare it
with (tests/interop/test_c_host.py, tests/fast_paths/test_kernels.py)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from agilesat.orchestration.output.results import Results
from helpers import ROOT, run_python

SOURCE = Path(__file__).resolve().parent / "fmi2_host.c"
#: the host's whole environment: no PYTHONPATH, no LD_PRELOAD, no virtualenv on PATH
CLEAN_ENV = {"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8"}
STOP = 60.0  # s of each scenario compared: 1200 macro steps


def compile_host(directory: Path) -> Path:
    """``fmi2_host`` compiled into ``directory``."""
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    assert compiler, "the C host test needs a C compiler (cc or gcc); building FMUs does too"
    binary = Path(directory) / "fmi2_host"
    subprocess.run(
        [
            compiler,
            "-O2",
            "-Wall",
            "-Werror",
            "-I",
            str(ROOT / "fmus" / "shim"),
            "-o",
            str(binary),
            str(SOURCE),
            "-ldl",
        ],
        check=True,
    )
    return binary


def run_host(host, script, results, env=CLEAN_ENV, *options):
    return subprocess.run(
        [str(host), str(script), str(results), *options],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
    )


def read_csv(path):
    results = Results.from_csv(path)
    return results.names, results.data


def master_results(ssd, stop, out):
    """The master's run of ``ssd`` in a fresh interpreter, saved as .npz."""
    result = run_python(
        "import sys\n"
        "from agilesat.orchestration.cosim.master import simulate\n"
        "simulate(sys.argv[1], stop=float(sys.argv[2])).to_npz(sys.argv[3])\n",
        ssd,
        stop,
        out,
    )
    assert result.returncode == 0, result.stderr
    results = Results.from_npz(out)
    return results.names, results.data
