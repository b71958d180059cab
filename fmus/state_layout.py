"""A restored FMU state checked against the model's own layout, before anything uses it.

``fmu_state`` decodes bytes into plain data without running code; this module checks that
the data is a state *this model* could have been in.  The reference is a model of the same
class initialised at its defaults (:func:`reference`, once per class and process): a
model's attributes are all set by ``initialize`` (tests/fmus/test_state_layout.py checks it
for every FMU and every shipped configuration), and their kinds do not depend on the
values.  Refused, with the attribute and what was expected:

- an attribute the model does not have, one that would shadow a method or anything else
  of its class (but the None default of an instance attribute, ``_initial_inputs``), and
  (for a state taken after initialisation) one that is missing;
- an array whose dtype or shape is not the reference's (the compiled kernels and the
  shim's C step path index the arrays without bounds checks), or with a non-finite value
  where the reference's array has a finite one;
- an object of another class than the reference's, or with other attributes (checked
  recursively), a container of arrays or objects of another length;
- a number where the reference holds another kind of scalar (a string for ``t``);
- in the value array: an input that is not finite, a parameter that is NaN (a Real one may
  be ±inf: a fault time "never", a limit "none"; the model's initialize judges it), a
  Boolean that is not 0 or
  1, an Integer that is not a whole number of fmi2Integer's range, and, where the state
  says its outputs are valid (the host would read them as they are), a non-finite output.

Where the reference holds None (a value set only once the model has run, a
parameter-dependent one), anything the format can hold is accepted.

The reference of an initialised state is the model initialised with the state's own
values (its parameters), so that an array sized from the parameters (a star tracker's
pipeline, an estimator's history) is checked against what they make; a model's kernels
also index its state array with rows of it (counts, places, section lengths), which
:meth:`Model.state_problem` checks against that reference.  Values that do not initialise
the model fall back to the class's reference.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .fmu_state import StateError

_INT32 = (-(2**31), 2**31 - 1)


@functools.cache
def reference(model_class) -> dict | None:
    """The attributes of a ``model_class`` initialised at its defaults (None: it cannot
    be, then only names are checked, against the class)."""
    return _initialised(model_class, None, None)


@functools.lru_cache(maxsize=32)
def _reference_of(model_class, parameters: bytes, strings: tuple) -> dict | None:
    """The attributes of a ``model_class`` initialised with these parameter values (the
    parameter group of its value array) and strings (None: it cannot be)."""
    return _initialised(model_class, np.frombuffer(parameters), dict(strings))


def _initialised(model_class, parameters, strings) -> dict | None:
    model = model_class()
    if parameters is not None:
        group = model.layout.range["parameter"]
        model.values[group.start : group.stop] = parameters
        model.strings.update(strings)
    try:
        model.initialize(0.0)
    except Exception:  # noqa: BLE001 - a model that needs inputs to initialise
        return None
    return {k: v for k, v in vars(model).items() if k not in model._NOT_STATE}


def check(model_class, model_state, initialized: bool, outputs_valid: bool) -> None:
    """StateError naming the first thing in ``model_state`` (values, strings,
    attributes) that does not fit ``model_class``'s layout (module docstring)."""
    values, strings, attributes = model_state
    _check_values(model_class, values, outputs_valid)
    ref = None
    if initialized:  # the reference of the state's own parameters
        group = model_class.table_layout().range["parameter"]
        parameters = values[group.start : group.stop].tobytes()
        ref = _reference_of(model_class, parameters, tuple(sorted(strings.items())))
    ref = ref or reference(model_class)
    model = model_class.__name__
    for name, value in attributes.items():
        if (ref is None or name not in ref) and getattr(model_class, name, 0) is not None:
            kind = _class_member(model_class, name)
            raise StateError(
                f"the state's attribute {name!r} would shadow the {kind} {model}.{name}"
                if kind
                else f"the state has an attribute {name!r}, which {model} has not"
            )
        problem = _mismatch(value, ref.get(name) if ref else None, name)
        if problem:
            raise StateError(f"the state's {problem}")
    if initialized and ref is not None:
        missing = sorted(n for n in ref if n not in attributes and not hasattr(model_class, n))
        if missing:
            raise StateError(f"the state of an initialised {model} lacks {missing}")
        problem = model_class.state_problem(attributes, ref)
        if problem:
            raise StateError(f"the state's {problem}")


def _class_member(model_class, name: str) -> str:
    """What ``name`` is on the class ('method', 'class attribute', ...), or ''."""
    for cls in model_class.__mro__:
        if name in vars(cls):
            member = vars(cls)[name]
            if isinstance(member, property):
                return "property"
            return (
                "method" if callable(member) or hasattr(member, "__get__") else ("class attribute")
            )
    return ""


