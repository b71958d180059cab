"""A generic FMI 2.0 co-simulation host that interpolates inputs: it sends the derivative
of every input it can and asks the derivatives of every output there are.

    python interpolating_host.py SYSTEM.ssd|.ssp STOP STEP OUT.npz [--no-derivatives]
        [--read-after-step] [--gauss-seidel]

Run as a script in a fresh process (tests/interop/test_interpolating_host.py,
tests/interop/test_end_of_step.py).  It knows nothing of our FMUs: it reads the system
(components, connections, parameter values) and drives the FMUs with fmpy's FMU2Slave by
their model descriptions alone.

Its algorithm: parameters set after instantiation; in initialisation mode and after every
step the outputs and inputs are settled by passes over the connections (set every input
from its output, read the outputs again) until nothing changes (a system without
algebraic loops settles in at most as many passes as it has components); then Jacobi: every
FMU steps from the inputs of t_n.  Before each step, for every connection into an FMU that
declares ``canInterpolateInputs`` from an FMU that declares ``maxOutputDerivativeOrder`` of
1 or more, the output's first derivative (``fmi2GetRealOutputDerivatives``) is set as the
input's (``fmi2SetRealInputDerivatives``), and the first derivatives of every Real output
of every FMU declaring them are asked and checked finite.  Columns "time", then
"Instance.output" of every output of every FMU, a row at the start and after each step;
with ``--no-derivatives`` nothing is sent or asked.  Exit status 2 with the FMU's message if
a call fails; the rows so far are saved all the same.

``--read-after-step``: the outputs are read right after the steps, no input set again
first (as libcosim and ECOS do); every input is set once from them before the next step.
``--gauss-seidel``: the FMUs step one after the other in the system's order, each right
after its inputs are set from the newest outputs, its outputs read right after its step
(or, without ``--read-after-step``, after its inputs are set again from the newest
outputs); a derivative link from an FMU that already stepped is interpolated, the value
y_n set with the slope (y_{n+1} − y_n)/H, one from an FMU still to step extrapolated.
"""

import ctypes
import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

from agilesat.orchestration.system.ssp import read_system

GET = {"Real": "getReal", "Integer": "getInteger", "Boolean": "getBoolean"}
SET = {"Real": "setReal", "Integer": "setInteger", "Boolean": "setBoolean", "String": "setString"}


class Fmu:
    def __init__(self, component, messages: list):
        self.name, path = component.name, str(component.source)
        self.md = read_model_description(path)
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.outputs = [v for v in self.md.modelVariables if v.causality == "output"]
        self.slave = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=extract(path),
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=self.name,
        )
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda env, instance, status, category, message: messages.append(
                f"{instance.decode()} [{status}] {message.decode()}"
            )
        )
        self._callbacks = callbacks
        self.slave.instantiate(callbacks=callbacks)
        self.interpolates = bool(self.md.coSimulation.canInterpolateInputs)
        self.order = int(self.md.coSimulation.maxOutputDerivativeOrder or 0)
        self.real_outputs = [v.valueReference for v in self.outputs if v.type == "Real"]

    def get(self, type_name, vrs):
        return list(getattr(self.slave, GET[type_name])(vrs)) if vrs else []

    def set(self, type_name, vrs, values):
        if type_name == "String":
            values = [v.encode() for v in values]
        getattr(self.slave, SET[type_name])(vrs, values)

    def outputs_now(self):
        values = {}
        for type_name in GET:
            vrs = [v.valueReference for v in self.outputs if v.type == type_name]
            values.update(zip(((type_name, vr) for vr in vrs), self.get(type_name, vrs)))
        return [float(values[v.type, v.valueReference]) for v in self.outputs]

    def derivatives(self, vrs):
        """fmi2GetRealOutputDerivatives, order 1, of ``vrs``."""
        n = len(vrs)
        values = (ctypes.c_double * n)()
        status = self.slave.dll.fmi2GetRealOutputDerivatives(
            self.slave.component, (ctypes.c_uint * n)(*vrs), n, (ctypes.c_int * n)(*[1] * n), values
        )
        if status > 1:
            raise RuntimeError(f"{self.name}: fmi2GetRealOutputDerivatives returned {status}")
        return list(values)

    def set_derivatives(self, vrs, values):
        n = len(vrs)
        status = self.slave.dll.fmi2SetRealInputDerivatives(
            self.slave.component,
            (ctypes.c_uint * n)(*vrs),
            n,
            (ctypes.c_int * n)(*[1] * n),
            (ctypes.c_double * n)(*values),
        )
        if status > 1:
            raise RuntimeError(f"{self.name}: fmi2SetRealInputDerivatives returned {status}")


