"""Base class of every component model (plain NumPy, no FMI).

A model owns one flat float64 array holding its parameters, inputs and outputs (see
:mod:`.variables`) and three buses over it: ``p`` (parameters), ``u`` (inputs) and ``y``
(outputs).  Subclasses implement three hooks:

``initialize(t0)``
    set the state at ``t0`` from the parameters (and, where the model says so in
    ``INITIAL_STATE_DEPENDS``, from the inputs);
``step(t, dt)``
    advance the state from ``t`` to ``t + dt`` with the inputs in ``u`` (held at their
    values at ``t``, or extrapolated where the model documents it);
``output()``
    write ``y`` from the state at ``self.t`` and the current inputs.

Every model also has the parameter ``warnings_return_ok`` (:data:`COMMON_VARIABLES`,
appended to each table): the FMU logs the model's warnings (limits, saturation,
singularity) at category ``logStatusWarning`` in any case, as warnings; with it set the
call returns ``fmi2OK`` instead of ``fmi2Warning``, for hosts that stop on a warning
(OMSimulator).  Exported packages set it (orchestration/export.py).

A model whose initial state depends on inputs (``INITIAL_STATE_DEPENDS``) calls
:meth:`Model.remember_initial_inputs` at the end of ``initialize`` and
:meth:`Model.check_initial_inputs` at the start of ``step``: an FMI host that sets those
inputs only after initialisation would otherwise start the model from another state,
silently.  At the first step the inputs may have moved by what one step explains (a
Gauss-Seidel host passes the values at the step's end); a larger jump is an error (the
in-process :meth:`Model.start` leaves the inputs to its caller: no check).

Input and output derivatives (FMI 2.0 section 4.2.1).  A model that integrates inputs
across a step says ``INTERPOLATES_INPUTS`` (the FMU declares ``canInterpolateInputs``):
a host may then set the first derivative u̇ of every continuous Real input, and the model
takes u(t) = u + u̇ (t − t_c) over the step where it integrates u (:meth:`Model.input_rate`;
never set, u̇ is zero: u held).  Where a table also has an input that *is* an input's rate
(``hdot_cmg`` of ``h_cmg``), the slope of ``h_cmg`` over the step is the derivative set for
it if one was set, else ``hdot_cmg`` (:meth:`Model.slope`); a non-zero ``hdot_cmg`` that
differs from a set derivative is reported once as a warning (:meth:`Model.slope_conflicts`).
After the step the inputs are those of its end (:meth:`Model.inputs_to_step_end`, which
the FMU calls after every step, in Python and in C): every input whose derivative was set
is moved to u + u̇ h (with ½ ü h² where its rate input's derivative was set too: ``h_cmg``
with that of ``hdot_cmg``), so that outputs read right after ``fmi2DoStep`` are those of
the inputs the step integrated, as FMI 2.0 computes the outputs at t_{c+1} from the inputs
it extrapolated (section 4.1; a host that sets the inputs again first gets the same
outputs).  An input without a derivative set stays as the host set it.
A model that says ``OUTPUT_DERIVATIVES`` (``maxOutputDerivativeOrder="1"``) answers
:meth:`Model.output_derivatives`: the first time derivative of every output at ``self.t``,
along its own trajectory over the coming step with the inputs as it interpolates them
(exact, or zero for an output held between communication points).

The same object runs in-process (tests, references) and inside the FMU wrapper.
"""

from __future__ import annotations

import copy
from types import ModuleType
from typing import TypeVar

import numpy as np

from .runtime.flat import offsets
from .variables import CAUSALITIES, Bus, Layout, Var, parameter

#: parameters of every model, appended to each table
COMMON_VARIABLES = (
    parameter(
        "warnings_return_ok",
        False,
        "1",
        "log limit, saturation and singularity "
        "warnings (category logStatusWarning) but return fmi2OK, not fmi2Warning, for "
        "hosts that stop on a warning",
        type="Boolean",
    ),
)

_M = TypeVar("_M", bound="Model")


class ModelError(RuntimeError):
    """The model cannot continue (bad parameter, non-finite state, ...)."""


