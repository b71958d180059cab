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
wrong mode (FMI 2.0 section 4.2.4: setup and entering initialisation only after
instantiation, setting nothing after terminate, ...), and exceptions or non-finite outputs
from the model.  FMU states are data (``fmu_state``), never pickles.

Input and output derivatives (FMI 2.0 section 4.2.1).  pythonfmu 0.7 answers
``fmi2SetRealInputDerivatives`` and ``fmi2GetRealOutputDerivatives`` "not supported"; the
shim passes them on as ``fmi2SetReal``/``fmi2GetReal`` of the value references
``DERIVATIVE_BASE + (order << ORDER_SHIFT) + vr`` (a range no variable has).  A table row
with ``derivative_of`` makes the pair: the first derivative of input ``h_cmg`` *is* the
input ``hdot_cmg`` (setting one sets the other; the last call before ``fmi2DoStep`` wins,
and it stays until set again, like any input: FMI 2.0 puts the same restrictions on it as
on ``fmi2SetReal``); never set, it is the start value, zero: the input held over the
step.  The output derivative of ``h`` is the output ``hdot``, at the current time.  Refused
with fmi2Error: a variable without a declared derivative, an order other than 1, a
non-finite derivative, setting after ``fmi2Terminate``, getting before
``fmi2ExitInitializationMode`` (FMI 2.0 section 4.2.4's state table).

The shim's fast path (``shim/agilesat_fmi2.c``, "fast get/set").  After instantiation
(and after ``fmi2Reset``, which makes pythonfmu create a new slave) the shim asks for the
value reference ``FAST_PATH_VR`` and gets the addresses of three arrays this slave owns
for its whole life: the model's value array ``model.values`` (never replaced: state
restore, reset and initialisation copy into it), ``_kind`` (per scalar: ``KIND_*``) and
``_control`` (``STEP_MODE``: the mode is "step"; ``OUTPUTS_VALID``: ``model.output()``
has been evaluated for the current state and inputs; ``PREDICTED``, ``FED``: see below).  With
``STEP_MODE`` and ``OUTPUTS_VALID`` set the shim answers a ``fmi2GetReal`` of Real scalars
itself (and clears ``PREDICTED``); in step mode it writes a ``fmi2SetReal`` of finite
values to Real inputs itself, clearing ``OUTPUTS_VALID`` and setting ``FED`` when one of
them feeds an output through (``KIND_FEEDTHROUGH``: an input some output's ``depends``
lists, the dependencies of modelDescription.xml), unless ``PREDICTED`` is set.  Every
other call comes here as before.  A set of inputs no output depends on keeps the outputs
valid (they would not change).

Predicted outputs, so that a macro step enters Python once (``fmi2DoStep``).  Without the
shim, ``model.output()`` runs at the first get after a step or a feedthrough set.
``do_step`` runs it at its end instead, *predicting* that the next call is a get; a model
that raises or gives non-finite outputs leaves them invalid (the next get comes here and
reports it as it always did).  The prediction is right when a get comes first
(``PREDICTED`` cleared: the outputs are those a get computes).  Otherwise (a feedthrough
set, the next ``do_step``, an FMU state taken) it is undone first (``_unpredict``): the
model's attributes, its outputs and warnings are put back as they were before the
prediction, so ``output()`` runs later exactly as without the shim, and the results stay
the same bit for bit even for models whose ``output()`` remembers its last result (the
sign of a quaternion, an Euler angle branch).  The undo restores the attribute
references and the contents of the model's arrays (a kernel's state array), so
``output()`` must assign any other memory, not modify it in place
(tests/test_shim_fast.py checks every model).  An instance predicts only while that pays:
after an undone prediction it stops, until a get comes first after a step again (``FED``
cleared by ``do_step``, set by a feedthrough set).

