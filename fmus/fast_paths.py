"""The slave's half of the shim's fast paths (the C half: ``shim/fast_paths.c``; what both
share: ``protocol.py``).  Everything here only saves entries into Python: with it or
without it (AGILESAT_SHIM_FAST=0, AGILESAT_SHIM_STEP=0) a host sees the same values,
statuses, messages and FMU states, bit for bit (tests/fast_paths/test_shim_fast.py,
tests/fast_paths/test_shim_step.py).

Fast get/set.  At instantiation (and after fmi2Reset, which makes pythonfmu create a new
slave) the shim asks for the addresses of the model's value array and of ``kind``,
``control`` and ``block`` (the handshake), which live as long as the slave: the value
array is never replaced (state restore and initialisation copy into it).  The slave keeps
``control`` up to date: STEP_MODE at the end of every call (``leave``) and OUTPUTS_VALID
(the slave's own flag lives there); the step's end lives in ``block``.  In step mode the
shim answers gets of Real, Integer and Boolean scalars itself while the outputs are valid,
and writes sets of finite Real inputs and of Integer and Boolean inputs itself (as the
slave writes them: the integer as a double, a Boolean as 1.0 or 0.0; a feedthrough input
invalidates the outputs).  Every other call reaches the slave.

The C step path.  A model whose kernels follow the kernel convention (components/runtime/jit.py)
has C entries (``c_entries.py``): once its kernels run compiled, the shim also takes
``fmi2DoStep`` and evaluates the outputs at a get, in C.  ``leave`` (at the end of every
call the slave answers) arms it with what it may do until the next call: the step
(C_STEP: the slave's, the step entry's, or only the time for a stateless model) and the
output (C_OUTPUT), with the addresses of the entries, of the model's state array and of
the snapshot buffer ``saved`` (both may be replaced by a call here, never between two).
The shim serves a step only when ``do_step`` would accept it, does what ``do_step`` does
(the inputs brought to the step's end included: ``step_end``, Model.inputs_to_step_end)
and sets C_DIRTY; at the start of the next call here ``sync`` takes over the model's time.
An entry leaving the call to the Python (a warning, an error) makes the shim put the
arrays back from the snapshot and forward the call: the slave gives its status and
message.  The snapshot keeps the value array and the state array but its scratch: a
model may declare ``scratch``, the index of its state array from which on its kernels
rewrite the array before reading it, or read it only while it still is what they would
write there (components/sensing.py, reusing the advanced section).  Whatever a failed
entry leaves there is then what the Python's call would compute from the arrays put back,
and copying it twice per call is saved (an estimator's history: 10 kB).  Left to the
Python: a step while the first step's input check is pending
(``Model.remember_initial_inputs``) and any call while warnings wait to be reported.

Outputs are evaluated when a get asks for them, never ahead of it: evaluating them at a
step's end in anticipation of a get (and undoing that when a feedthrough set came first)
saved nothing measurable (docs/fast_paths.md).
"""

from __future__ import annotations

import math

import numpy as np

from ..components.runtime import jit
from ..components.runtime.switches import value
from . import c_entries
from .protocol import (
    B_N_KEPT,
    B_N_SAVED,
    B_N_STATE,
    B_N_STEP_END,
    B_OUTPUT,
    B_OUTPUTS_START,
    B_OUTPUTS_STOP,
    B_SAVED,
    B_STATE,
    B_STEP,
    B_STEP_END,
    B_STOP,
    B_TIME,
    C_DIRTY,
    C_OUTPUT,
    C_STEP,
    C_STEP_ENTRY,
    C_STEP_PYTHON,
    C_STEP_TIME,
    FAST_PATH_VERSION,
    KIND_BOOLEAN,
    KIND_BOOLEAN_FEEDTHROUGH,
    KIND_BOOLEAN_INPUT,
    KIND_FEEDTHROUGH,
    KIND_INPUT,
    KIND_INTEGER,
    KIND_INTEGER_FEEDTHROUGH,
    KIND_INTEGER_INPUT,
    KIND_OTHER,
    KIND_OUTPUT,
    KIND_PARAMETER,
    N_BLOCK,
    N_CONTROL,
    STEP_MODE,
)


def _address(array: np.ndarray) -> int:
    return array.__array_interface__["data"][0]


#: Integer and Boolean kinds: (not an input, an input, a feedthrough input)
_WHOLE = {
    "Integer": (KIND_INTEGER, KIND_INTEGER_INPUT, KIND_INTEGER_FEEDTHROUGH),
    "Boolean": (KIND_BOOLEAN, KIND_BOOLEAN_INPUT, KIND_BOOLEAN_FEEDTHROUGH),
}


def kind(causality: str, type_name: str, feeds: bool) -> int:
    """``kind`` of a scalar of this causality and type (the table's names); ``feeds``: some
    output depends on it directly."""
    if type_name in _WHOLE:
        other, plain, feeding = _WHOLE[type_name]
        return (feeding if feeds else plain) if causality == "input" else other
    if type_name != "Real":
        return KIND_OTHER
    if causality == "input":
        return KIND_FEEDTHROUGH if feeds else KIND_INPUT
    return KIND_OUTPUT if causality == "output" else KIND_PARAMETER


