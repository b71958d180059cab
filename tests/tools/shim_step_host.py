"""A plain fmpy host driving built FMUs through the shim's C step path, or with it off
(``AGILESAT_SHIM_STEP=0``), with the kernels compiled from the first call
(``AGILESAT_JIT_AFTER=0``).  It does not import agilesat.  Run by
tests/fast_paths/test_shim_step.py in a fresh interpreter:
``python shim_step_host.py on|off NAME=FMU...``; prints, per FMU and program, what a host
sees (statuses, log messages, values, serialized states) and the shim's counters, as JSON.
``python shim_step_host.py on|off programs=end_of_step,end_of_step_again NAME=FMU...``
runs only those programs (tests/interop/test_end_of_step.py)."""

import ctypes
import json
import math
import os
import sys

os.environ["AGILESAT_JIT_AFTER"] = "0"
if sys.argv[1] == "off":
    os.environ["AGILESAT_SHIM_STEP"] = "0"

from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE  # noqa: E402

H = 0.05


class Fmu:
    def __init__(self, path, name):
        md = read_model_description(path)
        self.interpolates = bool(md.coSimulation.canInterpolateInputs)
        #: input -> the input declared its derivative (FMI 2.0 ``derivative``: hdot_cmg)
        self.rate_of = {
            v.derivative.name: v.name
            for v in md.modelVariables
            if v.causality == "input" and v.derivative is not None
        }
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        real = [v for v in md.modelVariables if v.type == "Real"]
        self.outputs = [v.valueReference for v in real if v.causality == "output"]
        self.inputs = [v.valueReference for v in real if v.causality == "input"]
        self.integers = [
            v.valueReference
            for v in md.modelVariables
            if v.type == "Integer" and v.causality == "output"
        ]
        self.messages = []
        self.slave = FMU2Slave(
            guid=md.guid,
            unzipDirectory=extract(path),
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda env, inst, status, cat, msg: self.messages.append([status, msg.decode()])
        )
        self._callbacks = callbacks
        self.slave.instantiate(callbacks=callbacks)
        self.c, self.dll = self.slave.component, self.slave.dll
        self.dll.fmi2DoStep.argtypes = [
            ctypes.c_void_p,
            ctypes.c_double,
            ctypes.c_double,
            ctypes.c_int,
        ]
        counters = self.dll.agilesat_shim_step_counters
        counters.argtypes, counters.restype = [ctypes.c_void_p, ctypes.c_void_p], ctypes.c_int
        self._counters = counters

    def counts(self):
        """[on, doSteps served in C, outputs evaluated in C, steps left to the slave]"""
        c = (ctypes.c_ulonglong * 3)()
        return [self._counters(self.c, c), *c]

    def initialize(self):
        assert self.dll.fmi2SetupExperiment(self.c, 0, 0.0, 0.0, 0, 0.0) == 0
        assert self.dll.fmi2EnterInitializationMode(self.c) == 0
        assert self.dll.fmi2ExitInitializationMode(self.c) == 0

    def step(self, t, h=H):
        return self.dll.fmi2DoStep(self.c, t, h, 1)

    def set_real(self, vrs, values):
        array = (ctypes.c_double * len(vrs))(*values)
        return self.dll.fmi2SetReal(self.c, (ctypes.c_uint * len(vrs))(*vrs), len(vrs), array)

    def get_real(self, vrs):
        array = (ctypes.c_double * len(vrs))()
        status = self.dll.fmi2GetReal(self.c, (ctypes.c_uint * len(vrs))(*vrs), len(vrs), array)
        return [status, list(array)]

    def get_integer(self, vrs):
        array = (ctypes.c_int * len(vrs))()
        status = self.dll.fmi2GetInteger(self.c, (ctypes.c_uint * len(vrs))(*vrs), len(vrs), array)
        return [status, list(array)]

    def get_state(self):
        state = ctypes.c_void_p()
        assert self.dll.fmi2GetFMUstate(self.c, ctypes.byref(state)) == 0
        return state

    def serialize(self, state):
        size = ctypes.c_size_t()
        assert self.dll.fmi2SerializedFMUstateSize(self.c, state, ctypes.byref(size)) == 0
        data = (ctypes.c_char * size.value)()
        assert self.dll.fmi2SerializeFMUstate(self.c, state, data, size) == 0
        return data.raw

    def deserialize(self, data):
        state = ctypes.c_void_p()
        buffer = ctypes.create_string_buffer(data, len(data))
        assert self.dll.fmi2DeSerializeFMUstate(self.c, buffer, len(data), ctypes.byref(state)) == 0
        return state

    def steps(self, t0, n, inputs=None):
        """n steps from t0: each a doStep, every third a set of the inputs (to the values
        read at the start: a feedthrough set after the step, before the gets), the gets."""
        inputs = self.get_real(self.inputs)[1] if inputs is None else inputs
        record = []
        for k in range(n):
            row = [self.step(t0 + k * H)]
            if k % 3 == 1:
                row.append(self.set_real(self.inputs, inputs))
            row.append(self.get_real(self.outputs))
            if self.integers:
                row.append(self.get_integer(self.integers))
            record.append(row)
        return record


