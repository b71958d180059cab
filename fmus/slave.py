"""The one generic pythonfmu slave: maps FMI calls onto a :class:`components.model.Model`.

Every FMU of the toolkit is ``class Name(ModelSlave): model_class = ...`` and nothing more;
the variables come from the model's table.  Value reference = offset in the model's flat
value array (see ``components/variables.py``).

pythonfmu turns any Python exception into ``fmi2Fatal`` and can only return OK or Discard,
so no exception leaves this class: a bad call is *logged* at ``fmi2Error`` and answered
with a harmless value, and the FMU's C shim (``shim/agilesat_fmi2.c``) returns the worst
status logged during the call.  Checked here: unknown value reference or wrong type,
setting an output or a fixed parameter after initialisation, non-finite values,
non-positive or non-finite step size, a time discontinuity between steps, calls in the
wrong mode, and exceptions or non-finite outputs from the model.
"""
from __future__ import annotations

import functools
import math
import pickle
import traceback

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.enums import Fmi2Status

from ..components.model import ModelError

PARAMETER, INPUT, OUTPUT = 0, 1, 2
_CAUSALITY_CODE = {"parameter": PARAMETER, "input": INPUT, "output": OUTPUT}
_TYPE_CODE = {"Real": 0, "Integer": 1, "Boolean": 2, "String": 3}
_PLAN_CACHE_SIZE = 64


def _guarded(default):
    """Run an FMI entry point; turn any exception into a logged fmi2Error."""
    def decorate(method):
        @functools.wraps(method)
        def wrapper(self, *args):
            try:
                return method(self, *args)
            except (_CallRejected, ModelError) as rejected:
                self._error(f"{method.__name__}: {rejected}")
            except Exception as exc:  # noqa: BLE001 - the FMI boundary
                self._error(f"{method.__name__}: {type(exc).__name__}: {exc}\n"
                            f"{traceback.format_exc(limit=4)}")
            return default(*args) if callable(default) else default
        return wrapper
    return decorate


def _zeros(vrs):
    return [0] * len(vrs)


class _CallRejected(Exception):
    pass