class Wires:
    """The connections grouped per (source, target, type), for array gets and sets."""

    def __init__(self, fmus, connections):
        groups: dict = {}
        for c in connections:
            source, target = fmus[c.start_element], fmus[c.end_element]
            y, u = source.variables[c.start_connector], target.variables[c.end_connector]
            group = groups.setdefault((c.start_element, c.end_element, y.type), ([], []))
            group[0].append(y.valueReference)
            group[1].append(u.valueReference)
        self.groups = [
            (fmus[a], fmus[b], type_name, ys, us) for (a, b, type_name), (ys, us) in groups.items()
        ]
        self.last: dict = {}
        self.passes = len(fmus) + 1

    def settle(self):
        """Pass over the connections until no input changes (module docstring)."""
        for _ in range(self.passes):
            changed = False
            for k, (source, target, type_name, ys, us) in enumerate(self.groups):
                values = source.get(type_name, ys)
                if self.last.get(k) != values:
                    target.set(type_name, us, values)
                    self.last[k], changed = values, True
            if not changed:
                return
        raise RuntimeError("the inputs do not settle: an algebraic loop?")

    def feed(self, target=None):
        """Every input (of ``target``) set once from the outputs as they are now: all read
        first, then all set (a set of a feedthrough input would change what a later read
        gives)."""
        chosen = [g for g in self.groups if target is None or g[1] is target]
        values = [source.get(type_name, ys) for source, _, type_name, ys, _ in chosen]
        for (_, to, type_name, _, us), got in zip(chosen, values):
            to.set(type_name, us, got)


def main(path, stop, step, out, *options):
    stop, step, derivatives = float(stop), float(step), "--no-derivatives" not in options
    after_step, gauss_seidel = "--read-after-step" in options, "--gauss-seidel" in options
    messages: list[str] = []
    system = read_system(path)
    fmus = {c.name: Fmu(c, messages) for c in system.components}
    start = system.start_time
    links = []  # (source FMU, output vr, target FMU, input vr): derivatives passed
    for c in system.connections:
        source, target = fmus[c.start_element], fmus[c.end_element]
        y, u = source.variables[c.start_connector], target.variables[c.end_connector]
        if target.interpolates and source.order >= 1 and u.type == "Real":
            links.append((source, y.valueReference, target, u.valueReference))
    names = ["time"] + [f"{name}.{v.name}" for name, fmu in fmus.items() for v in fmu.outputs]
    rows = []
    try:
        for fmu in fmus.values():
            fmu.slave.setupExperiment(startTime=start, stopTime=stop)
        for p in system.parameters:
            fmu = fmus[p.component]
            fmu.set(p.type, [fmu.variables[p.name].valueReference], [p.value])
        wires = Wires(fmus, system.connections)
        for fmu in fmus.values():
            fmu.slave.enterInitializationMode()
        wires.settle()
        for fmu in fmus.values():
            fmu.slave.exitInitializationMode()
        wires.last.clear()  # the outputs of the initialised models
        wires.settle()
        rows.append([start] + [x for fmu in fmus.values() for x in fmu.outputs_now()])
        for k in range(round((stop - start) / step)):
            t = start + k * step
            if derivatives:
                for fmu in fmus.values():  # every output's derivative, asked and checked
                    if fmu.order >= 1 and not np.all(
                        np.isfinite(fmu.derivatives(fmu.real_outputs))
                    ):
                        raise RuntimeError(f"{fmu.name}: non-finite output derivatives at t={t}")
            if gauss_seidel:
                _gauss_seidel(fmus, wires, links if derivatives else [], t, step, after_step)
            else:
                for source, y, target, u in links if derivatives else []:
                    target.set_derivatives([u], source.derivatives([y]))
                for fmu in fmus.values():
                    fmu.slave.doStep(currentCommunicationPoint=t, communicationStepSize=step)
            if not after_step:
                if gauss_seidel:
                    wires.last.clear()  # the inputs were set outside settle()
                wires.settle()
            rows.append(
                [start + (k + 1) * step] + [x for f in fmus.values() for x in f.outputs_now()]
            )
            if after_step and not gauss_seidel:
                wires.feed()
    finally:
        np.savez(out, names=np.array(names), data=np.array(rows, dtype=float))
        print("\n".join(messages))
    print(f"{len(links)} derivative links")


def _gauss_seidel(fmus, wires, links, t, step, after_step):
    """One macro step of the Gauss-Seidel scheme (module docstring)."""
    start = {(source, y): source.get("Real", [y])[0] for source, y, _, _ in links}
    stepped = set()
    for fmu in fmus.values():
        wires.feed(fmu)
        for source, y, target, u in links:
            if target is not fmu:
                continue
            if source in stepped:  # y_n with the slope to y_{n+1}
                y_n = start[source, y]
                target.set("Real", [u], [y_n])
                target.set_derivatives([u], [(source.get("Real", [y])[0] - y_n) / step])
            else:
                target.set_derivatives([u], source.derivatives([y]))
        fmu.slave.doStep(currentCommunicationPoint=t, communicationStepSize=step)
        stepped.add(fmu)
        if not after_step:
            wires.feed(fmu)


if __name__ == "__main__":
    try:
        main(*sys.argv[1:])
    except Exception as error:  # noqa: BLE001 - report the FMU's failure, keep the rows
        print(error, file=sys.stderr)
        sys.exit(2)