class FastPaths:
    """What the slave shares with the shim, and what it does for it (module docstring)."""

    def __init__(self, slave, kinds: np.ndarray):
        self.slave = slave
        self.values = slave.model.values  # the array the shim reads and writes
        self.kind = kinds  # per scalar
        self.control = np.zeros(N_CONTROL, dtype=np.int32)  # never replaced
        self.block = np.zeros(N_BLOCK)  # never replaced
        self.block[B_TIME] = math.nan
        self.block[B_STOP] = math.inf
        #: the rows that bring the inputs to a step's end (Model.inputs_to_step_end)
        self.step_end = np.array(slave.model.layout.step_end, dtype=np.float64).reshape(-1, 6)
        self.block[B_STEP_END] = _address(self.step_end) if self.step_end.size else 0.0
        self.block[B_N_STEP_END] = len(self.step_end)
        self.saved = np.zeros(0)  # the C path's snapshot (its address is in block)
        self.entries = c_entries.of(type(slave.model))
        self.c_path = False  # the shim asked for the addresses, the model has C entries
        self.armed = (C_STEP_PYTHON, 0.0, 0.0)  # (C_STEP, step entry, output entry)
        self.armed_state = None  # the model's state array, checked

    def handshake(self) -> list:
        """The addresses the shim asks for (protocol.py, "the handshake")."""
        n_values = min(self.values.size, self.kind.size)  # the shim reads both up to it
        value("AGILESAT_SHIM_FAST")  # checked: the shim reads it (SwitchError: no fast paths)
        # the shim reads the same switch at the same moment
        self.c_path = self.entries.any and value("AGILESAT_SHIM_STEP")
        return [
            FAST_PATH_VERSION,
            _address(self.values),
            n_values,
            *(_address(a) for a in (self.kind, self.control, self.block)),
        ]

    # -- the door: start and end of every call the slave answers ------------------------
    def sync(self) -> None:
        """Take over what the shim did since the slave's last call: the model's time (the
        step's end), so that everything goes on as if every call had come here."""
        self.control[C_DIRTY] = 0
        self.slave.model.t = float(self.block[B_TIME])

    def leave(self) -> None:
        slave = self.slave
        self.control[STEP_MODE] = slave._mode == "step" and slave.model.values is self.values
        if self.c_path and (jit.compiled_tier or self.entries.native):  # before, arming
            # costs what it saves
            try:
                self._arm()
            except Exception as exc:  # noqa: BLE001 - never into pythonfmu (fmi2Fatal)
                # the call itself succeeded: the Python steps from now on, and says so once
                self._set(C_STEP_PYTHON, 0.0, 0.0)
                self.c_path = False
                why = f"{type(exc).__name__}: {exc}"
                slave._warn([f"the C step path is off ({why}); the Python steps"])

    def _arm(self) -> None:
        """Tell the shim what its C step path may do until the next call (module
        docstring): the step and output entries usable now."""
        slave, model = self.slave, self.slave.model
        state = getattr(model, "state", None)
        if state is not self.armed_state:
            self._point_at(state)
        step, step_entry, output = C_STEP_PYTHON, 0.0, 0.0
        if (
            slave._mode == "step"
            and slave._state_valid
            and self.armed_state is not None
            and not model.warnings  # the next doStep reports them
            and model.t == self.block[B_TIME]
        ):
            entries = self.entries
            first = model._initial_inputs is not None  # the first step checks the inputs
            if entries.stateless and not first:
                step = C_STEP_TIME
            elif entries.step is not None and not first and (address := entries.step.address):
                step, step_entry = C_STEP_ENTRY, address
            if entries.output is not None:
                output = entries.output.address or 0.0
        if (step, step_entry, output) != self.armed:
            self._set(step, step_entry, output)

    def _set(self, step: int, step_entry: float, output: float) -> None:
        self.armed = (step, step_entry, output)
        self.control[C_STEP], self.block[B_STEP] = step, step_entry
        self.control[C_OUTPUT], self.block[B_OUTPUT] = output != 0.0, output

    def _point_at(self, state) -> None:
        """The model's state array (once per array: initialisation and state restore
        make new ones) and a snapshot buffer for it and the values, in the block."""
        plain = type(state) is np.ndarray and state.dtype == np.float64
        self.armed_state = state if plain and state.flags.c_contiguous else None
        if self.armed_state is None:
            return
        block, kept = self.block, _kept(self.slave.model, state)
        need = self.values.size + kept
        if self.saved.size < need:
            self.saved = np.zeros(need)
        block[B_STATE], block[B_N_STATE], block[B_N_KEPT] = _address(state), state.size, kept
        block[B_SAVED], block[B_N_SAVED] = _address(self.saved), self.saved.size
        outputs = self.slave._outputs
        block[B_OUTPUTS_START], block[B_OUTPUTS_STOP] = outputs.start, outputs.stop


def _kept(model, state: np.ndarray) -> int:
    """The length of the part of ``state`` a snapshot keeps: all of it, or the part before
    the model's ``scratch`` where it declares one (module docstring)."""
    at = getattr(model, "scratch", None)
    return at if type(at) is int and 0 <= at <= state.size else state.size