def run(fmu):
    fmu.initialize()
    return {"record": fmu.steps(0.0, 30), "counts": fmu.counts()}


def states(fmu):
    """FMU state get, set, serialize and deserialize mid-run after C steps."""
    fmu.initialize()
    fmu.steps(0.0, 10)
    fmu.step(10 * H)  # a step in C, no get yet: the model's time is the shim's
    state = fmu.get_state()
    data = fmu.serialize(state)
    after = fmu.steps(11 * H, 5)
    assert fmu.dll.fmi2SetFMUstate(fmu.c, state) == 0
    restored = fmu.steps(11 * H, 5)
    assert fmu.dll.fmi2SetFMUstate(fmu.c, fmu.deserialize(data)) == 0
    deserialized = fmu.steps(11 * H, 5)
    return {
        "state": data.hex(),
        "after": after,
        "restored": restored,
        "deserialized": deserialized,
        "counts": fmu.counts(),
    }


def faults(fmu):
    """Bad calls after C steps: the slave's status and message, then the run goes on."""
    fmu.initialize()
    fmu.steps(0.0, 5)
    t = 5 * H
    calls = {
        "discontinuity": fmu.step(t + 0.3),
        "zero step": fmu.step(t, 0.0),
        "negative step": fmu.step(t, -H),
        "nan step": fmu.step(t, math.nan),
        "nan time": fmu.step(math.nan),
        "close enough": fmu.step(t + 1e-13),  # within math.isclose: accepted
    }
    record = fmu.steps(t + H, 3)
    calls["terminate"] = fmu.dll.fmi2Terminate(fmu.c)
    calls["step after terminate"] = fmu.step(t + 4 * H)
    return {"calls": calls, "messages": fmu.messages, "record": record, "counts": fmu.counts()}


def reset(fmu):
    fmu.initialize()
    first = fmu.steps(0.0, 6)
    before = fmu.counts()
    assert fmu.dll.fmi2Reset(fmu.c) == 0
    fmu.initialize()
    return {"first": first, "again": fmu.steps(0.0, 6), "before": before, "after": fmu.counts()}


def saturation(fmu):
    """CmgCluster: a command over the rate limit in step 5 (a warning from the step)."""
    fmu.initialize()
    command = [fmu.vr[f"delta_dot_cmd[{i}]"] for i in range(1, 7)]
    record = []
    for k in range(12):
        fmu.set_real(command, [5.0 if k == 5 else 0.1 * (k % 3)] + [0.0] * 5)
        record.append([fmu.step(k * H), fmu.get_real(fmu.outputs)])
    return {"record": record, "messages": fmu.messages, "counts": fmu.counts()}


def unphysical(fmu):
    """SatelliteDynamics: a body rate needing too many sub-steps in step 5 (an error from
    the step, nothing changed), then the run goes on."""
    fmu.initialize()
    h = [fmu.vr[f"h_cmg[{i}]"] for i in (1, 2, 3)]
    record, done = [], 0
    for k in range(10):
        fmu.set_real(h, [1e9 if k == 5 else 0.0, 0.0, 0.0])
        record.append([fmu.step(done * H), fmu.get_real(fmu.outputs)])
        done += record[-1][0] == 0  # a failed step leaves the time: the next one retries
    return {"record": record, "messages": fmu.messages, "counts": fmu.counts()}


def set_derivatives(fmu, names, values):
    n = len(names)
    return fmu.dll.fmi2SetRealInputDerivatives(
        fmu.c,
        (ctypes.c_uint * n)(*(fmu.vr[name] for name in names)),
        n,
        (ctypes.c_int * n)(*[1] * n),
        (ctypes.c_double * n)(*values),
    )


def interpolated(names, rates):
    """A host interpolating inputs: ``names`` set to zero and their derivatives set before
    every step (``rates(k)``), every step served by the C step path but where the kernel
    leaves it (a slope conflict's warning)."""

    def program(fmu):
        fmu.initialize()
        record = []
        for k in range(20):
            fmu.set_real([fmu.vr[name] for name in names], [0.0] * len(names))
            row = [set_derivatives(fmu, names, rates(k)), fmu.step(k * H)]
            record.append(row + [fmu.get_real(fmu.outputs)])
        return {"record": record, "messages": fmu.messages, "counts": fmu.counts()}

    return program


