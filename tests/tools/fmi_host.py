"""A plain FMI 2.0 host on fmpy, run by the tests in a fresh interpreter.

It does not import agilesat: it uses built FMUs the way any third-party importer does and
prints its findings as JSON.  Usage: ``python fmi_host.py COMMAND FMU...``
"""

import ctypes
import json
import math
import sys

from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    calloc,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    free,
)


class Fmu:
    """One instance, raw FMI calls returning statuses, log messages collected."""

    def __init__(self, path, name):
        self.md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages = []
        self.slave = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=extract(path),
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda env, inst, status, cat, msg: self.messages.append((status, msg.decode()))
        )
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self._callbacks = callbacks
        self.slave.instantiate(callbacks=callbacks)
        self.c = self.slave.component
        self.dll = self.slave.dll

    def names(self, causality, type_="Real"):
        return [
            v.name for v in self.md.modelVariables if v.causality == causality and v.type == type_
        ]

    def set_real(self, values: dict) -> int:
        vr = (ctypes.c_uint * len(values))(*(self.vr[n] for n in values))
        array = (ctypes.c_double * len(values))(*values.values())
        return self.dll.fmi2SetReal(self.c, vr, len(values), array)

    def get_real(self, names):
        vr = (ctypes.c_uint * len(names))(*(self.vr[n] for n in names))
        array = (ctypes.c_double * len(names))()
        status = self.dll.fmi2GetReal(self.c, vr, len(names), array)
        return status, list(array)

    def initialize(self, inputs=None):
        assert self.dll.fmi2SetupExperiment(self.c, 0, 0.0, 0.0, 0, 0.0) == 0
        assert self.dll.fmi2EnterInitializationMode(self.c) == 0
        if inputs:
            assert self.set_real(inputs) == 0
        assert self.dll.fmi2ExitInitializationMode(self.c) == 0

    def step(self, t, h) -> int:
        return self.dll.fmi2DoStep(self.c, t, h, 1)


def orbit_geometry(k):
    """A consistent orbit geometry, changing with k: an equatorial circular orbit at angle
    0.01 k, its orbit frame q_OI (DESIGN.md §2: z = −r̂, y = −ĥ), a target below it on an
    Earth turning at 7.292e-5 rad/s, a geomagnetic field of 30 µT turning with it."""
    a, mu, earth_rate, radius = 6.945e6, 3.986004418e14, 7.292115e-5, 6.378e6
    u = 0.01 * k
    c, s = math.cos(u), math.sin(u)
    speed = math.sqrt(mu / a)
    C = ((-s, c, 0.0), (0.0, 0.0, -1.0), (-c, -s, 0.0))  # rows x_O, y_O, z_O in I
    q0 = 0.5 * math.sqrt(1.0 + C[0][0] + C[1][1] + C[2][2])  # C = (q0² − q·q) 1 + 2 q qᵀ
    q = [
        q0,
        (C[1][2] - C[2][1]) / (4 * q0),
        (C[2][0] - C[0][2]) / (4 * q0),  # − 2 q0 [q×]
        (C[0][1] - C[1][0]) / (4 * q0),
    ]
    return {
        "r_I": [a * c, a * s, 0.0],
        "v_I": [-speed * s, speed * c, 0.0],
        "q_OI": q,
        "r_T_I": [radius * c, radius * s, 1.0e5],
        "v_T_I": [-earth_rate * radius * s, earth_rate * radius * c, 0.0],
        "b_B": [1.5e-5 * c, 1.5e-5 * s, -2.6e-5],
    }


def plausible_inputs(fmu, k=0):
    """Valid values for every Real input: the geometry of :func:`orbit_geometry`, unit
    quaternions, small values elsewhere."""
    values = {}
    geometry = orbit_geometry(k)
    for name in fmu.names("input"):
        base, _, index = name.partition("[")
        i = int(index.split(",")[0].rstrip("]")) if index else 1
        if base in geometry:
            values[name] = geometry[base][i - 1]
        elif base.startswith("q_"):
            angle = 0.1 * (k + 1)
            values[name] = [math.cos(angle), math.sin(angle), 0.0, 0.0][i - 1]
        else:
            values[name] = 0.01 * math.sin(i + 0.7 * k)
    return values


