"""FMI hosts in the ways third-party tools drive our FMUs, for tests/interop/test_hosts.py.

    python late_input_host.py defaults FMU              fmpy.simulate_fmu at its defaults
                                                        (its DefaultExperiment)
    python late_input_host.py late FMU READ JSON        inputs set only after initialisation
    python late_input_host.py warning FMU RETURN_OK     a warning condition, logging off

Prints one JSON line.  ``late``: a host like FMPy's SSP prototype sets the parameters,
initialises with no inputs, then sets the inputs in JSON ({"name": [values]}) before the
first doStep; with READ = 1 it reads every output first (as a Jacobi host does at the
start time), with 0 it does not.  Reports the doStep status, the messages logged, and the
Real outputs after the step.  ``warning``: CmgSteering at an exactly singular gimbal set
(all zero), with ``warnings_return_ok`` as given; logging (fmi2SetDebugLogging) stays
off; reads the outputs and steps once; reports the worst status of the two calls and the
messages the host received.
"""

import ctypes
import json
import sys

import fmpy
from fmpy import read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy


def logger_into(messages):
    def log(_env, _name, status, category, message):
        messages.append([int(status), category.decode(), message.decode()])

    return log


def defaults(path):
    messages = []
    experiment = read_model_description(path).defaultExperiment
    result = fmpy.simulate_fmu(path, logger=logger_into(messages))
    finite = bool(all(all(abs(x) < float("inf") for x in row) for row in result.tolist()))
    declared = experiment and [
        float(x) for x in (experiment.startTime, experiment.stopTime, experiment.stepSize)
    ]
    return {
        "rows": len(result),
        "stop": float(result["time"][-1]),
        "experiment": declared,
        "messages": messages,
        "finite": finite,
    }


def open_slave(path, messages):
    md = read_model_description(path)
    unzipped = fmpy.extract(path)
    slave = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipped,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="x",
    )
    callbacks = fmi2CallbackFunctions()  # as fmpy.simulate_fmu builds them
    callbacks.logger = fmi2CallbackLoggerTYPE(logger_into(messages))
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
    addLoggerProxy(ctypes.byref(callbacks))
    slave.instantiate(loggingOn=False, callbacks=callbacks)
    return md, slave


def raw_do_step(slave, t, h) -> int:
    """fmi2DoStep's status as returned (FMPy raises only above fmi2Warning)."""
    return slave.dll.fmi2DoStep(slave.component, ctypes.c_double(t), ctypes.c_double(h), 1)


def raw_get_real(slave, refs) -> int:
    n = len(refs)
    return slave.dll.fmi2GetReal(
        slave.component, (ctypes.c_uint * n)(*refs), n, (ctypes.c_double * n)()
    )


def late(path, read, inputs):
    messages = []
    md, slave = open_slave(path, messages)
    refs = {v.name: v.valueReference for v in md.modelVariables}
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    outputs = [v for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    if int(read):
        slave.getReal([v.valueReference for v in outputs])
    for name, values in json.loads(inputs).items():
        slave.setReal([refs[f"{name}[{i + 1}]"] for i in range(len(values))], values)
    status = raw_do_step(slave, 0.0, 0.1)
    values = (
        dict(zip([v.name for v in outputs], slave.getReal([v.valueReference for v in outputs])))
        if status == 0
        else {}
    )
    slave.terminate()
    slave.freeInstance()
    return {"status": status, "messages": messages, "outputs": values}


def warning(path, return_ok):
    messages = []
    md, slave = open_slave(path, messages)
    refs = {v.name: v.valueReference for v in md.modelVariables}
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setBoolean([refs["warnings_return_ok"]], [bool(int(return_ok))])
    slave.setReal([refs[f"delta[{i}]"] for i in range(1, 7)], [0.0] * 6)
    slave.exitInitializationMode()
    statuses = [raw_get_real(slave, [refs["singularity"]]), raw_do_step(slave, 0.0, 0.1)]
    slave.terminate()
    slave.freeInstance()
    return {"status": max(statuses), "messages": messages}


if __name__ == "__main__":
    command, *args = sys.argv[1:]
    print(json.dumps({"defaults": defaults, "late": late, "warning": warning}[command](*args)))