class Model:
    VARIABLES: tuple[Var, ...] = ()
    #: inputs that the initial state depends on (beyond the parameters)
    INITIAL_STATE_DEPENDS: tuple[str, ...] = ()
    #: the model interpolates its continuous Real inputs with the derivatives a host sets
    #: (module docstring); the FMU declares canInterpolateInputs
    INTERPOLATES_INPUTS = False
    #: the model answers output_derivatives(); the FMU declares maxOutputDerivativeOrder 1
    OUTPUT_DERIVATIVES = False
    #: the FMU's DefaultExperiment: its natural communication step and a stop time that
    #: shows its behaviour at its defaults (s), what a host runs it with by default
    DEFAULT_STEP = 0.05
    DEFAULT_STOP = 10.0
    _layouts: dict[type, Layout] = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        names = {v.name for v in cls.VARIABLES}
        cls.VARIABLES = cls.VARIABLES + tuple(v for v in COMMON_VARIABLES if v.name not in names)

    @classmethod
    def table_layout(cls) -> Layout:
        """The layout of this model's value array (one per class)."""
        if cls not in Model._layouts:
            Model._layouts[cls] = Layout(cls.VARIABLES, cls.INTERPOLATES_INPUTS)
        return Model._layouts[cls]

    @classmethod
    def names(cls) -> tuple[ModuleType, ModuleType, ModuleType]:
        """(P, U, Y): the offsets of the parameters, inputs and outputs in the value array,
        by the table's names, one namespace each (components/runtime/flat.py): what a
        kernel indexes ``values`` with, ``values[U.tau_cmd + 1]`` for ``tau_cmd[2]``."""
        layout = cls.table_layout()
        p, u, y = (
            offsets(
                f"{cls.__name__} {c}s",
                {v.name: layout.offset[v.name] for v in layout.group(c) if v.type != "String"},
            )
            for c in CAUSALITIES
        )
        return p, u, y

    @classmethod
    def derivative_names(cls) -> tuple[ModuleType, ModuleType]:
        """(DU, GIVEN) of a model that interpolates its inputs: where the value array holds,
        by input name, the derivative a host set and 1.0 where it set one (Layout)."""
        layout = cls.table_layout()
        return (
            offsets(f"{cls.__name__} input derivatives", layout.derivative),
            offsets(f"{cls.__name__} input derivatives given", layout.given),
        )

    def __init__(self, **parameters):
        self.layout = type(self).table_layout()
        self.values = self.layout.start_values()
        self.strings = {v.name: str(v.start) for v in self.layout.variables if v.type == "String"}
        self.p = Bus(self.values, self.layout, "parameter", self.strings)
        self.u = Bus(self.values, self.layout, "input", self.strings)
        self.y = Bus(self.values, self.layout, "output", self.strings)
        self.t = 0.0
        #: messages for the user (saturation, ...); the FMU logs them as fmi2Warning
        self.warnings: list[str] = []
        for name, value in parameters.items():
            self.set(name, value)

    # -- hooks -------------------------------------------------------------------------
    def initialize(self, t0: float) -> None:
        self.t = t0

    def step(self, t: float, dt: float) -> None:
        raise NotImplementedError

    def output(self) -> None:
        raise NotImplementedError

    def output_derivatives(self) -> np.ndarray:
        """d/dt of the outputs (the output group of the value array, in order) at ``self.t``
        after :meth:`output` (module docstring); only a model with OUTPUT_DERIVATIVES."""
        raise NotImplementedError

    # -- input derivatives (module docstring) -----------------------------------------
    def input_rate(self, name: str) -> np.ndarray:
        """The derivative a host set for input ``name`` (zero where none was set)."""
        at = self.layout.derivative[name]
        return self.values[at : at + self.layout.by_name[name].size]

    def set_input_rate(self, name: str, rate) -> None:
        """In-process: the derivative of input ``name`` (whole arrays), as a host sets it
        with fmi2SetRealInputDerivatives."""
        size = self.layout.by_name[name].size
        self.input_rate(name)[:] = np.broadcast_to(np.asarray(rate, dtype=float).reshape(-1), size)
        at = self.layout.given[name]
        self.values[at : at + size] = 1.0

    def inputs_to_step_end(self, dt: float) -> None:
        """The inputs at the end of a step of ``dt`` (module docstring): each whose
        derivative u̇ was set moves to u + u̇ dt; an input with a rate input (``h_cmg``,
        ``hdot_cmg``) where either's derivative was set to u + (s dt + ½ ü dt dt), s its
        slope (:meth:`slope`), ü the rate's derivative.  Rows of ``Layout.step_end``; the
        shim's C step path does the same, operation for operation
        (``fmus/shim/fast_paths.c``, ``inputs_to_step_end``)."""
        rows = self.layout.step_end
        v = self.values
        if not rows or not v[self.layout.n_numeric :].any():
            return  # no derivative set (the derivatives and the given flags are zero)
        for x, d, g, r, c, rg in rows:
            if r >= 0:
                if v[g] != 0.0 or v[rg] != 0.0:
                    slope = v[d] if v[g] != 0.0 else v[r]
                    v[x] = v[x] + (slope * dt + 0.5 * v[c] * dt * dt)
            elif v[g] != 0.0:
                v[x] = v[x] + v[d] * dt

    def _given(self, name: str) -> np.ndarray:
        at = self.layout.given[name]
        return self.values[at : at + self.layout.by_name[name].size] != 0.0

    def slope(self, name: str, rate: str) -> np.ndarray:
        """The slope of input ``name`` over the step: the derivative set for it where one
        was set, else the input ``rate`` (``hdot_cmg`` for ``h_cmg``)."""
        return np.where(
            self._given(name), self.input_rate(name), self.values[self.layout.slice(rate)]
        )

    def slope_conflicts(self, name: str, rate: str) -> list[str]:
        """The scalars of ``rate`` that are non-zero and differ from a derivative set for
        ``name``, as "rate[i] = x, the derivative of name[i] = y" (empty: none)."""
        given, derivative = self._given(name), self.input_rate(name)
        stated = self.values[self.layout.slice(rate)]
        v = self.layout.by_name[rate]
        return [
            f"{scalar} = {x!r}, the derivative of {base} = {d!r}"
            for scalar, base, g, x, d in zip(
                v.scalar_names(),
                self.layout.by_name[name].scalar_names(),
                given,
                stated.tolist(),
                derivative.tolist(),
            )
            if g and x != 0.0 and x != d
        ]

    # -- inputs the initial state was computed from --------------------------------
    _initial_inputs: dict | None = None

    def remember_initial_inputs(self) -> None:
        """End of ``initialize``: keep the INITIAL_STATE_DEPENDS inputs it used."""
        self._initial_inputs = self._initial_state_inputs()

    def check_initial_inputs(self, dt: float) -> None:
        """Start of the first ``step``: ModelError if an INITIAL_STATE_DEPENDS input has
        jumped since ``initialize`` by more than a step of ``dt`` explains
        (:meth:`initial_input_jumps`): the host set it only after initialisation."""
        used = getattr(self, "_initial_inputs", None)
        if used is None:
            return
        self._initial_inputs = None  # only the first step is checked
        jumps = self.initial_input_jumps(used, dt)
        if jumps:
            detail = "; ".join(f"{name}: {text}" for name, text in jumps.items())
            raise ModelError(
                f"at the first step the inputs {list(jumps)} are not those the "
                f"initial state was computed from ({detail}): the host set them "
                "only after initialisation. Set them before "
                "exitInitializationMode (FMI 2.0 allows it in initialisation "
                "mode); the run would start from another state"
            )

    def initial_input_jumps(self, used: dict, dt: float) -> dict:
        """{input: description} of the INITIAL_STATE_DEPENDS inputs that moved since
        ``initialize`` (values ``used``) by more than one step of ``dt`` explains.  This
        default allows no change; models bound the change by their physics."""
        now = self._initial_state_inputs()
        return {
            name: f"{used[name].tolist()} -> {now[name].tolist()}"
            for name in used
            if not np.allclose(now[name], used[name], rtol=1e-9, atol=1e-12)
        }

    def _initial_state_inputs(self) -> dict:
        return {
            name: self.values[self.layout.slice(name)].copy() for name in self.INITIAL_STATE_DEPENDS
        }

    # -- in-process convenience ------------------------------------------------------
    def set(self, name: str, value) -> None:
        """Set a parameter or input by name (whole arrays at once; a named choice by its
        name or number)."""
        v = self.layout.by_name.get(name)
        if v is None:
            raise KeyError(f"{type(self).__name__} has no variable {name!r}")
        if v.causality == "output":
            raise KeyError(f"{type(self).__name__}.{name} is an output")
        if v.type == "String":
            self.strings[name] = str(value)
            return
        if v.choices and isinstance(value, str):  # a number is checked by initialize
            value = v.choice_value(value)
        array = np.asarray(value, dtype=float)
        if array.shape != v.shape and array.size != v.size:
            raise ValueError(
                f"{type(self).__name__}.{name}: expected shape {v.shape}, got {array.shape}"
            )
        self.values[self.layout.slice(name)] = array.reshape(-1)

    def get(self, name: str):
        """Value of any variable by name (outputs as last written by ``output``)."""
        v = self.layout.by_name[name]
        if v.type == "String":
            return self.strings[name]
        data = self.values[self.layout.slice(name)]
        return data.reshape(v.shape).copy() if v.shape else data[0]

    def start(self: _M, t0: float = 0.0) -> _M:
        """Initialize at ``t0`` and evaluate the outputs; returns self.  In-process the
        caller owns the inputs and may change them at will: no first-step check."""
        self.initialize(t0)
        self._initial_inputs = None
        self.output()
        return self

    def advance(self: _M, t: float, dt: float) -> _M:
        """Step from ``t`` to ``t + dt``, bring the inputs to its end
        (:meth:`inputs_to_step_end`) and evaluate the outputs; returns self."""
        self.step(t, dt)
        self.inputs_to_step_end(dt)
        self.output()
        return self

    # -- state (FMU get/set state) --------------------------------------------------
    _NOT_STATE = frozenset({"layout", "values", "strings", "p", "u", "y", "warnings"})

    def get_state(self):
        """A deep copy of everything that evolves: the value array and all attributes."""
        attributes = {k: v for k, v in vars(self).items() if k not in self._NOT_STATE}
        return self.values.copy(), dict(self.strings), copy.deepcopy(attributes)

    @classmethod
    def state_problem(cls, attributes: dict, reference: dict) -> str:
        """What in a restored state's ``attributes`` (checked for names, kinds and shapes)
        a model of this class could never hold, given ``reference``, the attributes of the
        model initialised with the state's parameters: the rows of a kernel's state array
        that it indexes with (counts, places, section lengths).  '' if nothing."""
        return ""

    def set_state(self, state) -> None:
        values, strings, attributes = state
        self.values[:] = values
        self.strings.clear()
        self.strings.update(strings)
        vars(self).update(copy.deepcopy(attributes))