def state(path):
    """Save, step, restore, step again: identical outputs (and through serialization)."""
    fmu = Fmu(path, "a")
    fmu.initialize(plausible_inputs(fmu))
    outputs = fmu.names("output")
    t, h = 0.0, 0.05
    for k in range(5):
        assert fmu.set_real(plausible_inputs(fmu, k)) == 0 and fmu.step(t, h) == 0
        t += h

    def run(t0):
        trace = []
        for k in range(10):
            fmu.set_real(plausible_inputs(fmu, 5 + k))
            assert fmu.step(t0 + k * h, h) == 0
            trace.append(fmu.get_real(outputs)[1])
        return trace

    saved = ctypes.c_void_p()
    assert fmu.dll.fmi2GetFMUstate(fmu.c, ctypes.byref(saved)) == 0
    first = run(t)
    assert fmu.dll.fmi2SetFMUstate(fmu.c, saved) == 0
    second = run(t)
    size = ctypes.c_size_t()
    assert fmu.dll.fmi2SerializedFMUstateSize(fmu.c, saved, ctypes.byref(size)) == 0
    data = (ctypes.c_char * size.value)()
    assert fmu.dll.fmi2SerializeFMUstate(fmu.c, saved, data, size) == 0
    restored = ctypes.c_void_p()
    assert fmu.dll.fmi2DeSerializeFMUstate(fmu.c, data, size, ctypes.byref(restored)) == 0
    assert fmu.dll.fmi2SetFMUstate(fmu.c, restored) == 0
    third = run(t)
    changed = any(a != b for a, b in zip(first[0], first[-1]))
    return {
        "restored_identical": first == second,
        "deserialized_identical": first == third,
        "outputs_change": changed,
        "n_outputs": len(outputs),
    }


def errors(path):
    """Statuses of bad calls, and that the instance still works afterwards."""
    fmu = Fmu(path, "bad")
    fmu.initialize(plausible_inputs(fmu))
    first_input = fmu.names("input")[0] if fmu.names("input") else None
    parameter = fmu.names("parameter")[0]
    output = fmu.names("output")[0]
    result = {
        "zero_step": fmu.step(0.0, 0.0),
        "negative_step": fmu.step(0.0, -0.1),
        "nan_step": fmu.step(0.0, float("nan")),
        "time_jump": fmu.step(5.0, 0.1),
        "unknown_vr_get": fmu.dll.fmi2GetReal(
            fmu.c, (ctypes.c_uint * 1)(10**6), 1, (ctypes.c_double * 1)()
        ),
        "unknown_vr_set": fmu.dll.fmi2SetReal(
            fmu.c, (ctypes.c_uint * 1)(10**6), 1, (ctypes.c_double * 1)(1.0)
        ),
        "wrong_type": fmu.dll.fmi2GetInteger(
            fmu.c, (ctypes.c_uint * 1)(fmu.vr[output]), 1, (ctypes.c_int * 1)()
        ),
        "set_output": fmu.set_real({output: 1.0}),
        "set_parameter_after_init": fmu.set_real({parameter: 1.0}),
    }
    if first_input:
        result["nan_input"] = fmu.set_real({first_input: float("nan")})
        result["inf_input"] = fmu.set_real({first_input: float("inf")})
    result["valid_step_after_errors"] = fmu.step(0.0, 0.1)
    result["valid_get_after_errors"] = fmu.get_real([output])[0]
    result["messages"] = [m for s, m in fmu.messages if s >= 3]
    return result


def together(*paths):
    """All FMUs and a second instance of the first, side by side, stepped."""
    fmus = [Fmu(p, f"i{k}") for k, p in enumerate(paths)] + [Fmu(paths[0], "twin")]
    for k, fmu in enumerate(fmus):
        fmu.initialize(plausible_inputs(fmu, 3 * k if fmu.slave.instanceName == "twin" else 0))
    statuses = []
    for n in range(20):
        for fmu in fmus:
            statuses.append(fmu.step(n * 0.05, 0.05))
    first, twin = fmus[0], fmus[-1]
    outputs = first.names("output")
    return {
        "all_ok": all(s == 0 for s in statuses),
        "instances": len(fmus),
        "twin_differs": first.get_real(outputs)[1] != twin.get_real(outputs)[1],
    }


def singularity(*paths):
    """The CmgCluster output 'singularity' of each FMU given, loaded side by side."""
    fmus = [Fmu(p, f"c{k}") for k, p in enumerate(paths)]
    for fmu in fmus:
        fmu.initialize()
    return {"singularity": [fmu.get_real(["singularity"])[1][0] for fmu in fmus]}


def shadowed(path):
    """Import and patch the host's own agilesat copy first: the FMU must not see it."""
    import agilesat.components.cmg_cluster as host_copy

    host_copy.det3 = lambda M: 123.0
    fmu = Fmu(path, "c")
    fmu.initialize()
    return {
        "singularity": fmu.get_real(["singularity"])[1][0],
        "host_patched": host_copy.det3(None),
    }


def many(path, count):
    """Instantiate many instances and leave them alive at exit (exit must be clean)."""
    fmus = [Fmu(path, f"m{k}") for k in range(int(count))]
    for fmu in fmus:
        fmu.initialize()
    return {"instances": len(fmus)}


if __name__ == "__main__":
    command, *arguments = sys.argv[1:]
    print(json.dumps(globals()[command](*arguments)))
