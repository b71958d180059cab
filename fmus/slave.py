"""The one generic pythonfmu slave: maps FMI calls onto a :class:`components.model.Model`.

Every FMU of the toolkit is ``class Name(ModelSlave): model_class = ...`` and nothing more;
the variables come from the model's table.  Value reference = offset in the model's flat
value array (see ``components/variables.py``).

pythonfmu turns any Python exception into ``fmi2Fatal`` and can only return OK or Discard,
so no exception leaves this class: a bad call is *logged* at ``fmi2Error`` and answered
with a harmless value, and the FMU's C shim (``shim/agilesat_fmi2.c``) returns the worst
status logged during the call.  Checked here: unknown value reference or wrong type,
setting an output or a fixed parameter after initialisation, non-finite values,
non-positive or non-finite step size, a time discontinuity between steps, a step past the
stop time fmi2SetupExperiment defined (section 4.2.1), calls in the wrong mode (FMI 2.0
section 4.2.4: setup and entering initialisation only after instantiation, getting nothing
before initialisation mode, setting nothing after terminate, ...), and exceptions,
non-finite outputs, Integer outputs that are not whole numbers of fmi2Integer's range and
Boolean outputs that are not 0 or 1 from the model.  FMU states are data (``fmu_state``),
never pickles.

Input and output derivatives (FMI 2.0 section 4.2.1).  pythonfmu 0.7 answers
``fmi2SetRealInputDerivatives`` and ``fmi2GetRealOutputDerivatives`` "not supported"; the
shim passes them on as ``fmi2SetReal``/``fmi2GetReal`` of the value references
``DERIVATIVE_BASE + (order << ORDER_SHIFT) + vr`` (a range no variable has).  An FMU whose
model interpolates its inputs (``INTERPOLATES_INPUTS``: canInterpolateInputs) takes the
first derivative of every continuous Real input into the model's derivative block
(``components/variables.py``, ``Layout``): it stays until set again, like any input (FMI
2.0 puts the same restrictions on it as on ``fmi2SetReal``), and the model uses it where
it integrates the input (``components/model.py``; an input that *is* another's rate, as
``hdot_cmg`` of ``h_cmg``, is never overwritten by it).  An FMU whose model has
``OUTPUT_DERIVATIVES`` (maxOutputDerivativeOrder 1) answers the first derivative of every
Real output at the current time: the value of its declared derivative output (``hdot`` of
``h``), else ``Model.output_derivatives``.  Refused with fmi2Error, naming the variable: a
variable that is not a continuous Real input (output) of an FMU declaring the capability,
an order other than 1, a non-finite derivative, setting after ``fmi2Terminate``, getting
before ``fmi2ExitInitializationMode`` (FMI 2.0 section 4.2.4's state table).

The shim's fast paths (``fast_paths.py``, ``shim/fast_paths.c``) answer many calls in C
from the arrays this slave shares with them; the state machine's own flags live there
(``_outputs_valid``, ``_next_time``: the step's end), and ``_guarded``, the one door of
every call, lets the fast paths take over what the shim did before the call (``sync``)
and tell it what it may do after (``leave``).
"""

from __future__ import annotations

import functools
import json
import math
import os
import sys
import traceback

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.enums import Fmi2Status

from ..components.model import ModelError
from ..components.runtime import jit
from ..components.runtime.switches import SwitchError
from . import CONFIGURATION, configuration_key, fmu_state, state_layout
from .fast_paths import FastPaths, kind
from .protocol import (
    B_STOP,
    B_TIME,
    C_DIRTY,
    DERIVATIVE_BASE,
    FAST_PATH_N,
    FAST_PATH_VR,
    KIND_OTHER,
    ORDER_SHIFT,
    OUTPUTS_VALID,
    continuous,
    fmu_guid,
)

PARAMETER, INPUT, OUTPUT = 0, 1, 2
_CAUSALITY_CODE = {"parameter": PARAMETER, "input": INPUT, "output": OUTPUT}
_TYPE_CODE = {"Real": 0, "Integer": 1, "Boolean": 2, "String": 3}
_PLAN_CACHE_SIZE = 256  # per model class
_PACKAGE = __name__.split(".")[0]  # agilesat_<hash> inside an FMU
_MODES = ("instantiated", "initialization", "step", "terminated")
#: the handshake's value reference as pythonfmu 0.7.0 passes it (a C int) and as unsigned
_HANDSHAKE = (FAST_PATH_VR - (1 << 32), FAST_PATH_VR)
_INT32 = (-(2**31), 2**31 - 1)  # fmi2Integer