class ModelSlave(Fmi2Slave):
    model_class = None  # set by each FMU wrapper

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.model = self.model_class()
        layout = self.model.layout
        self._layout = layout
        self._scalar_names = [name for _, name in layout.scalars]
        self._causality = np.array([_CAUSALITY_CODE[v.causality] for v, _ in layout.scalars])
        self._type = np.array([_TYPE_CODE[v.type] for v, _ in layout.scalars])
        self._string_names = [v.name for v in layout.variables if v.type == "String"]
        self._outputs = slice(layout.range["output"].start, layout.range["output"].stop)
        self._plans: dict = {}
        self._mode = "instantiated"
        self._start_time = 0.0
        self._next_time: float | None = None
        self._state_valid = False
        self._outputs_valid = False

    # -- FMI life cycle ------------------------------------------------------------
    @_guarded(None)
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)

    @_guarded(None)
    def enter_initialization_mode(self):
        self._mode = "initialization"

    @_guarded(None)
    def exit_initialization_mode(self):
        self._ensure_state()
        self._mode = "step"
        self._next_time = self._start_time

    @_guarded(False)
    def do_step(self, current_time, step_size):
        if self._mode != "step":
            raise _CallRejected(f"called in mode '{self._mode}' (expected after "
                                "exitInitializationMode)")
        if not (math.isfinite(step_size) and step_size > 0.0):
            raise _CallRejected(f"step size must be positive and finite, got {step_size!r}")
        if not math.isclose(current_time, self._next_time, rel_tol=1e-9, abs_tol=1e-12):
            raise _CallRejected(f"time discontinuity: the last step ended at "
                                f"t={self._next_time!r}, doStep starts at t={current_time!r}")
        self.model.step(current_time, step_size)
        self._flush_warnings()
        self._next_time = current_time + step_size
        self._outputs_valid = False
        return True

    @_guarded(None)
    def terminate(self):
        self._mode = "terminated"

    # -- getters and setters -------------------------------------------------------
    @_guarded(_zeros)
    def get_real(self, vrs):
        return self._read(vrs, "Real").tolist()

    @_guarded(_zeros)
    def get_integer(self, vrs):
        return [int(x) for x in self._read(vrs, "Integer")]

    @_guarded(_zeros)
    def get_boolean(self, vrs):
        return [bool(x) for x in self._read(vrs, "Boolean")]

    @_guarded(lambda vrs: [""] * len(vrs))
    def get_string(self, vrs):
        self._plan(vrs, "String")
        return [self.model.strings[self._scalar_names[vr]] for vr in vrs]

    @_guarded(None)
    def set_real(self, vrs, values):
        self._write(vrs, values, "Real")

    @_guarded(None)
    def set_integer(self, vrs, values):
        self._write(vrs, values, "Integer")

    @_guarded(None)
    def set_boolean(self, vrs, values):
        self._write(vrs, [1.0 if v else 0.0 for v in values], "Boolean")

    @_guarded(None)
    def set_string(self, vrs, values):
        self._plan(vrs, "String", setting=True)
        for vr, value in zip(vrs, values):
            self.model.strings[self._scalar_names[vr]] = value
        self._state_valid = self._outputs_valid = False

    # -- FMU state -----------------------------------------------------------------
    def _get_fmu_state(self):
        wrapper = (self._mode, self._start_time, self._next_time,
                   self._state_valid, self._outputs_valid)
        return self.model.get_state(), wrapper

    def _set_fmu_state(self, state):
        model_state, wrapper = state
        self.model.set_state(model_state)
        (self._mode, self._start_time, self._next_time,
         self._state_valid, self._outputs_valid) = wrapper

    @staticmethod
    def _fmu_state_to_bytes(state) -> bytes:
        return pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL)

    @staticmethod
    def _fmu_state_from_bytes(data: bytes):
        return pickle.loads(data)

    # -- internals -----------------------------------------------------------------
    def _error(self, message: str) -> None:
        self.log(f"{self.model_class.__name__} '{self.instance_name}': {message}",
                 Fmi2Status.error)

    def _plan(self, vrs, type_name: str, setting: bool = False):
        """Validate a value-reference list once; cached per (type, list, direction)."""
        key = (type_name, setting, tuple(vrs))
        plan = self._plans.get(key)
        if plan is None:
            plan = self._make_plan(vrs, type_name, setting)
            if len(self._plans) < _PLAN_CACHE_SIZE:
                self._plans[key] = plan
        if isinstance(plan, str):
            raise _CallRejected(plan)
        index, touches_parameters = plan
        if setting and touches_parameters and self._mode in ("step", "terminated"):
            names = [self._scalar_names[vr] for vr in vrs
                     if self._causality[vr] == PARAMETER]
            raise _CallRejected(f"parameters {names} are fixed: they can only be set before "
                                "exitInitializationMode")
        return index

    def _make_plan(self, vrs, type_name, setting):
        n = len(self._scalar_names)
        unknown = [vr for vr in vrs if not 0 <= vr < n]
        if unknown:
            return f"unknown value references {unknown} (this FMU has 0..{n - 1})"
        index = np.array(vrs, dtype=np.intp)
        wrong = [self._scalar_names[i] for i in index if self._type[i] != _TYPE_CODE[type_name]]
        if wrong:
            return f"variables {wrong} are not of type {type_name}"
        if setting:
            outputs = [self._scalar_names[i] for i in index if self._causality[i] == OUTPUT]
            if outputs:
                return f"outputs {outputs} cannot be set"
        touches_parameters = bool(np.any(self._causality[index] == PARAMETER))
        if len(vrs) and list(vrs) == list(range(vrs[0], vrs[0] + len(vrs))):
            index = slice(vrs[0], vrs[0] + len(vrs))  # one range: a view, not a gather
        return index, touches_parameters

    def _read(self, vrs, type_name):
        index = self._plan(vrs, type_name)
        values = self.model.values
        if not self._outputs_valid:
            self._ensure_state()
            self.model.output()
            outputs = values[self._outputs].tolist()
            if not math.isfinite(sum(outputs)) and not all(map(math.isfinite, outputs)):
                bad = [name for name, x in zip(self._scalar_names[self._outputs], outputs)
                       if not math.isfinite(x)]
                raise _CallRejected(f"the model produced non-finite outputs {bad} at "
                                    f"t={self.model.t!r}")
            self._outputs_valid = True
        return values[index]

    def _write(self, vrs, values, type_name):
        index = self._plan(vrs, type_name, setting=True)
        if not math.isfinite(sum(values)) and not all(map(math.isfinite, values)):
            bad = [f"{self._scalar_names[vr]}={x!r}" for vr, x in zip(vrs, values)
                   if not math.isfinite(x)]
            raise _CallRejected(f"non-finite values rejected: {bad}")
        self.model.values[index] = values
        if self._mode in ("instantiated", "initialization"):
            self._state_valid = False
        self._outputs_valid = False

    def _ensure_state(self):
        if not self._state_valid:
            self.model.initialize(self._start_time)
            self._flush_warnings()
            self._state_valid = True

    def _flush_warnings(self):
        """The model's warnings, at category logStatusWarning; with the parameter
        warnings_return_ok at status fmi2OK, which the shim forwards to the host (even
        with debug logging off) without raising the call's status."""
        status = Fmi2Status.ok if self.model.p.warnings_return_ok else Fmi2Status.warning
        for message in self.model.warnings:
            self.log(f"{self.model_class.__name__} '{self.instance_name}': {message}",
                     status, "logStatusWarning")
        self.model.warnings.clear()