The C step path (``shim/agilesat_fmi2.c``, "the C step path").  Once a model's kernels run
compiled (components/jit.py), the shim also takes ``fmi2DoStep`` and the evaluation of the
outputs (the prediction at the step's end, a get with the outputs invalid, the undo on a
feedthrough set), calling the model's C entries (``model.c_entries()``: the compiled
step and output as C functions, or None where the next call needs the Python: the first
step of SatelliteDynamics, a saturated cluster, a singular steering, SGP4, CPython's
``math.hypot``).  The slave hands them over in ``_block`` (B_*: addresses of the entries,
of the model's state array and of the snapshot buffer ``_saved``; the model's ``t`` and
the step's end) with ``_control`` (C_STEP, C_OUTPUT) at the end of every call it answers
(``_arm``, in ``_guarded``): the state array and the buffer may be replaced by a call here
(initialisation, state restore), never between two.  The shim serves a step only when
``do_step`` would accept it, with nothing to report; it does what ``do_step`` and
``_predict_outputs`` do, flags ``C_DIRTY``, and forwards anything else (after putting the
arrays back) so that this class gives its status and message.  At the start of the next
call here (``_guarded`` is the one door) ``_sync`` takes over what the shim did: ``model.t``,
``_next_time`` and a prediction the shim made (``C_PREDICTED``; its snapshot in ``_saved``
becomes ``_prediction``), so that every call here sees the slave exactly as if every call
had come here: FMU states, errors, terminate, reset.  ``_predicting`` lives in
``_control`` (PREDICTING) for the same reason.
"""

from __future__ import annotations

import functools
import math
import os
import traceback

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.enums import Fmi2Status

from ..components import jit
from ..components.model import ModelError
from . import fmu_state

PARAMETER, INPUT, OUTPUT = 0, 1, 2
_CAUSALITY_CODE = {"parameter": PARAMETER, "input": INPUT, "output": OUTPUT}
_TYPE_CODE = {"Real": 0, "Integer": 1, "Boolean": 2, "String": 3}
_PLAN_CACHE_SIZE = 64
_PACKAGE = __name__.split(".")[0]  # agilesat_<hash> inside an FMU
_MODES = ("instantiated", "initialization", "step", "terminated")
#: value references of the derivative calls the shim forwards (shim/agilesat_fmi2.c)
DERIVATIVE_BASE, ORDER_SHIFT = 1 << 30, 24
#: the shim's fast-path handshake: a get_real of FAST_PATH_N copies of the value reference
#: 0xFFFFFFFF (pythonfmu 0.7.0 passes value references as C ints: -1) gives
#: (FAST_PATH_VERSION, values address, number of values, _kind address, _control address,
#: _block address); the shim checks the version (shim/agilesat_fmi2.c)
FAST_PATH_VR, FAST_PATH_N, FAST_PATH_VERSION = (-1, 0xFFFFFFFF), 6, 2.0
#: per scalar, for the shim: a String, Real parameter, output, input, feedthrough input,
#: an Integer, a Boolean
KIND_OTHER, KIND_PARAMETER, KIND_OUTPUT, KIND_INPUT, KIND_FEEDTHROUGH = 0, 1, 2, 3, 4
KIND_INTEGER, KIND_BOOLEAN = 5, 6
#: indices in the control block shared with the shim (int32)
STEP_MODE, OUTPUTS_VALID, PREDICTED, FED, PREDICTING = 0, 1, 2, 3, 4
C_STEP, C_OUTPUT, C_PREDICTED, C_DIRTY = 5, 6, 7, 8
N_CONTROL = 9
#: C_STEP: the next step is the Python's, the step entry's, or changes nothing but t
PYTHON_STEP, ENTRY_STEP, TIME_STEP = 0, 1, 2
#: indices in the C step block shared with the shim (float64; addresses as exact doubles)
B_TIME, B_NEXT_TIME, B_STEP, B_OUTPUT, B_STATE, B_N_STATE, B_SAVED, B_N_SAVED = range(8)
B_OUTPUTS_START, B_OUTPUTS_STOP = 8, 9
N_BLOCK = 10


def _guarded(default):
    """Run an FMI entry point; turn any exception into a logged fmi2Error."""

    def decorate(method):
        @functools.wraps(method)
        def wrapper(self, *args):
            if self._control[C_DIRTY]:  # the shim served calls in C since the last entry
                self._sync()
            try:
                return method(self, *args)
            except (_CallRejected, ModelError) as rejected:
                self._error(f"{method.__name__}: {rejected}")
            except Exception as exc:  # noqa: BLE001 - the FMI boundary
                self._error(
                    f"{method.__name__}: {type(exc).__name__}: {exc}\n"
                    f"{traceback.format_exc(limit=4)}"
                )
            finally:
                if self._c_path:
                    self._arm_or_disarm()
            return default(*args) if callable(default) else default

        return wrapper

    return decorate


def _address(array: np.ndarray) -> int:
    return array.__array_interface__["data"][0]


def _same_arrays(model, attributes: dict) -> None:
    """A state's arrays must have the shape and dtype of the model's own (the compiled
    kernels index them without bounds checks): else _CallRejected."""
    for name, value in attributes.items():
        mine = vars(model).get(name)
        if type(mine) is np.ndarray and not (
            type(value) is np.ndarray and value.dtype == mine.dtype and value.shape == mine.shape
        ):
            raise _CallRejected(
                f"the state's {name} is not a {mine.dtype} array of shape {mine.shape}"
            )


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
        #: vr of a scalar with a declared derivative -> vr of its derivative
        self._derivative = {
            layout.offset[v.derivative_of] + k: layout.offset[v.name] + k
            for v in layout.variables
            if v.derivative_of
            for k in range(v.size)
        }
        #: inputs some output depends on directly (its table row's ``depends``)
        feeds = {
            vr
            for v in layout.variables
            for name in v.depends
            for vr in range(layout.offset[name], layout.offset[name] + layout.by_name[name].size)
        }
        self._feeds = np.array([vr in feeds for vr in range(len(layout.scalars))], dtype=bool)
        kind = np.where(
            self._causality == INPUT,
            np.where(self._feeds, KIND_FEEDTHROUGH, KIND_INPUT),
            np.where(self._causality == OUTPUT, KIND_OUTPUT, KIND_PARAMETER),
        )
        kind = np.where(self._type == _TYPE_CODE["Real"], kind, KIND_OTHER)
        kind[self._type == _TYPE_CODE["Integer"]] = KIND_INTEGER
        kind[self._type == _TYPE_CODE["Boolean"]] = KIND_BOOLEAN
        self._kind = kind.astype(np.uint8)
        self._control = np.zeros(N_CONTROL, dtype=np.int32)  # shared with the shim: never replaced
        self._block = np.zeros(N_BLOCK)  # the C step path's, shared with the shim: never replaced
        self._saved = np.zeros(0)  # the C path's snapshot (its address is in _block)
        self._c_path = False  # the shim asked for the addresses, the model has C entries
        self._armed, self._armed_state = 0, None  # C_STEP or C_OUTPUT set; the state checked
        self._prediction = None
        self._predicting = True  # see _predict_outputs
        self._arrays: list | None = None  # the model's array attributes but values, found once
        self._values = self.model.values  # the array the shim reads and writes
        self._plans: dict = {}
        self._mode = "instantiated"
        self._start_time = 0.0
        self._next_time: float | None = None
        self._state_valid = False
        self._outputs_valid = False

    # -- the flags the shim reads (see the module docstring) ------------------------
    @property
    def _mode(self) -> str:
        return self._mode_name

    @_mode.setter
    def _mode(self, mode: str) -> None:
        self._mode_name = mode
        self._control[STEP_MODE] = mode == "step" and self.model.values is self._values

    @property
    def _predicting(self) -> bool:
        return bool(self._control[PREDICTING])

    @_predicting.setter
    def _predicting(self, predicting: bool) -> None:
        self._control[PREDICTING] = predicting

    @property
    def _outputs_valid(self) -> bool:
        return bool(self._control[OUTPUTS_VALID])

    @_outputs_valid.setter
    def _outputs_valid(self, valid: bool) -> None:
        self._control[OUTPUTS_VALID] = valid

    def _fast_path_addresses(self, n: int) -> list:
        if n != FAST_PATH_N:
            raise _CallRejected(f"the fast-path handshake takes {FAST_PATH_N} values, not {n}")
        address = [_address(a) for a in (self._values, self._kind, self._control, self._block)]
        n_values = min(self._values.size, self._kind.size)  # the shim reads both up to it
        # the shim reads the same switch at the same moment (handshake)
        self._c_path = (
            hasattr(self.model, "c_entries") and os.environ.get("AGILESAT_SHIM_STEP") != "0"
        )
        return [FAST_PATH_VERSION, address[0], n_values, *address[1:]]

    def _arm(self) -> None:
        """End of every call the slave answers: tell the shim what its C step path may do
        until the next one (module docstring, "The C step path"): the model's C entries
        usable now (``c_entries``: compiled kernels, nothing for the Python to do), the
        addresses of the model's state array and of the snapshot buffer (both may have been
        replaced: initialisation, FMU state restore), the times."""
        control, block, model = self._control, self._block, self.model
        state = getattr(model, "state", None)
        if state is not self._armed_state:  # checked once per array
            plain = type(state) is np.ndarray and state.dtype == np.float64
            self._armed_state = state if plain and state.flags.c_contiguous else None
        step = output = None
        ready = self._mode_name == "step" and self._state_valid and self._armed_state is not None
        if ready and not model.warnings:  # warnings waiting: the next doStep reports them
            step, output = model.c_entries()
        kind = PYTHON_STEP
        if type(step) is jit.TimeStep:
            kind = TIME_STEP if step.ready else PYTHON_STEP
        elif step is not None and (address := step.address):
            kind, block[B_STEP] = ENTRY_STEP, address
        address = output.address if output is not None else None
        if not (kind or address):
            if self._armed:
                control[C_STEP] = control[C_OUTPUT] = self._armed = 0
            return
        control[C_OUTPUT], block[B_OUTPUT] = (1, address) if address else (0, 0.0)
        control[C_STEP], self._armed = kind, 1
        need = self._values.size + state.size
        if self._saved.size < need:
            self._saved = np.zeros(need)
        block[B_TIME], block[B_NEXT_TIME] = model.t, self._next_time
        block[B_STATE], block[B_N_STATE] = _address(state), state.size
        block[B_SAVED], block[B_N_SAVED] = _address(self._saved), self._saved.size
        block[B_OUTPUTS_START], block[B_OUTPUTS_STOP] = self._outputs.start, self._outputs.stop

    def _arm_or_disarm(self) -> None:
        try:
            self._arm()
        except Exception as exc:  # noqa: BLE001 - never into pythonfmu (fmi2Fatal)
            # the call itself succeeded: the Python steps from now on, and says so once
            self._control[C_STEP] = self._control[C_OUTPUT] = self._armed = 0
            self._c_path = False
            self._warn([f"the C step path is off ({type(exc).__name__}: {exc}); the Python steps"])

    def _sync(self) -> None:
        """Start of a call after calls the shim served in C: take over what they did (the
        model's time, the step's end; a prediction the shim made becomes the slave's, with
        the shim's snapshot), so that everything goes on as if they had come here."""
        control, block, model = self._control, self._block, self.model
        control[C_DIRTY] = 0
        model.t = float(block[B_TIME])
        self._next_time = float(block[B_NEXT_TIME])
        if control[C_PREDICTED]:
            control[C_PREDICTED] = 0
            n, saved = self._values.size, self._saved
            arrays = {"state": saved[n : n + model.state.size].copy()}
            outputs = saved[self._outputs].copy()
            self._prediction = (dict(vars(model)), arrays, outputs, len(model.warnings))

    def _predict_outputs(self) -> None:
        """End of a step: evaluate the outputs, so that the shim answers the gets (see
        the module docstring).  A model that raises or produces non-finite outputs is
        put back and leaves them invalid: the next get evaluates them again and reports
        it (``_read``).  Only while predictions pay: one undone (a feedthrough set came
        first, as in a Jacobi master's feedthrough pass, or no get at all) stops them
        until a get comes first after a step again (``FED``: no feedthrough set since the
        step); either way the results are the same."""
        self._control[FED] = 0
        if not self._predicting:
            return
        model = self.model
        before = self._values[self._outputs].copy()
        attributes = vars(model)
        if self._arrays is None:  # the kernels' state arrays, which output() updates in place
            self._arrays = [
                k for k, v in attributes.items() if type(v) is np.ndarray and v is not self._values
            ]
        arrays = {k: attributes[k].copy() for k in self._arrays if k in attributes}
        self._prediction = (dict(attributes), arrays, before, len(model.warnings))
        try:
            model.output()
        except Exception:  # noqa: BLE001 - reported by the get that needs them
            self._unpredict()
            return
        if not math.isfinite(self._values[self._outputs].sum()):
            self._unpredict()
            return
        self._control[OUTPUTS_VALID] = self._control[PREDICTED] = 1

    def _unpredict(self) -> None:
        """Undo the prediction of ``_predict_outputs`` (no get came first)."""
        attributes, arrays, outputs, n_warnings = self._prediction
        self._prediction = None
        model = self.model
        vars(model).clear()
        vars(model).update(attributes)
        for name, saved in arrays.items():
            attributes[name][...] = saved
        self._values[self._outputs] = outputs
        del model.warnings[n_warnings:]
        self._control[OUTPUTS_VALID] = self._control[PREDICTED] = 0

    def _consume_prediction(self, wrong: bool = True) -> None:
        """A call that changes what a get would compute: a prediction no get used is undone
        (and, ``wrong``, no longer made: see ``_predict_outputs``)."""
        if self._control[PREDICTED]:
            self._unpredict()
            self._predicting = self._predicting and not wrong

    # -- FMI life cycle ------------------------------------------------------------
    @_guarded(None)
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._require_mode("instantiated")
        self._start_time = float(start_time)

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
        self._consume_prediction()
        if not (math.isfinite(step_size) and step_size > 0.0):
            raise _CallRejected(f"step size must be positive and finite, got {step_size!r}")
        if not math.isclose(current_time, self._next_time, rel_tol=1e-9, abs_tol=1e-12):
            raise _CallRejected(
                f"time discontinuity: the last step ended at "
                f"t={self._next_time!r}, doStep starts at t={current_time!r}"
            )
        self.model.step(current_time, step_size)
        self._flush_warnings()
        self._next_time = current_time + step_size
        self._outputs_valid = False
        if self.model.values is not self._values:  # the shim would see another array
            self._control[STEP_MODE] = 0
        self._predict_outputs()
        return True

    @_guarded(None)
    def terminate(self):
        self._require_mode("step")
        self._mode = "terminated"

    # -- getters and setters -------------------------------------------------------
    @_guarded(_zeros)
    def get_real(self, vrs):
        if vrs and vrs[0] in FAST_PATH_VR:
            return self._fast_path_addresses(len(vrs))
        if vrs and vrs[0] >= DERIVATIVE_BASE:
            return self.get_real_output_derivatives(vrs)
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
        if vrs and vrs[0] >= DERIVATIVE_BASE:
            return self.set_real_input_derivatives(vrs, values)
        self._write(vrs, values, "Real")

    # -- input and output derivatives (see the module docstring) ---------------------
    @_guarded(_zeros)
    def get_real_output_derivatives(self, vrs):
        if self._mode not in ("step", "terminated"):
            raise _CallRejected(
                f"not allowed in mode '{self._mode}' (only after "
                "fmi2ExitInitializationMode: FMI 2.0 section 4.2.4)"
            )
        return self._read(self._derivative_vrs(vrs, OUTPUT), "Real").tolist()

    @_guarded(None)
    def set_real_input_derivatives(self, vrs, values):
        targets = self._derivative_vrs(vrs, INPUT)
        if not all(map(math.isfinite, values)):
            bad = [
                f"{self._scalar_names[vr]}={x!r}"
                for vr, x in zip(self._decoded(vrs), values)
                if not math.isfinite(x)
            ]
            raise _CallRejected(f"non-finite derivatives rejected: {bad}")
        self._write(targets, values, "Real")

    @staticmethod
    def _decoded(vrs):
        return [(vr - DERIVATIVE_BASE) & ((1 << ORDER_SHIFT) - 1) for vr in vrs]

    def _derivative_vrs(self, vrs, causality: int) -> list:
        """The value references of the derivatives the (order, vr) codes ask for."""
        key = ("derivative", causality, tuple(vrs))
        plan = self._plans.get(key)
        if plan is None:
            plan = self._make_derivative_plan(vrs, causality)
            if len(self._plans) < _PLAN_CACHE_SIZE:
                self._plans[key] = plan
        if isinstance(plan, str):
            raise _CallRejected(plan)
        return plan

    def _make_derivative_plan(self, vrs, causality: int):
        n, kind = len(self._scalar_names), ("input", "output")[causality - INPUT]
        declared = [
            self._scalar_names[vr] for vr in self._derivative if self._causality[vr] == causality
        ]
        targets = []
        for code, vr in zip(vrs, self._decoded(vrs)):
            order = (code - DERIVATIVE_BASE) >> ORDER_SHIFT
            if not 0 <= vr < n:
                return f"unknown value reference {vr} (this FMU has 0..{n - 1})"
            name = self._scalar_names[vr]
            if vr not in self._derivative or self._causality[vr] != causality:
                return (
                    f"{name} is not a Real continuous {kind} with a declared derivative "
                    f"(those of this FMU: {declared or 'none'})"
                )
            if order != 1:
                why = "maxOutputDerivativeOrder is 1" if kind == "output" else "linear inputs"
                return f"order {order} of {name}: only order 1, the first derivative ({why})"
            targets.append(self._derivative[vr])
        return targets

    @_guarded(None)
    def set_integer(self, vrs, values):
        self._write(vrs, values, "Integer")

    @_guarded(None)
    def set_boolean(self, vrs, values):
        self._write(vrs, [1.0 if v else 0.0 for v in values], "Boolean")

    @_guarded(None)
    def set_string(self, vrs, values):
        self._plan(vrs, "String", setting=True)
        self._consume_prediction()
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
        self._consume_prediction(wrong=False)  # the state as without the shim
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
        _same_arrays(self.model, model_state[2])
        self.model.set_state(model_state)
        self._prediction = None
        self._control[PREDICTED] = 0
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
        size = layout.n_numeric if layout else None
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
                bad = [
                    name
                    for name, x in zip(self._scalar_names[self._outputs], outputs)
                    if not math.isfinite(x)
                ]
                raise _CallRejected(
                    f"the model produced non-finite outputs {bad} at t={self.model.t!r}"
                )
            self._outputs_valid = True
            if self._mode == "step" and not self._control[FED]:
                self._predicting = True  # a get came first after the step
        self._control[PREDICTED] = 0  # a get came first: the prediction was right
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
        self.model.values[index] = values
        if self._mode in ("instantiated", "initialization"):
            self._state_valid = False
            self._outputs_valid = False
        elif self._feeds[index].any():  # else the outputs stay what they are
            self._consume_prediction()
            self._outputs_valid = False
            self._control[FED] = 1

    def _ensure_state(self):
        if not self._state_valid:
            self.model.initialize(self._start_time)
            self._flush_warnings()
            self._state_valid = True

    def _flush_warnings(self):
        """The model's warnings, at category logStatusWarning; with the parameter
        warnings_return_ok at status fmi2OK, which the shim forwards to the host (even
        with debug logging off) without raising the call's status."""
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