def _guarded(default):
    """Run an FMI entry point; turn any exception into a logged fmi2Error."""

    def decorate(method):
        @functools.wraps(method)
        def wrapper(self, *args):
            fast = self._fast
            if fast.control[C_DIRTY]:  # the shim served calls in C since the last entry
                fast.sync()
            try:
                return method(self, *args)
            except (_CallRejected, ModelError, SwitchError) as rejected:
                self._error(f"{method.__name__}: {rejected}")
            except Exception as exc:  # noqa: BLE001 - the FMI boundary
                self._error(
                    f"{method.__name__}: {type(exc).__name__}: {exc}\n"
                    f"{traceback.format_exc(limit=4)}"
                )
            finally:
                fast.leave()
            return default(*args) if callable(default) else default

        return wrapper

    return decorate


def _zeros(vrs):
    return [0] * len(vrs)


class _CallRejected(Exception):
    pass


class _Rejected:
    """What deserializing bytes that are not a state of this FMU gives (never raised)."""

    __slots__ = ("reason",)

    def __init__(self, reason: str):
        self.reason = reason


def _rejection(state) -> str:
    if isinstance(state, _Rejected):
        return f"not a state of this FMU: {state.reason}"
    return f"not a state of this FMU (a {type(state).__name__})"


class _Constants:
    """What a slave reads from its model's layout, the same for every instance of a model
    class: made once per class and layout (an instance was ~0.1 ms of every fmi2Instantiate
    and fmi2Reset making them), and the value-reference lists checked (a new instance
    checked again each list a host passes).  Shared: never written (the arrays are
    read-only)."""

    _made: dict[type, _Constants] = {}

    @classmethod
    def of(cls, model_class: type, layout) -> _Constants:
        made = cls._made.get(model_class)
        if made is None or made.layout is not layout:
            made = cls._made[model_class] = cls(layout)
        return made

    def __init__(self, layout):
        self.layout = layout
        self.scalar_names = [name for _, name in layout.scalars]
        self.causality = _frozen([_CAUSALITY_CODE[v.causality] for v, _ in layout.scalars])
        self.type = _frozen([_TYPE_CODE[v.type] for v, _ in layout.scalars])
        self.string_names = [v.name for v in layout.variables if v.type == "String"]
        self.outputs = slice(layout.range["output"].start, layout.range["output"].stop)
        #: vr of an output with a declared derivative output -> vr of that output
        self.derivative = {
            layout.offset[v.derivative_of] + k: layout.offset[v.name] + k
            for v in layout.group("output")
            if v.derivative_of
            for k in range(v.size)
        }
        #: input vr + block: its derivative in the value array; + n_inputs more: its flag
        self.n_inputs = len(layout.range["input"])
        self.block = layout.n_numeric - layout.range["input"].start
        #: inputs some output depends on directly (its table row's ``depends``)
        feeds = {
            vr
            for v in layout.variables
            for name in v.depends
            for vr in range(layout.offset[name], layout.offset[name] + layout.by_name[name].size)
        }
        self.feeds = _frozen([vr in feeds for vr in range(len(layout.scalars))], dtype=bool)
        kinds = [kind(v.causality, v.type, f) for (v, _), f in zip(layout.scalars, self.feeds)]
        kinds += [KIND_OTHER] * (layout.n_values - len(kinds))  # the derivative block
        self.kinds = _frozen(kinds, dtype=np.uint8)  # each instance its own copy
        #: checked value-reference lists (``ModelSlave._plan``): they depend on these alone
        self.plans: dict = {}


def _same(held: np.ndarray, values) -> bool:
    """Are ``values`` bit for bit the ones ``held`` (0.0 and -0.0 differ)?"""
    given = np.asarray(values, dtype=np.float64)
    return held.shape == given.shape and bool(np.all(held.view(np.uint64) == given.view(np.uint64)))


def _frozen(values, dtype=None) -> np.ndarray:
    array = np.array(values, dtype=dtype)
    array.flags.writeable = False
    return array


