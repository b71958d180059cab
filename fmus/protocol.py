"""What the slave (Python, ``slave.py`` and ``fast_paths.py``) and the shim (C,
``shim/*.c``) share: one table, from which ``agilesat generate`` writes the C header the
shim compiles against (``shim/protocol.h``; ``agilesat generate --check`` and the build
refuse a stale one).  Nothing here is written twice.

- The derivative calls.  pythonfmu 0.7 has no fmi2SetRealInputDerivatives and
  fmi2GetRealOutputDerivatives; the shim passes them on as fmi2SetReal/fmi2GetReal of the
  value references ``DERIVATIVE_BASE + (order << ORDER_SHIFT) + vr`` (orders up to
  ``MAX_ORDER``), a range no variable has.
- The handshake.  A fmi2GetReal of ``FAST_PATH_N`` copies of ``FAST_PATH_VR`` (which
  pythonfmu, passing value references as C ints, hands the slave as -1) answers
  (``FAST_PATH_VERSION``, address of the model's value array, its length, addresses of
  ``kind``, ``control`` and ``block``); the shim uses the arrays only if the version is
  its own.  A fmi2GetString of ``FAST_PATH_VR`` answers the FMU's GUID
  (:func:`fmu_guid`), which the shim compares with the one the host passes.
- ``kind``: per scalar (value reference), ``KIND_*``.
- ``control`` (int32): the flags of the state machine and of the fast paths.
- ``block`` (float64): the step's end and the C step path's addresses (exact doubles).
- Time continuity: a step starts where the last one ended when
  ``math.isclose(t, end, rel_tol=TIME_REL_TOL, abs_tol=TIME_ABS_TOL)``.
"""

from __future__ import annotations

import math
import uuid

DERIVATIVE_BASE, ORDER_SHIFT, MAX_ORDER = 1 << 30, 24, 63

FAST_PATH_VR, FAST_PATH_N, FAST_PATH_VERSION = 0xFFFFFFFF, 6, 8.0

#: per scalar: a String (or anything the shim leaves alone), a Real parameter, output,
#: input, input some output depends on directly (feedthrough), an Integer, a Boolean (not
#: inputs), an Integer input, feedthrough input, a Boolean input, feedthrough input
KIND_OTHER, KIND_PARAMETER, KIND_OUTPUT, KIND_INPUT, KIND_FEEDTHROUGH = range(5)
KIND_INTEGER, KIND_BOOLEAN = 5, 6
KIND_INTEGER_INPUT, KIND_INTEGER_FEEDTHROUGH = 7, 8
KIND_BOOLEAN_INPUT, KIND_BOOLEAN_FEEDTHROUGH = 9, 10

#: control[]: the slave is in step mode (and its value array is the one shared); the
#: outputs are those of the current state and inputs; the C step path's step (C_STEP_*) and
#: output (1: the output entry does all of output()); the shim served calls since the
#: slave's last one
STEP_MODE, OUTPUTS_VALID, C_STEP, C_OUTPUT, C_DIRTY = range(5)
N_CONTROL = 5
#: control[C_STEP]: the next step is the slave's, the step entry's, or changes only the time
C_STEP_PYTHON, C_STEP_ENTRY, C_STEP_TIME = range(3)

#: block[]: the step's end (the model's time t; NaN before the first step's start is
#: known), the C entries' addresses, the model's state array (address, length), the
#: snapshot buffer (address, length: values then state), the outputs values[start:stop],
#: the rows that bring the inputs to a step's end (address, count: components/variables.py
#: Layout.step_end, six offsets a row, as float64), the stop time of fmi2SetupExperiment
#: (inf when not defined: no step may end after it), the length of the part of the state
#: array a snapshot keeps (the rest is the model's scratch: fmus/fast_paths.py)
B_TIME, B_STEP, B_OUTPUT, B_STATE, B_N_STATE, B_SAVED, B_N_SAVED = range(7)
B_OUTPUTS_START, B_OUTPUTS_STOP, B_STEP_END, B_N_STEP_END, B_STOP, B_N_KEPT = range(7, 13)
N_BLOCK = 13

TIME_REL_TOL, TIME_ABS_TOL = 1e-9, 1e-12

#: the header's sections: (comment, names)
SECTIONS = (
    ("derivative calls", ("DERIVATIVE_BASE", "ORDER_SHIFT", "MAX_ORDER")),
    ("the handshake", ("FAST_PATH_VR", "FAST_PATH_N", "FAST_PATH_VERSION")),
    (
        "kind[]: per scalar",
        ("KIND_OTHER", "KIND_PARAMETER", "KIND_OUTPUT", "KIND_INPUT", "KIND_FEEDTHROUGH")
        + ("KIND_INTEGER", "KIND_BOOLEAN")
        + ("KIND_INTEGER_INPUT", "KIND_INTEGER_FEEDTHROUGH")
        + ("KIND_BOOLEAN_INPUT", "KIND_BOOLEAN_FEEDTHROUGH"),
    ),
    (
        "control[] (int32)",
        ("STEP_MODE", "OUTPUTS_VALID", "C_STEP", "C_OUTPUT", "C_DIRTY", "N_CONTROL"),
    ),
    ("control[C_STEP]", ("C_STEP_PYTHON", "C_STEP_ENTRY", "C_STEP_TIME")),
    (
        "block[] (float64)",
        ("B_TIME", "B_STEP", "B_OUTPUT", "B_STATE", "B_N_STATE", "B_SAVED", "B_N_SAVED")
        + ("B_OUTPUTS_START", "B_OUTPUTS_STOP", "B_STEP_END", "B_N_STEP_END", "B_STOP")
        + ("B_N_KEPT", "N_BLOCK"),
    ),
    ("time continuity (math.isclose)", ("TIME_REL_TOL", "TIME_ABS_TOL")),
)


#: an FMU's GUID is its name and the content hash of its code (fmus/build.py ``_sources``)
GUID_NAMESPACE = uuid.UUID("6f1c4c1e-3d0e-4c55-9a4e-0a9e5a7f2b11")


def fmu_guid(name: str, digest: str, key: str = "") -> str:
    """The GUID of FMU ``name`` built from code of content hash ``digest`` (and configured
    by ``agilesat export`` with values of hash ``key``: fmus/configure.py): the build
    writes it into modelDescription.xml, the slave answers it (its package is
    ``agilesat_<digest>``, its configuration in its resources), and the shim refuses an
    fmi2Instantiate given another (FMI 2.0 section 2.1.5: the GUID ties
    modelDescription.xml to the binary)."""
    return str(uuid.uuid5(GUID_NAMESPACE, f"{name}:{digest}" + (f":{key}" if key else "")))


def continuous(t: float, end: float) -> bool:
    """Does a step starting at ``t`` continue one that ended at ``end``?"""
    return math.isclose(t, end, rel_tol=TIME_REL_TOL, abs_tol=TIME_ABS_TOL)


def header() -> str:
    """``shim/protocol.h``."""
    lines = [
        "/* Generated from fmus/protocol.py by `agilesat generate`: do not edit. */",
        "#ifndef AGILESAT_PROTOCOL_H",
        "#define AGILESAT_PROTOCOL_H",
    ]
    for comment, names in SECTIONS:
        lines.append(f"\n/* {comment} */")
        for name in names:
            value = globals()[name]
            text = repr(value) if isinstance(value, float) else f"{value}{'u' * (value > 2**31)}"
            lines.append(f"#define {name} {text}")
    return "\n".join(lines) + "\n\n#endif\n"
