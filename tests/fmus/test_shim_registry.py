"""The shim's registry of live instances (fmus/shim/agilesat_fmi2.c): every FMI call finds
its instance in the slots it reads without the lock, or in the list under it (instances
beyond the slots, and anything not live).  Built on a stand-in for pythonfmu's binary
(tests/tools/c_host/fake_inner.c), in a child process; about 2 s (two compiles)."""

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from agilesat.fmus.build import SHIM_C_FILES, SHIM_LIBRARIES, shim_flags

HERE = Path(__file__).resolve().parent
SHIM_DIR = SHIM_C_FILES[0].parent

#: more instances than the shim's slots (N_SEEN = 64): some live in the list only
CHILD = r"""
import ctypes, json, sys, tempfile
from pathlib import Path
dll = ctypes.CDLL(sys.argv[1])
dll.fmi2Instantiate.restype = ctypes.c_void_p
dll.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                                ctypes.c_char_p, ctypes.c_void_p, ctypes.c_int, ctypes.c_int]
dll.fmi2DoStep.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
dll.fmi2FreeInstance.argtypes = [ctypes.c_void_p]
resources = Path(tempfile.mkdtemp(), "resources")
resources.mkdir()
(resources / "slavemodule.txt").write_text("fake")
callbacks = (ctypes.c_void_p * 5)()  # no logger: the shim logs nothing
def new():
    return dll.fmi2Instantiate(b"fake", 1, b"{0}", resources.as_uri().encode(),
                               ctypes.addressof(callbacks), 0, 0)
live = [new() for _ in range(70)]
answer = {"distinct": len(set(live)) == 70 and all(live)}
answer["steps"] = [dll.fmi2DoStep(c, 0.0, 0.05, 1) for c in live]
freed = [live.pop(3), live.pop(-2)]  # one in a slot, one in the list only
for c in freed:
    dll.fmi2FreeInstance(c)
answer["freed"] = [dll.fmi2DoStep(c, 0.0, 0.05, 1) for c in freed]
answer["still"] = [dll.fmi2DoStep(c, 0.0, 0.05, 1) for c in live]
again = new()  # takes the free slot
answer["again"] = dll.fmi2DoStep(again, 0.0, 0.05, 1)
for c in live + [again]:
    dll.fmi2FreeInstance(c)
answer["all_freed"] = sorted({dll.fmi2DoStep(c, 0.0, 0.05, 1) for c in live + [again]})
print(json.dumps(answer))
"""


def _compile(sources, output: Path, *flags: str) -> None:
    command = ["cc", "-O2", "-Wall", "-Werror", "-I", str(SHIM_DIR), *flags, "-o", str(output)]
    subprocess.run([*command, *map(str, sources), "-ldl"], check=True)


@pytest.mark.slow
def test_calls_find_live_instances_in_slots_and_beyond_and_refuse_freed_ones():
    ok, error = 0, 3  # fmi2OK, fmi2Error
    with tempfile.TemporaryDirectory() as directory:
        folder = Path(directory)
        _compile(
            [HERE.parent / "tools" / "c_host" / "fake_inner.c"],
            folder / "pythonfmu-export.so",
            "-shared",
            "-fPIC",
        )
        _compile(SHIM_C_FILES, folder / "Fake.so", *shim_flags("", "", "3.0"), *SHIM_LIBRARIES)
        run = subprocess.run(
            [sys.executable, "-c", CHILD, str(folder / "Fake.so")],
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert run.returncode == 0, run.stderr[-800:]
    answer = json.loads(run.stdout.strip().splitlines()[-1])
    assert answer["distinct"]
    assert answer["steps"] == [ok] * 70
    assert answer["freed"] == [error, error]
    assert answer["still"] == [ok] * 68
    assert answer["again"] == ok
    assert answer["all_freed"] == [error]