def _momentum_rates(k):
    """h_cmg's slope (0.1, as hdot_cmg says, until step 12, then 0.2: a conflict), ḧ, τ̇,
    ṙ."""
    return [0.0, 0.2 if k >= 12 else 0.1, 0.1, 1e-3, 0.02, 0.0, 0.0, 1e-4, 0.0, 10.0, 7e3, 3e2]


def hub_interpolated(fmu):
    """SatelliteDynamics with its momentum, torque and position interpolated."""
    names = [f"{v}[{i}]" for v in ("h_cmg", "hdot_cmg", "tau_ext", "r_I") for i in (1, 2, 3)]
    fmu.initialize()
    fmu.set_real([fmu.vr[f"r_I[{i}]"] for i in (1, 2, 3)], [7e6, 1e5, -2e5])
    record = []
    for k in range(20):  # hdot_cmg set at every step: it moves along its derivative
        fmu.set_real([fmu.vr[f"hdot_cmg[{i}]"] for i in (1, 2, 3)], [0.0, 0.1, 0.0])
        row = [set_derivatives(fmu, names, _momentum_rates(k)), fmu.step(k * H)]
        record.append(row + [fmu.get_real(fmu.outputs)])
    return {"record": record, "messages": fmu.messages, "counts": fmu.counts()}


def end_of_step(again: bool):
    """A host that sets the derivative of every Real input before every step and reads the
    outputs right after it, or (``again``) first sets the inputs again to their values at
    the step's end as it computes them: u + u̇ H (FMI 2.0's derivatives, from the step's
    start), u + (u̇ H + ½ ü H H) for an input with a declared derivative input whose
    derivative ü was set too (docs/coupling.md).  None for an FMU that does not
    interpolate its inputs."""

    def program(fmu):
        if not fmu.interpolates:
            return None
        fmu.initialize()
        u = fmu.get_real(fmu.inputs)[1]
        names = [name for name, vr in fmu.vr.items() if vr in fmu.inputs]
        names.sort(key=lambda name: fmu.inputs.index(fmu.vr[name]))
        record = []
        # a row of the hub's h_extra with a frequency is a rotor's, turned to the step's end
        # as the sinusoid it is, not along u + u̇ H (tests/components/test_flexible.py):
        # here the frequencies stay zero, every row a straight one
        rotating = [name.startswith("h_extra_frequency") for name in names]
        for k in range(12):
            rates = [
                0.0 if rotating[i] else 1e-3 * (1 + (i + k) % 3) * (-1) ** i for i in range(len(u))
            ]
            status = [set_derivatives(fmu, names, rates), fmu.step(k * H)]
            rate = dict(zip(names, rates))
            u = [
                x + (r * H + 0.5 * rate[fmu.rate_of[n]] * H * H) if n in fmu.rate_of else x + r * H
                for n, x, r in zip(names, u, rates)
            ]
            if again:
                status.append(fmu.set_real(fmu.inputs, u))
            record.append([status, fmu.get_real(fmu.outputs), fmu.get_real(fmu.inputs)])
        return {"record": record, "messages": fmu.messages, "counts": fmu.counts()}

    return program


PROGRAMS = {"run": run, "states": states, "faults": faults, "reset": reset}
#: chosen with ``programs=NAME,...`` as the first FMU argument
OPTIONAL = {"end_of_step": end_of_step(False), "end_of_step_again": end_of_step(True)}
SPECIAL = {
    "CmgCluster": {
        "saturation": saturation,
        "interpolated": interpolated(
            [f"delta_dot_cmd[{i}]" for i in range(1, 7)],
            lambda k: [0.5 * math.sin(0.3 * k), 20.0, -3.0, 0.0, 1.0, -0.2],
        ),
    },
    "SatelliteDynamics": {"unphysical": unphysical, "interpolated": hub_interpolated},
}

results = {}
arguments = sys.argv[2:]
chosen = None
if arguments and arguments[0].startswith("programs="):
    chosen = {p: OPTIONAL[p] for p in arguments.pop(0).split("=", 1)[1].split(",")}
for argument in arguments:
    name, path = argument.split("=", 1)
    for program, function in (chosen or {**PROGRAMS, **SPECIAL.get(name, {})}).items():
        fmu = Fmu(path, "a")
        results[f"{name}:{program}"] = function(fmu)
        fmu.dll.fmi2FreeInstance(fmu.c)
print(json.dumps(results))
