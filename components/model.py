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

The same object runs in-process (tests, references) and inside the FMU wrapper.
"""
from __future__ import annotations

import copy
from typing import TypeVar

import numpy as np

from .variables import Bus, Layout, Var

_M = TypeVar("_M", bound="Model")


class ModelError(RuntimeError):
    """The model cannot continue (bad parameter, non-finite state, ...)."""


class Model:
    VARIABLES: tuple[Var, ...] = ()
    #: inputs that the initial state depends on (beyond the parameters)
    INITIAL_STATE_DEPENDS: tuple[str, ...] = ()
    _layouts: dict[type, Layout] = {}

    def __init__(self, **parameters):
        cls = type(self)
        if cls not in Model._layouts:
            Model._layouts[cls] = Layout(cls.VARIABLES)
        self.layout = Model._layouts[cls]
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

    # -- in-process convenience ------------------------------------------------------
    def set(self, name: str, value) -> None:
        """Set a parameter or input by name (whole arrays at once)."""
        v = self.layout.by_name.get(name)
        if v is None:
            raise KeyError(f"{type(self).__name__} has no variable {name!r}")
        if v.causality == "output":
            raise KeyError(f"{type(self).__name__}.{name} is an output")
        if v.type == "String":
            self.strings[name] = str(value)
            return
        array = np.asarray(value, dtype=float)
        if array.shape != v.shape and array.size != v.size:
            raise ValueError(f"{type(self).__name__}.{name}: expected shape {v.shape}, "
                             f"got {array.shape}")
        self.values[self.layout.slice(name)] = array.reshape(-1)

    def get(self, name: str):
        """Value of any variable by name (outputs as last written by ``output``)."""
        v = self.layout.by_name[name]
        if v.type == "String":
            return self.strings[name]
        data = self.values[self.layout.slice(name)]
        return data.reshape(v.shape).copy() if v.shape else data[0]

    def start(self: _M, t0: float = 0.0) -> _M:
        """Initialize at ``t0`` and evaluate the outputs; returns self."""
        self.initialize(t0)
        self.output()
        return self

    def advance(self: _M, t: float, dt: float) -> _M:
        """Step from ``t`` to ``t + dt`` and evaluate the outputs; returns self."""
        self.step(t, dt)
        self.output()
        return self

    # -- state (FMU get/set state) --------------------------------------------------
    _NOT_STATE = frozenset({"layout", "values", "strings", "p", "u", "y", "warnings"})

    def get_state(self):
        """A deep copy of everything that evolves: the value array and all attributes."""
        attributes = {k: v for k, v in vars(self).items() if k not in self._NOT_STATE}
        return self.values.copy(), dict(self.strings), copy.deepcopy(attributes)

    def set_state(self, state) -> None:
        values, strings, attributes = state
        self.values[:] = values
        self.strings.clear()
        self.strings.update(strings)
        vars(self).update(copy.deepcopy(attributes))
