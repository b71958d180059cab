"""Fault injection on our FMU binary (the C shim and the slave) and its resource figures.

``CASES``: each a function that drives a built FMU in a *separate process* (fmpy/ctypes
calls as any host makes them, or the C host ``tests/tools/c_host/hostile_host.c``) and returns
``{"fault", "expected", "observed", "ok"}``: what was done, what must happen, what did
(statuses, messages, or the signal that killed the process).

``resource_figures(n)``: (figure, value) rows measured in fresh processes: memory and
memory mappings after ``n`` ``simulate()`` calls, after ``n`` instantiate/free cycles of
one FMU, and the memory of one live instance.

The child processes run this file: ``python fault_cases_fmu.py CASE [ARGS]`` prints the
case's observations as JSON.  They use ``fmi_host`` (a plain fmpy host, no agilesat).
``python tests/tools/fault_cases_fmu.py figures N`` prints the resource figures.
"""

from __future__ import annotations

import ctypes
import functools
import json
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
BUILD = Path(os.environ.get("AGILESAT_FAULT_FMUS", ROOT / "fmus" / "build"))
FMU, OTHER = "AttitudeController", "CmgCluster"  # two small FMUs


# -- the parent side: one child process per case ------------------------------------------
def _child(
    case: str, *args, timeout: float = 300, script: Path | None = None, env=None
) -> tuple[dict | None, str]:
    """(the child's JSON answer or None, what happened to the process): ``case`` of this
    file (or of ``script``), with ``env`` added to the environment."""
    run = subprocess.run(
        [sys.executable, str(script or Path(__file__)), case, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=ROOT,
        env={**os.environ, **(env or {})},
    )
    if run.returncode < 0:
        return None, f"killed by signal {-run.returncode}; stderr: {run.stderr[-400:]}"
    lines = run.stdout.strip().splitlines()
    if run.returncode != 0 or not lines:
        return None, f"exit code {run.returncode}; stderr: {run.stderr[-600:]}"
    return json.loads(lines[-1]), "exit code 0"


def _case(fault: str, expected: str, child: str, want: dict, *args):
    """A case whose child answers a dict that must contain ``want``."""

    def run():
        answer, process = _child(child, *args)
        ok = answer is not None and all(answer.get(k) == v for k, v in want.items())
        observed = process if answer is None else f"{process}; {json.dumps(answer)}"
        return {"fault": fault, "expected": expected, "observed": observed, "ok": ok}

    run.__name__ = child
    return run


ERROR = 3
CASES = [
    _case(
        "fmi2FreeInstance twice, then exit",
        "no crash, clean exit",
        "double_free",
        {"exit": "clean"},
    ),
    _case(
        "fmi2DoStep, fmi2GetReal, fmi2SetReal, fmi2Terminate, fmi2GetFMUstate on a freed instance",
        "fmi2Error for each, no crash",
        "call_after_free",
        {"statuses": [ERROR] * 5},
    ),
    _case(
        "calls on NULL and on a made-up instance handle (the derivative calls too)",
        "fmi2Error for each, no crash",
        "garbage_handle",
        {"statuses": [ERROR] * 6},
    ),
    _case(
        "NULL value-reference, value and string arrays with n > 0; a NULL string; NULL categories",
        "fmi2Error with a message for each; the instance still steps",
        "null_arrays",
        {"statuses": [ERROR] * 7, "messages": 7, "step_after": 0},
    ),
    _case(
        "fmi2SetFMUstate(NULL), a freed state, a state of another instance and of "
        "another FMU; fmi2FreeFMUstate twice",
        "fmi2Error with a message for each; both instances still step",
        "wrong_states",
        {"statuses": [ERROR] * 5, "messages": 5, "steps_after": [0, 0]},
    ),
    _case(
        "fmi2DeSerializeFMUstate of random bytes, of truncated bytes, of another FMU's "
        "state, of a wrong format version, and of empty bytes",
        "fmi2Error naming the reason for each; the instance still steps and restores a valid state",
        "garbage_bytes",
        {"statuses": [ERROR] * 5, "reasons": True, "step_after": 0, "valid_restore": 0},
    ),
    _case(
        "fmi2DeSerializeFMUstate of a pickle that runs a command when unpickled",
        "fmi2Error; the command never runs",
        "pickle_bytes",
        {"status": ERROR, "command_ran": False},
    ),
    _case(
        "fmi2SerializeFMUstate into a buffer one byte too small, and into one 16 bytes too large",
        "fmi2Error for the small one; the large one (NUL-padded) deserializes and restores",
        "buffer_sizes",
        {"small": ERROR, "large": 0, "large_restores": [0, 0]},
    ),
    _case(
        "fmi2GetFMUstate into a state it handed out before",
        "the same handle, updated (FMI 2.0 section 2.1.8)",
        "state_reuse",
        {"same_handle": True, "restores": 0},
    ),
    _case(
        "fmi2SetupExperiment and fmi2EnterInitializationMode after initialisation, "
        "fmi2ExitInitializationMode twice, fmi2DoStep before initialisation, "
        "fmi2Terminate twice, fmi2SetReal after fmi2Terminate",
        "fmi2Error with a message for each",
        "mode_rules",
        {"statuses": [ERROR] * 6, "messages": 6},
    ),
    _case(
        "the FMU unpacked under a path with a comma, a space and a percent sign (fmpy "
        "percent-encodes them in fmuResourceLocation); fmi2Instantiate with a location that "
        "does not exist and with an http:// one",
        "the first instantiates and steps; the others get NULL and a message each, no crash",
        "resource_locations",
        {"step": 0, "refused": [True, True], "messages": 2},
    ),
    _case(
        "a KeyboardInterrupt inside the FMU (fmi2Fatal), then more calls, then fmi2FreeInstance",
        "the later calls refused with fmi2Error (only "
        "fmi2FreeInstance is allowed); no crash, clean exit",
        "after_fatal",
        {"fatal": True, "after": [ERROR, ERROR, ERROR], "refused": True, "exit": "clean"},
    ),
]


def _late_case(mode: str, fault: str):
    def run():
        host = _hostile_host()
        directory = Path(tempfile.mkdtemp(prefix="agilesat-late-"))
        try:
            with zipfile.ZipFile(BUILD / f"{FMU}.fmu") as archive:
                archive.extractall(directory)
                guid = archive.read("modelDescription.xml").decode().split('guid="')[1]
            run = subprocess.run(
                [str(host), str(directory), FMU, guid.split('"')[0], mode],
                capture_output=True,
                text=True,
                timeout=300,
                env={"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8"},
            )
        finally:
            shutil.rmtree(directory, ignore_errors=True)
        lines = run.stdout.strip().splitlines()
        ok = run.returncode == 0 and any("fmi2FreeInstance returned" in l for l in lines)
        observed = (
            (
                f"exit code {run.returncode}"
                if run.returncode >= 0
                else f"killed by signal {-run.returncode}"
            )
            + "; "
            + " | ".join(lines[-3:])
        )
        return {
            "fault": fault,
            "expected": "the late calls are harmless (fmi2Error, no crash), clean exit",
            "observed": observed,
            "ok": ok,
        }

    run.__name__ = f"late_calls_{mode}"
    return run


CASES += [
    _case(
        "fmi2GetRealOutputDerivatives before initialisation, of order 2, of an input, "
        "with a NULL order array; fmi2GetReal of a value reference "
        "the shim reserves for them; fmi2SetRealInputDerivatives of orders "
        "0, -1 and 2, of a parameter, of NaN, with NULL value-reference "
        "and value arrays, after fmi2Terminate",
        "fmi2Error with a message for each, naming the FMU and the variable where there is "
        "one; both instances still step",
        "derivative_faults",
        {"statuses": [ERROR] * 13, "messages": 13, "named": True, "steps_after": [0, 0]},
    ),
    _case(
        "fmi2GetFMUstate and fmi2SerializeFMUstate after fmi2SetRealInputDerivatives, another "
        "derivative set, then the state restored (and deserialized into a fresh instance)",
        "the derivative comes back with the state: the steps after both restores are "
        "bit-identical to a run that never set the other derivative; the input hdot_cmg "
        "stays what it was (the derivative of h_cmg is not written into it)",
        "derivative_state",
        {"restored": [True, True], "derivative": [True, True]},
    ),
]

CASES += [
    _late_case(
        "finalize",
        "a C host finalizes its embedded Python, then calls fmi2Terminate and fmi2FreeInstance",
    ),
    _late_case(
        "destructor",
        "a C host calls fmi2Terminate and fmi2FreeInstance from a "
        "static destructor, after the exit handlers",
    ),
]


CASES += [
    _case(
        "fmi2GetReal right after fmi2Instantiate; fmi2DoStep ending past the stop time "
        "fmi2SetupExperiment defined (0.5 s: 10 steps of 0.05 s to it, an 11th past it), "
        "with the kernels in Python and compiled (the shim's C step path)",
        "fmi2Error with a message for each (FMI 2.0 sections 4.2.4 and 4.2.1), the steps up "
        "to the stop time fmi2OK",
        "state_machine_gaps",
        {
            "get_before": [ERROR, ERROR],
            "steps": [[10, ERROR], [10, ERROR]],
            "c_path": [False, True],
            "messages": 4,
        },
    ),
]


def user_model_outputs():
    """A user's model (``wild_model``) whose Integer output n is 2**40 or 1.5 and whose
    Boolean output b is 0.5, run by `agilesat run Wild.fmu`."""
    import wild_model

    fmu = wild_model.built()
    observed, ok = [], True
    for value, variable in (("count=1099511627776", "n"), ("count=1.5", "n"), ("flag=0.5", "b")):
        with tempfile.TemporaryDirectory() as tmp:
            run = subprocess.run(
                [sys.executable, "-m", "agilesat.orchestration", "run", str(fmu), "--step"]
                + ["0.1", "--stop", "0.3", "--set", f"Wild.{value}", "--no-figures", "-q"]
                + ["--no-report"]
                + ["--out", str(Path(tmp) / "out")],
                capture_output=True,
                text=True,
                timeout=600,
                cwd=ROOT,
            )
        said = [line for line in run.stderr.splitlines() if "error:" in line]
        good = (
            run.returncode == 1
            and "the model produced" in run.stderr
            and f"{variable}=" in run.stderr
            and "returned fmi2Error" in run.stderr
            and "Traceback" not in run.stderr
        )
        ok &= good
        said = (said or [""])[0][:150]
        observed.append(f"{value}: exit {run.returncode}: {said}" + ("" if good else " (!)"))
    return {
        "fault": "a user's model (agilesat build) whose Integer output is 2**40 or 1.5, "
        "whose Boolean output is 0.5",
        "expected": "fmi2Error from fmi2GetInteger/fmi2GetBoolean naming the model and the "
        "variable; the run exits 1 with the message, the rows before kept (never wrapped to "
        "0, truncated to 1 or read as true)",
        "observed": "; ".join(observed),
        "ok": ok,
    }


CASES.append(user_model_outputs)


def _warning_case():
    from agilesat.fmus.build import SHIM_C_FILES, SHIM_LIBRARIES, shim_flags

    directory = Path(tempfile.mkdtemp(prefix="agilesat-fake-"))
    try:
        inner = directory / "pythonfmu-export.so"
        _compile([HERE / "c_host" / "fake_inner.c"], inner, "-shared", "-fPIC")
        flags = shim_flags("", "", "3.0")
        _compile(SHIM_C_FILES, directory / "Fake.so", *flags, *SHIM_LIBRARIES)
        answer, process = _child("warning_as_ok", directory / "Fake.so")
    finally:
        shutil.rmtree(directory, ignore_errors=True)
    want = {"step": 0, "messages": [[1, "logStatusWarning", "gimbal rate command limited"]]}
    return {
        "fault": "the slave logs a warning at status OK, category logStatusWarning "
        "(the shim alone, on a stand-in for pythonfmu's binary), logging off",
        "expected": "the host's logger gets it as a warning (status fmi2Warning) with that "
        "category; fmi2DoStep returns fmi2OK; OK-level debug messages stay filtered",
        "observed": process if answer is None else f"{process}; {json.dumps(answer)}",
        "ok": answer == want,
    }


_warning_case.__name__ = "warning_as_ok"
CASES.append(_warning_case)


def _compile(sources, output: Path, *flags: str) -> None:
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    subprocess.run(
        [
            compiler,
            "-O2",
            "-Wall",
            "-Werror",
            "-I",
            str(ROOT / "fmus" / "shim"),
            *flags,
            "-o",
            str(output),
            *map(str, sources),
            "-ldl",
        ],
        check=True,
    )


@functools.cache
def _hostile_host() -> Path:
    binary = Path(tempfile.mkdtemp(prefix="agilesat-host-")) / "hostile_host"
    _compile([HERE / "c_host" / "hostile_host.c"], binary)
    return binary


def resource_figures(n: int) -> list[tuple[str, str]]:
    """Memory and mappings after n simulate() calls and n instantiate/free cycles, and the
    memory per live instance, each measured in a fresh process."""
    rows = []
    simulate, _ = _child("simulate_loop", n, timeout=36000)
    raw, _ = _child("raw_cycles", n, timeout=36000)
    master, _ = _child("instance_cycles", n, timeout=36000)
    live, _ = _child("live_instances", min(n, 200), timeout=36000)
    for label, answer in (
        (f"{n} simulate() calls of scan_pitch (0.1 s) in one process", simulate),
        (
            f"{n} instantiate/free cycles of {FMU} through the master's "
            "Instance (reset and reused)",
            master,
        ),
        (f"{n} raw fmi2Instantiate/fmi2FreeInstance cycles of {FMU} (fmpy)", raw),
    ):
        if answer is None:
            rows.append((label, "failed"))
            continue
        rows.append(
            (
                f"{label}: resident memory growth",
                f"{answer['rss_mb']:.1f} MB ({answer['rss_mb'] * 1024 / n:.2f} KB per call)",
            )
        )
        rows.append((f"{label}: memory mappings growth", str(answer["maps"])))
    if live is not None:
        rows.append(
            (
                f"resident memory per live {FMU} instance ({live['count']} instances)",
                f"{live['rss_mb'] * 1024 / live['count']:.0f} KB",
            )
        )
    return rows


# -- the child side --------------------------------------------------------------------------
def _host():
    sys.path.insert(0, str(HERE))
    import fmi_host

    return fmi_host


def _path(name=FMU) -> str:
    return str(BUILD / f"{name}.fmu")


def _ready(name=FMU, instance="a"):
    fmi_host = _host()
    fmu = fmi_host.Fmu(_path(name), instance)
    fmu.initialize(fmi_host.plausible_inputs(fmu))
    return fmu


def _errors(fmu, since: int) -> list[str]:
    return [m for s, m in fmu.messages[since:] if s >= ERROR]


def _state(fmu):
    state = ctypes.c_void_p()
    assert fmu.dll.fmi2GetFMUstate(fmu.c, ctypes.byref(state)) == 0
    return state


def _serialize(fmu, state) -> bytes:
    size = ctypes.c_size_t()
    assert fmu.dll.fmi2SerializedFMUstateSize(fmu.c, state, ctypes.byref(size)) == 0
    data = (ctypes.c_char * size.value)()
    assert fmu.dll.fmi2SerializeFMUstate(fmu.c, state, data, size) == 0
    return bytes(data)


def _deserialize(fmu, data: bytes) -> tuple[int, ctypes.c_void_p]:
    state = ctypes.c_void_p()
    buffer = (ctypes.c_char * max(len(data), 1)).from_buffer_copy(data or b"\0")
    return fmu.dll.fmi2DeSerializeFMUstate(fmu.c, buffer, len(data), ctypes.byref(state)), state


def resource_locations():
    directory = Path(tempfile.mkdtemp(), "a,b c%")
    directory.mkdir()
    tempfile.tempdir = str(directory)  # where fmpy unpacks
    fmu = _ready()
    step = fmu.step(0.0, 0.05)
    refused = []
    for uri in (b"file:///nonexistent/resources", b"http://example.com/resources"):
        c = fmu.dll.fmi2Instantiate(
            b"x", 1, fmu.md.guid.encode(), uri, ctypes.byref(fmu._callbacks), 0, 0
        )
        refused.append(c is None)
    said = [m for _, m in fmu.messages if "is not this FMU's resources directory" in m]
    return {"step": step, "refused": refused, "messages": len(said)}


def double_free():
    fmu = _ready()
    fmu.dll.fmi2FreeInstance(fmu.c)
    fmu.dll.fmi2FreeInstance(fmu.c)
    return {"exit": "clean"}


def call_after_free():
    fmu = _ready()
    fmu.dll.fmi2FreeInstance(fmu.c)
    vr, value = (ctypes.c_uint * 1)(0), (ctypes.c_double * 1)()
    state = ctypes.c_void_p()
    return {
        "statuses": [
            fmu.step(0.0, 0.05),
            fmu.dll.fmi2GetReal(fmu.c, vr, 1, value),
            fmu.dll.fmi2SetReal(fmu.c, vr, 1, value),
            fmu.dll.fmi2Terminate(fmu.c),
            fmu.dll.fmi2GetFMUstate(fmu.c, ctypes.byref(state)),
        ]
    }


def garbage_handle():
    fmu = _ready()
    junk = ctypes.create_string_buffer(b"\xff" * 256)
    made_up = ctypes.cast(junk, ctypes.c_void_p)
    vr, value = (ctypes.c_uint * 1)(0), (ctypes.c_double * 1)()
    order = (ctypes.c_int * 1)(1)
    return {
        "statuses": [
            fmu.dll.fmi2DoStep(None, 0.0, 0.05, 1),
            fmu.dll.fmi2DoStep(made_up, 0.0, 0.05, 1),
            fmu.dll.fmi2GetReal(made_up, vr, 1, value),
            fmu.dll.fmi2SetupExperiment(made_up, 0, 0.0, 0.0, 0, 0.0),
            fmu.dll.fmi2SetRealInputDerivatives(None, vr, 1, order, value),
            fmu.dll.fmi2GetRealOutputDerivatives(made_up, vr, 1, order, value),
        ]
    }


def null_arrays():
    fmu = _ready()
    mark = len(fmu.messages)
    vr, value = (ctypes.c_uint * 3)(0, 1, 2), (ctypes.c_double * 3)()
    strings = (ctypes.c_char_p * 2)(b"x", None)
    dll, c = fmu.dll, fmu.c
    statuses = [
        dll.fmi2GetReal(c, None, 3, value),
        dll.fmi2GetReal(c, vr, 3, None),
        dll.fmi2SetReal(c, None, 2, None),
        dll.fmi2GetString(c, vr, 2, None),
        dll.fmi2SetString(c, vr, 2, strings),
        dll.fmi2SetDebugLogging(c, 1, 2, None),
        dll.fmi2GetRealStatus(c, 2, None),
    ]
    return {
        "statuses": statuses,
        "messages": len(_errors(fmu, mark)),
        "step_after": fmu.step(0.0, 0.05),
    }


def wrong_states():
    a, twin, other = _ready(), _ready(instance="twin"), _ready(OTHER, "other")
    mark = len(a.messages)
    freed = _state(a)
    assert a.dll.fmi2FreeFMUstate(a.c, ctypes.byref(ctypes.c_void_p(freed.value))) == 0
    statuses = [
        a.dll.fmi2SetFMUstate(a.c, None),
        a.dll.fmi2SetFMUstate(a.c, freed),
        a.dll.fmi2SetFMUstate(a.c, _state(twin)),
        a.dll.fmi2SetFMUstate(a.c, _state(other)),
        a.dll.fmi2FreeFMUstate(a.c, ctypes.byref(freed)),
    ]
    return {
        "statuses": statuses,
        "messages": len(_errors(a, mark)),
        "steps_after": [a.step(0.0, 0.05), other.step(0.0, 0.05)],
    }


def garbage_bytes():
    import random

    a, other = _ready(), _ready(OTHER, "other")
    valid = _serialize(a, _state(a))
    version = bytearray(valid)
    version[18] ^= 0xFF  # the u16 after the 18 magic bytes
    random.seed(1)
    inputs = [
        bytes(random.randrange(256) for _ in range(len(valid))),
        valid[:-9],
        _serialize(other, _state(other)),
        bytes(version),
        b"",
    ]
    mark = len(a.messages)
    statuses = [_deserialize(a, data)[0] for data in inputs]
    reasons = _errors(a, mark)
    status, state = _deserialize(a, valid)
    return {
        "statuses": statuses,
        "reasons": len(reasons) == 5 and all("fmi2DeSerializeFMUstate" in r for r in reasons),
        "messages": reasons,
        "step_after": a.step(0.0, 0.05),
        "valid_restore": status or a.dll.fmi2SetFMUstate(a.c, state),
    }


class _Command:
    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {self.marker}",)


def pickle_bytes():
    import pickle

    a = _ready()
    marker = Path(tempfile.mkdtemp()) / "pwned"
    status, _ = _deserialize(a, pickle.dumps(_Command(marker)))
    return {"status": status, "command_ran": marker.exists(), "messages": _errors(a, 0)}


def buffer_sizes():
    a = _ready()
    state = _state(a)
    size = ctypes.c_size_t()
    assert a.dll.fmi2SerializedFMUstateSize(a.c, state, ctypes.byref(size)) == 0
    small = (ctypes.c_char * (size.value - 1))()
    large = (ctypes.c_char * (size.value + 16))()
    statuses = {
        "small": a.dll.fmi2SerializeFMUstate(a.c, state, small, size.value - 1),
        "large": a.dll.fmi2SerializeFMUstate(a.c, state, large, size.value + 16),
    }
    status, restored = _deserialize(a, bytes(large))
    return {
        **statuses,
        "large_restores": [status, a.dll.fmi2SetFMUstate(a.c, restored)],
        "messages": _errors(a, 0),
    }


def state_reuse():
    a = _ready()
    state = _state(a)
    first = state.value
    assert a.step(0.0, 0.05) == 0
    status = a.dll.fmi2GetFMUstate(a.c, ctypes.byref(state))
    return {
        "same_handle": status == 0 and state.value == first,
        "restores": a.dll.fmi2SetFMUstate(a.c, state),
    }


def mode_rules():
    fmi_host = _host()
    fresh = fmi_host.Fmu(_path(), "fresh")
    a = _ready()
    vr, value = (ctypes.c_uint * 1)(a.vr[a.names("input")[0]]), (ctypes.c_double * 1)(0.5)
    statuses = [
        fresh.step(0.0, 0.05),
        a.dll.fmi2SetupExperiment(a.c, 0, 0.0, 0.0, 0, 0.0),
        a.dll.fmi2EnterInitializationMode(a.c),
        a.dll.fmi2ExitInitializationMode(a.c),
    ]
    assert a.dll.fmi2Terminate(a.c) == 0
    statuses += [a.dll.fmi2Terminate(a.c), a.dll.fmi2SetReal(a.c, vr, 1, value)]
    return {
        "statuses": statuses,
        "messages": len(_errors(a, 0)) + len(_errors(fresh, 0)),
        "texts": _errors(a, 0),
    }


def state_machine_gaps():
    """fmi2GetReal of an instance only instantiated; fmi2DoStep past the stop time of
    fmi2SetupExperiment (stopTimeDefined), with the Python kernels (AGILESAT_NATIVE=0: a run
    this short keeps them) and, in a second child, the FMU's compiled C entries (the shim's
    C step path serves the steps)."""
    if "AGILESAT_NATIVE" not in os.environ:
        os.environ["AGILESAT_NATIVE"] = "0"
        compiled, _ = _child("state_machine_gaps", env={"AGILESAT_NATIVE": "1"})
        compiled = compiled or {"get_before": [None], "steps": [None], "c_path": [None]}
    fmi_host = _host()
    fresh = fmi_host.Fmu(_path(OTHER), "fresh")
    status, _ = fresh.get_real(fresh.names("output")[:1])
    a = fmi_host.Fmu(_path(OTHER), "a")
    assert a.dll.fmi2SetupExperiment(a.c, 0, 0.0, 0.0, 1, ctypes.c_double(0.5)) == 0
    assert a.dll.fmi2EnterInitializationMode(a.c) == 0
    assert a.set_real(fmi_host.plausible_inputs(a)) == 0
    assert a.dll.fmi2ExitInitializationMode(a.c) == 0
    statuses = [a.step(k * 0.05, 0.05) for k in range(11)]  # the last one to 0.55 s
    steps = [statuses.count(0), statuses[-1]]
    served, counters = (ctypes.c_ulonglong * 3)(), a.dll.agilesat_shim_step_counters
    counters.argtypes, counters.restype = [ctypes.c_void_p, ctypes.c_void_p], ctypes.c_int
    counters(a.c, served)  # [0]: the steps the shim's C path made
    mine = {
        "get_before": [status],
        "steps": [steps],
        "c_path": [served[0] > 0],
        "messages": len(_errors(fresh, 0)) + len(_errors(a, 0)),
        "texts": _errors(fresh, 0) + _errors(a, 0),
    }
    if os.environ["AGILESAT_NATIVE"] == "1":
        return mine
    both = {k: mine[k] + compiled.get(k, 0) for k in mine if k != "texts"}
    return both | {"texts": mine["texts"]}


SATELLITE = "SatelliteDynamics"  # interpolates its inputs (h_cmg, ...)


def _derivative_call(fmu, call, names, orders, values=None, vr=True, order=True):
    n = len(names)
    vrs = (ctypes.c_uint * n)(*(fmu.vr[name] for name in names)) if vr else None
    order_array = (ctypes.c_int * n)(*orders) if order else None
    array = (ctypes.c_double * n)(*(values or [0.0] * n)) if values is not False else None
    return getattr(fmu.dll, call)(fmu.c, vrs, n, order_array, array)


def derivative_faults():
    fmi_host = _host()
    cmg = fmi_host.Fmu(_path(OTHER), "cmg")
    get = "fmi2GetRealOutputDerivatives"
    statuses = [_derivative_call(cmg, get, ["h[1]"], [1])]  # before initialisation
    cmg.initialize(fmi_host.plausible_inputs(cmg))
    statuses += [
        _derivative_call(cmg, get, ["h[1]", "h[2]"], [1, 2]),
        _derivative_call(cmg, get, ["delta_dot_cmd[1]"], [1]),
        _derivative_call(cmg, get, ["h[1]"], [1], order=False),
        # the value references that carry the derivative calls to the slave, in a plain call
        cmg.dll.fmi2GetReal(
            cmg.c,
            (ctypes.c_uint * 1)((1 << 30) + (1 << 24) + cmg.vr["h[1]"]),
            1,
            (ctypes.c_double * 1)(),
        ),
    ]
    sat = _ready(SATELLITE, "sat")
    put = "fmi2SetRealInputDerivatives"
    statuses += [
        _derivative_call(sat, put, ["h_cmg[1]"], [0]),
        _derivative_call(sat, put, ["h_cmg[1]"], [-1]),
        _derivative_call(sat, put, ["h_cmg[1]"], [2]),
        _derivative_call(sat, put, ["mu"], [1]),
        _derivative_call(sat, put, ["h_cmg[1]", "h_cmg[2]"], [1, 1], [0.1, float("nan")]),
        _derivative_call(sat, put, ["h_cmg[1]"], [1], vr=False),
        _derivative_call(sat, put, ["h_cmg[1]"], [1], values=False),
    ]
    steps = [cmg.step(0.0, 0.05), sat.step(0.0, 0.05)]
    ended = fmi_host.Fmu(_path(SATELLITE), "ended")
    ended.initialize(fmi_host.plausible_inputs(ended))
    assert ended.dll.fmi2Terminate(ended.c) == 0
    statuses.append(_derivative_call(ended, put, ["h_cmg[1]"], [1], [0.1]))
    texts = _errors(cmg, 0) + _errors(sat, 0) + _errors(ended, 0)
    variables = ["h[2]", "delta_dot_cmd[1]", "h_cmg[1]", "mu", "h_cmg[2]"]
    return {
        "statuses": statuses,
        "messages": len(texts),
        "named": all(any(v in t for t in texts) for v in variables)
        and all(any(f in t for t in texts) for f in ("CmgCluster", SATELLITE)),
        "steps_after": steps,
        "texts": texts,
    }


def derivative_state():
    put = "fmi2SetRealInputDerivatives"
    names = ["h_cmg[1]", "h_cmg[2]", "h_cmg[3]"]
    outputs = [f"w_BI_B[{i}]" for i in (1, 2, 3)] + [f"q_BI[{i}]" for i in (1, 2, 3, 4)]
    kept, other = [0.02, -0.01, 0.03], [5.0, 5.0, 5.0]

    def steps(fmu):
        result = []
        for k in range(3):
            assert fmu.step(0.05 * k, 0.05) == 0
            result.append(fmu.get_real(outputs)[1])
        return result

    def ready(instance):  # hdot_cmg zero (unconnected): the derivatives are the slopes
        fmu = _ready(SATELLITE, instance)
        assert fmu.set_real({f"hdot_cmg[{i}]": 0.0 for i in (1, 2, 3)}) == 0
        return fmu

    twin = ready("twin")
    assert _derivative_call(twin, put, names, [1, 1, 1], kept) == 0
    expected = steps(twin)
    a = ready("a")
    assert _derivative_call(a, put, names, [1, 1, 1], kept) == 0
    state = _state(a)
    data = _serialize(a, state)
    assert _derivative_call(a, put, names, [1, 1, 1], other) == 0
    restored = [a.dll.fmi2SetFMUstate(a.c, state) == 0]
    derivative = [a.get_real([f"hdot_cmg[{i}]" for i in (1, 2, 3)])[1] == [0.0] * 3]
    restored[0] = restored[0] and steps(a) == expected
    fresh = ready("fresh")
    status, copy = _deserialize(fresh, data)
    restored.append(status == 0 and fresh.dll.fmi2SetFMUstate(fresh.c, copy) == 0)
    derivative.append(fresh.get_real([f"hdot_cmg[{i}]" for i in (1, 2, 3)])[1] == [0.0] * 3)
    restored[1] = restored[1] and steps(fresh) == expected
    return {"restored": restored, "derivative": derivative}


def after_fatal():
    """SIGALRM every 0.3 ms raises KeyboardInterrupt wherever Python runs; one landing in
    the FMU's Python code (the outputs evaluated there, not by the FMU's compiled C entries)
    is an exception pythonfmu turns into fmi2Fatal.  One interrupt is
    in flight at a time (the handler disarms itself; the host re-arms it when the interrupt
    landed in its own code): a second one raised while pythonfmu 0.7.0 formats the first
    crashes inside pythonfmu (PySlaveInstance::handle_py_exception passes the NULL of a
    failed PyObject_Str to PyUnicode_AsEncodedString), which no code of ours runs in."""
    import signal

    os.environ["AGILESAT_NATIVE"] = "0"  # the outputs in the kernels' Python: every get
    armed = [True]

    def interrupt(*_):
        if armed[0]:
            armed[0] = False
            raise KeyboardInterrupt

    fmi_host = _host()
    a = _ready()
    inputs = fmi_host.plausible_inputs(a)
    fatal = False
    signal.signal(signal.SIGALRM, interrupt)
    signal.setitimer(signal.ITIMER_REAL, 0.0003, 0.0003)
    for _ in range(200000):
        try:
            if a.set_real(inputs) == 4 or a.get_real(a.names("output"))[0] == 4:
                fatal = True
                break
        except KeyboardInterrupt:
            armed[0] = True
            continue
    while armed[0]:
        try:
            armed[0] = False
        except KeyboardInterrupt:
            pass
    signal.setitimer(signal.ITIMER_REAL, 0)
    mark = len(a.messages)
    after = [a.step(0.0, 0.05), a.get_real(a.names("output"))[0], a.set_real(inputs)]
    refused = len(_errors(a, mark)) == 3 and all("fmi2Fatal" in m for m in _errors(a, mark))
    a.dll.fmi2FreeInstance(a.c)
    return {"fatal": fatal, "after": after, "refused": refused, "exit": "clean"}


def warning_as_ok(library):
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

    messages = []
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(
        lambda env, name, status, category, message: messages.append(
            [status, category.decode(), message.decode()]
        )
    )
    dll = ctypes.CDLL(library)
    dll.fmi2Instantiate.restype = ctypes.c_void_p
    dll.fmi2Instantiate.argtypes = [
        ctypes.c_char_p,
        ctypes.c_int,
        ctypes.c_char_p,
        ctypes.c_char_p,
        ctypes.c_void_p,
        ctypes.c_int,
        ctypes.c_int,
    ]
    dll.fmi2DoStep.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
    resources = Path(tempfile.mkdtemp(), "resources")  # what the shim checks is there
    resources.mkdir()
    (resources / "slavemodule.txt").write_text("fake")
    c = dll.fmi2Instantiate(
        b"fake", 1, b"{0}", resources.as_uri().encode(), ctypes.addressof(callbacks), 0, 0
    )
    return {"step": dll.fmi2DoStep(c, 0.0, 0.05, 1), "messages": messages}


def _rss_maps() -> tuple[float, int]:
    rss = next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmRSS"))
    return rss / 1024, sum(1 for _ in open("/proc/self/maps"))


def _growth(step, n: int, warm: int = 20) -> dict:
    for _ in range(warm):
        step()
    rss0, maps0 = _rss_maps()
    for _ in range(n):
        step()
    rss1, maps1 = _rss_maps()
    return {"rss_mb": rss1 - rss0, "maps": maps1 - maps0}


def simulate_loop(n):
    """On a copy of the system and its FMUs (a rebuild meanwhile is a new FMU)."""
    from agilesat.orchestration.cosim.master import simulate
    from agilesat.orchestration.scenarios import get

    copy = Path(tempfile.mkdtemp(prefix="agilesat-loop-"))
    ssd = get("scan_pitch").ssd
    shutil.copytree(BUILD, copy / "fmus" / "build", ignore=shutil.ignore_patterns(".*"))
    (copy / "orchestration" / "systems").mkdir(parents=True)
    shutil.copy(ssd, copy / "orchestration" / "systems" / ssd.name)
    try:
        return _growth(
            lambda: simulate(copy / "orchestration" / "systems" / ssd.name, stop=0.1), int(n)
        )
    finally:
        shutil.rmtree(copy, ignore_errors=True)


def instance_cycles(n):
    from agilesat.orchestration.cosim.fmu import Instance, Log

    def cycle():
        instance = Instance("a", _path(), Log())
        instance.instantiate()
        instance.free()

    return _growth(cycle, int(n))


def raw_cycles(n):
    fmi_host = _host()

    def cycle():
        slave, callbacks = shared
        slave.instantiate(callbacks=callbacks)
        slave.fmi2FreeInstance(slave.component)

    probe = fmi_host.Fmu(_path(), "raw")
    probe.dll.fmi2FreeInstance(probe.c)
    shared = (probe.slave, probe._callbacks)
    return _growth(cycle, int(n))


def live_instances(n):
    fmi_host = _host()
    keep = [fmi_host.Fmu(_path(), "warm")]
    rss0, _ = _rss_maps()
    keep += [fmi_host.Fmu(_path(), f"i{k}") for k in range(int(n))]
    for fmu in keep[1:]:
        fmu.initialize(fmi_host.plausible_inputs(fmu))
    return {"rss_mb": _rss_maps()[0] - rss0, "count": int(n)}


if __name__ == "__main__":
    case, *arguments = sys.argv[1:]
    if case == "figures":  # python tests/tools/fault_cases_fmu.py figures N
        for figure, value in resource_figures(int(arguments[0])):
            print(f"{figure}: {value}")
    else:
        print(json.dumps(globals()[case](*arguments)), flush=True)