class ModelSlave(Fmi2Slave):
    model_class = None  # set by each FMU wrapper
    _configuration_key = ""  # of the values an exported FMU was configured with

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.model = self.model_class()
        layout = self.model.layout
        self._layout = layout
        constants = _Constants.of(type(self.model), layout)
        self._scalar_names = constants.scalar_names
        self._configure(kwargs.get("resources"))
        self._causality, self._type = constants.causality, constants.type
        self._string_names = constants.string_names
        self._outputs = constants.outputs
        self._derivative = constants.derivative
        self._n_inputs, self._block = constants.n_inputs, constants.block
        self._feeds = constants.feeds
        self._fast = FastPaths(self, constants.kinds.copy())
        self._plans = constants.plans  # of value-reference lists, the same for every instance
        self._mode = "instantiated"
        self._start_time = 0.0
        self._stop_time = None  # setupExperiment's, when defined
        self._state_valid = False

    def _configure(self, resources) -> None:
        """The defaults of an FMU configured by ``agilesat export`` (fmus/configure.py):
        the values in its resources' configuration.json, its model description's start
        values."""
        path = os.path.join(resources or "", CONFIGURATION)
        if not resources or not os.path.isfile(path):
            return
        with open(path, "rb") as file:
            data = file.read()
        self._configuration_key = configuration_key(data)  # in the GUID (get_string)
        values = json.loads(data)["values"]
        for scalar, value in values.items():
            vr = self._scalar_names.index(scalar)
            if self._layout.scalars[vr][0].type == "String":
                self.model.strings[scalar] = value
            else:
                self.model.values[vr] = float(value)

    # -- the state machine's flags that live in the arrays shared with the shim --------
    @property
    def _outputs_valid(self) -> bool:
        return bool(self._fast.control[OUTPUTS_VALID])

    @_outputs_valid.setter
    def _outputs_valid(self, valid: bool) -> None:
        self._fast.control[OUTPUTS_VALID] = valid

    @property
    def _next_time(self) -> float | None:
        """The step's end: where the next step must start (None before initialisation
        ends)."""
        end = float(self._fast.block[B_TIME])
        return None if math.isnan(end) else end

    @_next_time.setter
    def _next_time(self, end: float | None) -> None:
        self._fast.block[B_TIME] = math.nan if end is None else end

    # -- FMI life cycle ------------------------------------------------------------
    @_guarded(None)
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._require_mode("instantiated")
        self._start_time = float(start_time)
        stop = None if stop_time is None else float(stop_time)
        self._stop_time = stop if stop is not None and math.isfinite(stop) else None
        self._fast.block[B_STOP] = math.inf if self._stop_time is None else self._stop_time

    @_guarded(None)
    def enter_initialization_mode(self):
        self._require_mode("instantiated")
        self._mode = "initialization"

    @_guarded(None)
    def exit_initialization_mode(self):
        self._require_mode("initialization")
        self._ensure_state()
        self._mode = "step"
        self._next_time = self._start_time

    @_guarded(False)
    def do_step(self, current_time, step_size):
        self._require_mode("step")
        if not (math.isfinite(step_size) and step_size > 0.0):
            raise _CallRejected(f"step size must be positive and finite, got {step_size!r}")
        if not continuous(current_time, self._next_time):
            raise _CallRejected(
                f"time discontinuity: the last step ended at "
                f"t={self._next_time!r}, doStep starts at t={current_time!r}"
            )
        stop, end = float(self._fast.block[B_STOP]), current_time + step_size
        if not (end <= stop or continuous(end, stop)):
            raise _CallRejected(
                f"the step to t={end!r} ends after the stop time {stop!r} of "
                "fmi2SetupExperiment (FMI 2.0 section 4.2.1: no step past a defined stop time)"
            )
        if self._stop_time is not None:  # the first step: the run's length decides the tier
            steps, self._stop_time = (self._stop_time - current_time) / step_size, None
            if not self._fast.entries.native:  # the FMU's library steps it, compiled
                jit.expect(sys.modules[type(self.model).__module__], steps)
        self.model.step(current_time, step_size)
        self.model.inputs_to_step_end(step_size)
        self._flush_warnings()
        self._next_time = current_time + step_size
        self._outputs_valid = False
        return True

    @_guarded(None)
    def terminate(self):
        self._require_mode("step")
        self._mode = "terminated"

    # -- getters and setters -------------------------------------------------------
    @_guarded(_zeros)
    def get_real(self, vrs):
        if vrs and vrs[0] in _HANDSHAKE:
            if len(vrs) != FAST_PATH_N:
                raise _CallRejected(f"the handshake takes {FAST_PATH_N} values, not {len(vrs)}")
            return self._fast.handshake()
        if vrs and vrs[0] >= DERIVATIVE_BASE:
            return self.get_real_output_derivatives(vrs)
        return self._read(vrs, "Real").tolist()

    @_guarded(_zeros)
    def get_integer(self, vrs):
        values = self._read(vrs, "Integer")
        fits = (values == np.trunc(values)) & (values >= _INT32[0]) & (values <= _INT32[1])
        if not fits.all():
            self._unfit(vrs, values, fits, "Integer", "whole numbers of fmi2Integer's range")
        return [int(x) for x in values]

    @_guarded(_zeros)
    def get_boolean(self, vrs):
        values = self._read(vrs, "Boolean")
        fits = (values == 0.0) | (values == 1.0)
        if not fits.all():
            self._unfit(vrs, values, fits, "Boolean", "0 (false) or 1 (true)")
        return [bool(x) for x in values]

    def _unfit(self, vrs, values, fits, type_name: str, expected: str):
        """The values a model left in Integer or Boolean variables that their FMI type
        cannot hold (an output of a model of a user): refused, never wrapped or rounded."""
        bad = [
            f"{self._scalar_names[vr]}={x!r}"
            for vr, x, ok in zip(vrs, values.tolist(), fits.tolist())
            if not ok
        ]
        raise _CallRejected(
            f"the model produced {type_name} values {', '.join(bad)} at t={self.model.t!r}: "
            f"{type_name} variables hold {expected}"
        )

    @_guarded(lambda vrs: [""] * len(vrs))
    def get_string(self, vrs):
        if len(vrs) == 1 and vrs[0] in _HANDSHAKE:  # the shim asks for the binary's GUID
            digest = _PACKAGE.partition("_")[2]  # "" outside an FMU: nothing to compare
            guid = fmu_guid(type(self).__name__, digest, self._configuration_key)
            return ["{" + guid + "}" if digest else ""]  # as modelDescription.xml has it
        self._require_readable()
        self._plan(vrs, "String")
        return [self.model.strings[self._scalar_names[vr]] for vr in vrs]

    @_guarded(None)
    def set_real(self, vrs, values):
        if vrs and vrs[0] >= DERIVATIVE_BASE:
            return self.set_real_input_derivatives(vrs, values)
        self._write(vrs, values, "Real")

    # -- input and output derivatives (see the module docstring) ---------------------
    @_guarded(_zeros)
    def get_real_output_derivatives(self, codes):
        if self._mode not in ("step", "terminated"):
            raise _CallRejected(
                f"not allowed in mode '{self._mode}' (only after "
                "fmi2ExitInitializationMode: FMI 2.0 section 4.2.4)"
            )
        vrs = self._derivative_plan(codes, OUTPUT)
        declared = [self._derivative.get(vr) for vr in vrs]
        if None not in declared:  # hdot of h: the output itself
            return self._read(declared, "Real").tolist()
        self._read(vrs, "Real")  # the outputs of the current state and inputs
        rates = self.model.output_derivatives()[[vr - self._outputs.start for vr in vrs]]
        if not np.all(np.isfinite(rates)):
            bad = [self._scalar_names[vr] for vr, x in zip(vrs, rates) if not math.isfinite(x)]
            raise _CallRejected(f"the model produced non-finite derivatives of {bad}")
        return rates.tolist()

    @_guarded(None)
    def set_real_input_derivatives(self, codes, values):
        vrs = self._derivative_plan(codes, INPUT)
        if self._mode == "terminated":
            raise _CallRejected("variables cannot be set after fmi2Terminate")
        if not all(map(math.isfinite, values)):
            bad = [
                f"{self._scalar_names[vr]}={x!r}"
                for vr, x in zip(vrs, values)
                if not math.isfinite(x)
            ]
            raise _CallRejected(f"non-finite derivatives rejected: {bad}")
        at = [self._block + vr for vr in vrs]
        self.model.values[at] = values
        self.model.values[[k + self._n_inputs for k in at]] = 1.0

    def _derivative_plan(self, codes, causality: int) -> list:
        """The value references the (order, vr) codes ask the derivatives of; cached."""
        key = ("derivative", causality, tuple(codes))
        plan = self._plans.get(key)
        if plan is None:
            plan = self._make_derivative_plan(codes, causality)
            if len(self._plans) < _PLAN_CACHE_SIZE:
                self._plans[key] = plan
        if isinstance(plan, str):
            raise _CallRejected(plan)
        return plan

    def _make_derivative_plan(self, codes, causality: int):
        model, n = self.model_class, len(self._scalar_names)
        kind = ("input", "output")[causality - INPUT]
        if causality == INPUT and not model.INTERPOLATES_INPUTS:
            return "this FMU does not interpolate its inputs (canInterpolateInputs is false)"
        if causality == OUTPUT and not model.OUTPUT_DERIVATIVES:
            return "this FMU has no output derivatives (maxOutputDerivativeOrder is 0)"
        vrs = []
        for code in codes:
            order, vr = (code - DERIVATIVE_BASE) >> ORDER_SHIFT, code & ((1 << ORDER_SHIFT) - 1)
            if not 0 <= vr < n:
                return f"unknown value reference {vr} (this FMU has 0..{n - 1})"
            name = self._scalar_names[vr]
            if self._causality[vr] != causality or self._type[vr] != _TYPE_CODE["Real"]:
                return f"{name} is not a continuous Real {kind}"
            if order != 1:
                why = (
                    "maxOutputDerivativeOrder is 1"
                    if causality == OUTPUT
                    else "this FMU interpolates its inputs linearly, u(t) = u + du/dt (t - t_c)"
                )
                return f"order {order} of {name}: only order 1, the first derivative ({why})"
            vrs.append(vr)
        return vrs

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
    # A state is the bytes of fmu_state's data-only format: taken by _get_fmu_state,
    # checked and applied by _set_fmu_state.  pythonfmu calls the two byte converters on
    # the class and turns any exception into fmi2Fatal (and a broken instance), so they
    # never raise: a rejected state is a _Rejected, which serializes to a NUL byte and the
    # reason; the shim refuses such a state with fmi2Error and that reason.
    @_guarded(None)
    def _get_fmu_state(self):
        wrapper = (
            self._mode,
            self._start_time,
            self._next_time,
            self._state_valid,
            self._outputs_valid,
        )
        return fmu_state.encode(self._identity(), (self.model.get_state(), wrapper), _PACKAGE)

    @_guarded(None)
    def _set_fmu_state(self, state):
        if type(state) is not bytes:
            raise _CallRejected(_rejection(state))
        model_state, wrapper = self._check_state(
            fmu_state.decode(self._identity(), state, _PACKAGE)
        )
        self.model.set_state(model_state)
        (self._mode, self._start_time, self._next_time, self._state_valid, self._outputs_valid) = (
            wrapper
        )

    @classmethod
    def _identity(cls) -> str:
        return f"{_PACKAGE}.{cls.__name__}"

    @classmethod
    def _check_state(cls, value):
        """The structure a state of this FMU has (everything not depending on an instance)."""
        model = cls.model_class
        layout = model._layouts.get(model)  # set once a model was created
        size = layout.n_values if layout else None
        names = {v.name for v in layout.variables if v.type == "String"} if layout else None
        try:
            (values, strings, attributes), wrapper = value
            mode, start, next_time, state_valid, outputs_valid = wrapper
        except (TypeError, ValueError):
            raise fmu_state.StateError("not a (model state, wrapper state) pair") from None
        if not (
            type(values) is np.ndarray
            and values.dtype == np.float64
            and values.ndim == 1
            and (size is None or values.size == size)
        ):
            raise fmu_state.StateError(f"the value array must be float64 of {size} values")
        if not (
            type(strings) is dict
            and all(type(k) is str and type(v) is str for k, v in strings.items())
            and (names is None or set(strings) == names)
        ):
            raise fmu_state.StateError(
                f"the string values must map {sorted(names or [])} to strings"
            )
        if not (
            type(attributes) is dict
            and all(
                type(k) is str and k.isidentifier() and k not in model._NOT_STATE
                for k in attributes
            )
        ):
            raise fmu_state.StateError("the model attributes must be a dict of names")
        if not (
            mode in _MODES
            and type(start) is float
            and (next_time is None or type(next_time) is float)
            and type(state_valid) is bool
            and type(outputs_valid) is bool
        ):
            raise fmu_state.StateError("malformed FMI wrapper state")
        state_layout.check(model, value[0], state_valid, outputs_valid)
        return value

    @classmethod
    def _fmu_state_to_bytes(cls, state) -> bytes:
        return state if type(state) is bytes else b"\0" + _rejection(state).encode()

    @classmethod
    def _fmu_state_from_bytes(cls, data: bytes):
        try:
            cls._check_state(fmu_state.decode(cls._identity(), data, _PACKAGE))
            return bytes(data)
        except fmu_state.StateError as exc:
            return _Rejected(str(exc))
        except Exception as exc:  # noqa: BLE001 - never raise into pythonfmu
            return _Rejected(f"{type(exc).__name__}: {exc}")

    # -- internals -----------------------------------------------------------------
    _WHEN = {
        "instantiated": "after fmi2Instantiate",
        "initialization": "in initialization mode",
        "step": "after fmi2ExitInitializationMode",
    }

    def _require_mode(self, mode: str):
        """FMI 2.0 co-simulation state machine (section 4.2.4)."""
        if self._mode != mode:
            raise _CallRejected(f"not allowed in mode '{self._mode}' (only {self._WHEN[mode]})")

    def _error(self, message: str) -> None:
        self.log(f"{self.model_class.__name__} '{self.instance_name}': {message}", Fmi2Status.error)

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
        if setting and self._mode == "terminated":
            raise _CallRejected("variables cannot be set after fmi2Terminate")
        if setting and touches_parameters and self._mode == "step":
            names = [self._scalar_names[vr] for vr in vrs if self._causality[vr] == PARAMETER]
            raise _CallRejected(
                f"parameters {names} are fixed: they can only be set before exitInitializationMode"
            )
        return index

    def _make_plan(self, vrs, type_name, setting):
        n = len(self._scalar_names)
        unknown = [vr for vr in vrs if not 0 <= vr < n]
        if unknown:
            return f"unknown value references {unknown} (this FMU has 0..{n - 1})"
        index = _frozen(vrs, dtype=np.intp)  # kept for every instance of the class
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

    def _require_readable(self):
        """FMI 2.0 section 4.2.4: no fmi2Get* before initialisation mode."""
        if self._mode == "instantiated":
            raise _CallRejected(
                "not allowed in mode 'instantiated' (only from fmi2EnterInitializationMode "
                "on: FMI 2.0 section 4.2.4)"
            )

    def _read(self, vrs, type_name):
        self._require_readable()
        index = self._plan(vrs, type_name)
        values = self.model.values
        if not self._outputs_valid:
            self._ensure_state()
            self.model.output()
            outputs = values[self._outputs].tolist()
            if not math.isfinite(sum(outputs)) and not all(map(math.isfinite, outputs)):
                bad = [
                    name
                    for name, x in zip(self._scalar_names[self._outputs], outputs)
                    if not math.isfinite(x)
                ]
                raise _CallRejected(
                    f"the model produced non-finite outputs {bad} at t={self.model.t!r}"
                )
            self._outputs_valid = True
        return values[index]

    def _write(self, vrs, values, type_name):
        index = self._plan(vrs, type_name, setting=True)
        if not math.isfinite(sum(values)) and not all(map(math.isfinite, values)):
            bad = [
                f"{self._scalar_names[vr]}={x!r}"
                for vr, x in zip(vrs, values)
                if not math.isfinite(x)
            ]
            raise _CallRejected(f"non-finite values rejected: {bad}")
        if self._mode in ("instantiated", "initialization"):
            if self._state_valid and _same(self.model.values[index], values):
                return  # the values it holds: the state and outputs made of them stand
            self.model.values[index] = values
            self._state_valid = False
            self._outputs_valid = False
            return
        self.model.values[index] = values
        if self._feeds[index].any():  # else the outputs stay what they are
            self._outputs_valid = False

    def _ensure_state(self):
        if not self._state_valid:
            self.model.initialize(self._start_time)
            self._flush_warnings()
            self._state_valid = True

    def _flush_warnings(self):
        """The model's warnings, at category logStatusWarning; with the parameter
        warnings_return_ok at status fmi2OK, which the shim forwards to the host as a
        warning message (even with debug logging off) without raising the call's status."""
        if self.model.warnings:
            self._warn(self.model.warnings)
            self.model.warnings.clear()

    def _warn(self, messages) -> None:
        status = Fmi2Status.ok if self.model.p.warnings_return_ok else Fmi2Status.warning
        for message in messages:
            self.log(
                f"{self.model_class.__name__} '{self.instance_name}': {message}",
                status,
                "logStatusWarning",
            )