def _check_values(model_class, values: np.ndarray, outputs_valid: bool) -> None:
    layout = model_class._layouts.get(model_class) or model_class().layout
    if values.size != layout.n_values:  # the variables, then the input derivatives' block
        raise StateError(
            f"the state has {values.size} values, {model_class.__name__} has {layout.n_values}"
        )
    if not np.isfinite(values[layout.n_numeric :]).all():
        raise StateError("the state's input derivatives are not all finite")
    for v in layout.variables:
        if v.type == "String" or v.causality == "output" and not outputs_valid:
            continue
        x = values[layout.slice(v.name)]
        infinite = v.causality == "parameter" and v.type == "Real"  # may be ±inf, never NaN
        bad = (
            (np.isnan(x) if infinite else ~np.isfinite(x))
            | (v.type == "Boolean") & ~np.isin(x, (0.0, 1.0))
            | (v.type == "Integer") & ((x != np.round(x)) | (x < _INT32[0]) | (x > _INT32[1]))
        )
        if bad.any():
            element = v.scalar_names()[int(np.argmax(bad))]
            expected = {
                "Real": "a number" if infinite else "a finite Real",
                "Boolean": "a Boolean (0 or 1)",
                "Integer": "a whole number of fmi2Integer's range",
            }[v.type]
            raise StateError(
                f"the state's value of {v.causality} {element} is {float(x[bad][0])!r}, "
                f"not {expected}"
            )


def _kind(x) -> str:
    if isinstance(x, (bool, np.bool_)):
        return "bool"
    if isinstance(x, (int, float, np.integer, np.floating)):
        return "number"
    return type(x).__name__


def _structured(x) -> bool:
    """An array or an object: what a container of it must hold in the same places."""
    return type(x) is np.ndarray or hasattr(x, "__dict__") and not isinstance(x, type)


def _mismatch(value, ref, path: str) -> str:
    """'' if ``value`` fits the reference value ``ref`` (module docstring), else what does
    not, for a message."""
    if ref is None:
        return ""
    if type(ref) is np.ndarray:
        if type(value) is not np.ndarray or value.dtype != ref.dtype or value.shape != ref.shape:
            what = (
                f"a {value.dtype} array of shape {value.shape}"
                if type(value) is np.ndarray
                else f"a {type(value).__name__}"
            )
            return f"{path} is {what}, not a {ref.dtype} array of shape {ref.shape}"
        if ref.dtype.kind in "fc" and not np.isfinite(value[np.isfinite(ref)]).all():
            return f"{path} has non-finite values (the model keeps them finite)"
        return ""
    if isinstance(ref, (list, tuple)):
        if value is None:
            return ""
        if type(value) is not type(ref):
            return f"{path} is a {type(value).__name__}, not a {type(ref).__name__}"
        if len(value) == len(ref):
            for k, (a, b) in enumerate(zip(value, ref)):
                problem = _mismatch(a, b, f"{path}[{k}]")
                if problem:
                    return problem
        elif any(_structured(r) for r in ref):
            return f"{path} has {len(value)} items, not {len(ref)}"
        return ""
    if isinstance(ref, dict):
        if value is None:
            return ""
        if type(value) is not dict:
            return f"{path} is a {type(value).__name__}, not a dict"
        if set(value) == set(ref):
            found = (_mismatch(value[k], ref[k], f"{path}[{k!r}]") for k in ref)
            return next(filter(None, found), "")
        if any(_structured(r) for r in ref.values()):
            return f"{path} has the keys {sorted(map(str, value))}, not {sorted(map(str, ref))}"
        return ""
    if _structured(ref):
        if type(value) is not type(ref):
            return f"{path} is a {type(value).__name__}, not a {type(ref).__qualname__}"
        mine, theirs = vars(value), vars(ref)
        if set(mine) != set(theirs):
            return (
                f"{path} has the attributes {sorted(mine)}, not {sorted(theirs)} "
                f"(a {type(ref).__qualname__})"
            )
        for name in theirs:
            problem = _mismatch(mine[name], theirs[name], f"{path}.{name}")
            if problem:
                return problem
        return ""
    if value is None or _kind(value) == _kind(ref):
        finite = _kind(ref) == "number" and math.isfinite(ref)
        if finite and _kind(value) == "number" and not math.isfinite(value):
            return f"{path} is {value!r} (the model keeps it finite)"
        return ""
    return f"{path} is a {type(value).__name__}, not a {type(ref).__name__}"
