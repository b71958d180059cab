"""A system built in Python: :class:`System`.

    system = System("detumble", step=0.05, stop=100.0)    # Jacobi, derivatives where declared
    system.add("SatelliteDynamics", inertia=50 * np.eye(3), rate0=deg([1, -0.5, 0.8]))
    system.add("Damper", "rate_damper.py", gain=5.0)       # a model of yours (built as an FMU)
    system.add("Flywheel")                                 # one of ours, by name
    system.connect("SatelliteDynamics.w_BI_B", "Damper.w_BI_B")   # whole vectors by base name
    system.write("detumble.ssd")                           # or .ssp: the FMUs inside

A component is one of our FMUs by name, any FMI 2.0 co-simulation FMU file (``.fmu``), or
a model of yours on our :class:`~agilesat.components.model.Model` API (``.py``, built into
``build/`` beside it by :mod:`agilesat.fmus.user_models`, as ``agilesat build`` does).
Relative paths are relative to the file that names them.  Every FMU is described by its
model description alone, so a third-party FMU is described as well as ours.

Parameter values take a unit where the variable is a Real (``"120 deg"``, ``deg(120)``,
``deg([0, 120, 0])``; :mod:`..system.units`); a unit that does not convert is an error.

:meth:`System.check` (and everything that runs or writes the system) checks it against the
FMUs' model descriptions: unknown components and variables (with the closest names),
shapes, causality, types and units of each connection, parameter values, then the master's
own checks (:func:`..system.validation.check_system`: inputs driven twice, inputs left open,
parameters two FMUs must share, algebraic loops), each message naming the file and line of
the call that made the problem, all reported together.
"""

from __future__ import annotations

import copy
import os
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

from ..system.description import Description
from ..system.parameters import did_you_mean, typed_parameters, variables
from ..system.ssp import (
    ComponentRef,
    ConnectionRef,
    SystemFile,
    SystemFileError,
    render_ssd,
)
from ..system.validation import check_system, variable_pair_problems

ALGORITHMS = ("jacobi", "gauss-seidel")
_PACKAGE = os.path.dirname(os.path.abspath(__file__))


@dataclass(frozen=True)
class _Component:
    name: str
    fmu: str  # one of our FMUs by name, or the absolute path of an .fmu or a model .py
    step: float | None
    line: int


def _origin(prefer: str | None = None) -> tuple[str, int]:
    """(file, line) of the user's call: the innermost frame outside this package, or the
    innermost in ``prefer`` (the system's own file) further out, if there is one."""
    frame = sys._getframe(1)
    while frame is not None and (
        frame.f_code.co_filename == "<string>"  # a dataclass's generated __init__
        or os.path.dirname(os.path.abspath(frame.f_code.co_filename)) == _PACKAGE
    ):
        frame = frame.f_back
    if frame is None:
        return "<python>", 0
    found = (frame.f_code.co_filename, frame.f_lineno)
    if prefer is not None:
        outer = frame
        while outer is not None and outer.f_code.co_filename != prefer:
            outer = outer.f_back
        if outer is not None:
            return prefer, outer.f_lineno
    return found


def where_written() -> str:
    """Where the user's call is (:func:`_origin`), as "file:line" ("" where no file)."""
    file, line = _origin()
    return f"{file}:{line}" if line else ""


def _split(name: str, what: str) -> tuple[str, str]:
    component, _, variable = str(name).partition(".")
    if not component or not variable:
        raise ValueError(f"{what} {name!r}: expected Component.variable")
    return component, variable


class System:
    """A system of FMU components, their connections and parameter values, and how to run
    it: ``start``, ``stop`` and ``step`` (s), ``algorithm`` ("jacobi", the default, or
    "gauss-seidel") and ``derivatives`` (couple through FMI input/output derivatives where
    both FMUs declare them; default on).  Jacobi with derivatives is the master's most
    accurate scheme (docs/coupling.md)."""

    def __init__(
        self,
        name: str,
        *,
        start: float = 0.0,
        stop: float | None = None,
        step: float | None = None,
        algorithm: str = "jacobi",
        derivatives: bool = True,
    ):
        if algorithm not in ALGORITHMS:
            raise ValueError(f"algorithm must be one of {ALGORITHMS}, got {algorithm!r}")
        self.name = name
        self.start, self.stop, self.step = start, stop, step
        self.algorithm, self.derivatives = algorithm, derivatives
        self.file, _ = _origin()
        self._components: dict[str, _Component] = {}
        self._connections: list[tuple[str, str, int]] = []
        self._parameters: dict[str, tuple[object, int]] = {}
        self._resolved: dict[tuple, tuple] = {}  # (built?, settings) -> (system, described)

    # -- building ---------------------------------------------------------------------
    def add(self, name: str, fmu=None, *, step: float | None = None, **parameters) -> System:
        """Add component ``name``: ``fmu`` is one of our FMUs by name (default: ``name``),
        a path to an ``.fmu`` file, or a path to a model ``.py`` (``path.py:ClassName`` if
        it defines several); ``step`` its own communication step (a multiple of the
        system's, docs/coupling.md#multi-rate); ``parameters`` its values by variable."""
        file, line = _origin(self.file)
        if not str(name).isidentifier():
            raise ValueError(f"{file}:{line}: component name {name!r} is not an identifier")
        if name in self._components:
            raise ValueError(f"{file}:{line}: component {name!r} is added twice")
        self._components[name] = _Component(
            name, _fmu(fmu or name, file, f"{file}:{line}: component {name!r}"), step, line
        )
        for variable, value in parameters.items():
            self._parameters[f"{name}.{variable}"] = (value, line)
        self._resolved.clear()
        return self

    def remove(self, name: str) -> System:
        """Take component ``name`` out, with its connections and parameter values."""
        self._component(name, "remove")
        del self._components[name]
        self._connections = [
            c for c in self._connections if name not in (c[0].split(".")[0], c[1].split(".")[0])
        ]
        self._parameters = {k: v for k, v in self._parameters.items() if k.split(".")[0] != name}
        self._resolved.clear()
        return self

    def replace(self, name: str, fmu, **parameters) -> System:
        """Put another FMU in component ``name``'s place: its connections stay, its
        parameter values are ``parameters``."""
        file, line = _origin(self.file)
        old = self._component(name, "replace")
        self._components[name] = _Component(
            name, _fmu(fmu, file, f"{file}:{line}: component {name!r}"), old.step, line
        )
        self._parameters = {k: v for k, v in self._parameters.items() if k.split(".")[0] != name}
        for variable, value in parameters.items():
            self._parameters[f"{name}.{variable}"] = (value, line)
        self._resolved.clear()
        return self

    def set_step(self, name: str, step: float | None) -> System:
        """Give component ``name`` its own communication step (None: the system's)."""
        c = self._component(name, "set_step:")
        self._components[name] = _Component(c.name, c.fmu, step, c.line)
        self._resolved.clear()
        return self

    def connect(self, source: str, target: str, *, replace: bool = False) -> System:
        """Connect output ``source`` ("A.y", a whole vector or matrix by its base name, one
        row of a matrix "A.y[2]", or one element "A.y[2]", "A.y[2,1]") to input ``target``
        ("B.u", likewise).  A table of slots (an optional input of shape (n, k), the hub's
        ``tau_extra``, ``h_extra``) takes a k-vector, or an (m, k) table, into its first
        rows that nothing else feeds: ``connect("Magnetorquer.tau_B",
        "SatelliteDynamics.tau_extra")`` adds a torque to the hub whatever feeds it already;
        name the row ("SatelliteDynamics.h_extra[2]") where one device feeds several
        tables, so that its rows line up.  ``replace``: the target is already connected,
        and this connection takes its place."""
        file, line = _origin(self.file)
        for end in (source, target):
            component, _ = _split(end, f"{file}:{line}: connect")
            self._component(component, f"{file}:{line}: connect {source} -> {target}:")
        existing = [c for c in self._connections if c[1] == target]
        if existing and not replace and not self._may_take_several(target):
            raise ValueError(
                f"{file}:{line}: {target} is already connected (to {existing[0][0]}, line "
                f"{existing[0][2]}): connect(..., replace=True) to rewire it"
            )
        if replace and not existing:
            raise ValueError(f"{file}:{line}: replace=True, but {target} is not connected")
        if replace:
            self._connections = [c for c in self._connections if c[1] != target]
        self._connections.append((source, target, line))
        self._resolved.clear()
        return self

    def disconnect(self, target: str) -> System:
        """Remove the connection into input ``target``."""
        kept = [c for c in self._connections if c[1] != target]
        if len(kept) == len(self._connections):
            raise ValueError(f"{target} is not connected")
        self._connections = kept
        self._resolved.clear()
        return self

    def set(self, key, value=None) -> System:
        """Set parameter ``key`` ("A.p", a whole array or one element) to ``value``, or
        several: ``set({"A.p": 1.0, "B.q": deg(5)})``."""
        _, line = _origin(self.file)
        values = key if isinstance(key, dict) else {key: value}
        for name, given in values.items():
            self._set(name, given, line)
        return self

    def _set(self, name: str, value, line: int) -> None:
        component, _ = _split(name, f"{self.file}:{line}: set")
        self._component(component, f"{self.file}:{line}: set {name}:")
        self._parameters[name] = (value, line)
        self._resolved.clear()

    def copy(self, name: str | None = None) -> System:
        """An independent copy (a variant's system starts from one), renamed if ``name``."""
        twin = copy.copy(self)
        twin._components = dict(self._components)
        twin._connections = list(self._connections)
        twin._parameters = dict(self._parameters)
        twin._resolved = {}
        twin.name = name or self.name
        return twin

    def _may_take_several(self, target: str) -> bool:
        """Whether ``target`` may be fed by several connections: a table of slots of one of
        our FMUs (its model description says), or any input whose connections are checked
        only when the system is (the master's check of an input driven twice): of an FMU
        file, of a model of yours, of one of ours not built yet."""
        component, variable = _split(target, "connect")
        fmu = self._components[component].fmu
        if fmu.endswith(".fmu") or ".py" in fmu:
            return True
        try:
            d = Description(component, fmu_file(fmu, build=False))
        except FileNotFoundError:
            return True
        array = variables(d).get(variable)
        return array is not None and _is_slot_table(d, array.shape, array.scalars)

    def _component(self, name: str, what: str) -> _Component:
        if name not in self._components:
            raise KeyError(
                f"{what} unknown component {name!r}"
                + did_you_mean(name, self._components)
                + f" (components: {', '.join(self._components) or 'none yet'})"
            )
        return self._components[name]

    # -- what it is -----------------------------------------------------------------
    @property
    def components(self) -> tuple[str, ...]:
        return tuple(self._components)

    @property
    def connections(self) -> list[tuple[str, str]]:
        """(source, target) pairs as connected."""
        return [(a, b) for a, b, _ in self._connections]

    @property
    def parameters(self) -> dict:
        """{"A.p": value} as set."""
        return {k: v for k, (v, _) in self._parameters.items()}

    def fmu(self, name: str) -> str:
        """What component ``name`` is: our FMU's name, or the path of its .fmu or model."""
        return self._component(name, "fmu:").fmu

    def __repr__(self):
        return (
            f"<System {self.name}: {len(self._components)} components, "
            f"{len(self._connections)} connections, {len(self._parameters)} parameter values>"
        )

    # -- checked ----------------------------------------------------------------------
    def system_file(self, build: bool = True) -> SystemFile:
        """The system as the master runs it, checked against the FMUs' model descriptions
        (see the module); ``build``: build the FMUs that are missing or stale (ours and the
        model ``.py`` files), else they must be there.  Raises SystemFileError with every
        problem."""
        return self._resolve(build)[0]

    def descriptions(self, build: bool = True) -> dict[str, Description]:
        """{component: the Description of its FMU}."""
        return self._resolve(build)[1]

    def check(self, build: bool = True) -> System:
        """Raise SystemFileError naming every problem (see the module); else the system."""
        self._resolve(build)
        return self

    def _resolve(self, build: bool) -> tuple[SystemFile, dict]:
        settings = (self.start, self.stop, self.step, self.algorithm, self.derivatives)
        for done in (True, build):  # checked with the FMUs built serves either
            if (done, settings) in self._resolved:
                return self._resolved[(done, settings)]
        problems: list[str] = []
        described, refs = {}, []
        for c in self._components.values():
            try:
                path = fmu_file(c.fmu, build)
                described[c.name] = Description(c.name, path)
            except Exception as exc:  # noqa: BLE001 - any unusable FMU: say which and why
                message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
                problems.append(f"{self.file}:{c.line}: component '{c.name}': {message}")
                continue
            refs.append(ComponentRef(c.name, path, c.line, [], c.step))
        if problems:
            raise SystemFileError(_report(self.file, problems))
        connections = self._expanded(described, problems)
        values = {}
        for key, (value, line) in self._parameters.items():
            try:
                values.update(
                    typed_parameters(described, {key: value}, {key: f"{self.file}:{line}"})
                )
            except SystemFileError as exc:
                problems.append(str(exc))
        if problems:
            raise SystemFileError(_report(self.file, problems))
        system = SystemFile(
            Path(self.file),
            self.name,
            refs,
            connections,
            list(values.values()),
            self.start,
            self.stop,
            self.step,
            self.algorithm,
            self.derivatives,
        )
        check_system(system, described, system.parameters)
        self._resolved[(build, settings)] = system, described
        return system, described

    def _expanded(self, described: dict, problems: list) -> list[ConnectionRef]:
        """The connections element by element, after the whole-variable checks: components,
        variables (with the closest names), shapes, then causality, type and unit (the
        master's own messages, :func:`..system.validation.variable_pair_problems`).  A
        table of slots named whole takes the first rows nothing else feeds (explicit rows
        first, then in the order of the connections)."""
        tables = {name: variables(d) for name, d in described.items()}
        ends, fed = [], set()
        for source, target, line in self._connections:
            at = f"{self.file}:{line}: connection {source} -> {target}"
            pair = [_end(end, described, tables, at, problems) for end in (source, target)]
            if None in pair:
                continue
            (a, x, sa, xs), (b, y, sb, ys) = pair
            table = _slots(b, y, sb, ys, len(xs))
            if table is None:
                fed.update((b.name, v.name) for v in ys)
            ends.append((at, line, pair, table))
        result, seen = [], {}
        for at, line, ((a, x, sa, xs), (b, y, sb, ys)), table in ends:
            if table is not None:
                rows = _free_rows(b.name, ys, sb, len(xs) // sb[1], fed)
                if rows is None:
                    problems.append(
                        f"{at}: every row of {b.name}.{y} ({sb[0]}) is fed already: name a "
                        "row to rewire it, connect(..., replace=True)"
                    )
                    continue
                first, ys = rows
                count = len(ys) // sb[1]
                y = f"{y}[{first + 1}]" if count == 1 else f"{y}[{first + 1}..{first + count}]"
                fed.update((b.name, v.name) for v in ys)
            if len(xs) != len(ys):
                problems.append(
                    f"{at}: shapes differ: {a.name}.{x} is {_shape(sa)}, {b.name}.{y} is "
                    f"{_shape(sb)}"
                )
                continue
            twice = [v.name for v in ys if (b.name, v.name) in seen]
            if twice and table is None:
                first = seen[(b.name, twice[0])]
                problems.append(
                    f"{at}: {b.name}.{y} is already connected (to {first[0]}, line "
                    f"{first[1]}): connect(..., replace=True) to rewire it"
                )
                continue
            found = variable_pair_problems(at, a, _whole(x, xs), b, _whole(y, ys))
            if found:
                problems += found
                continue
            for u, v in zip(xs, ys):
                seen[(b.name, v.name)] = (f"{a.name}.{x}", line)
                result.append(ConnectionRef(a.name, u.name, b.name, v.name, line))
        return result

    # -- written ----------------------------------------------------------------------
    def ssd(self, sources: dict | None = None, build: bool = True) -> bytes:
        """The system as SSD; ``sources``: {component: its FMU source as written (relative
        to where the SSD goes)}, default the FMUs' absolute paths."""
        system, described = self._resolve(build)
        return render_ssd(system, described, sources)

    def write(self, path) -> Path:
        """Write the system as ``path``: an ``.ssd`` (FMU sources relative to it), or an
        ``.ssp`` package holding the SSD and every FMU (it runs wherever it is copied)."""
        path = Path(path)
        if path.suffix not in (".ssd", ".ssp"):
            raise ValueError(f"{path}: write an .ssd file or an .ssp package")
        system, _ = self._resolve(True)
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix == ".ssd":
            here = path.resolve().parent
            sources = {
                ref.name: Path(os.path.relpath(ref.source, here)).as_posix()
                for ref in system.components
            }
            path.write_bytes(self.ssd(sources))
            return path
        from .package import write_package

        return write_package(system, self.descriptions(), path)


def _end(end: str, described: dict, tables: dict, at: str, problems: list):
    """(description, variable, shape, scalars) of one end of a connection: a scalar by its
    FMI name, a whole array by its base name, or a row of a matrix, "y[2]"; None (the
    problem appended) if there is no such variable."""
    component, variable = _split(end, at)
    if component not in described:
        problems.append(f"{at}: unknown component '{component}'")
        return None
    d, table = described[component], tables[component]
    if variable in d.variables:
        return d, variable, (), [d.variables[variable]]
    if variable in table:
        return d, variable, table[variable].shape, table[variable].scalars
    row = _ROW.match(variable)
    array = table.get(row.group(1)) if row else None
    if array is not None and len(array.shape) == 2 and 1 <= int(row.group(2)) <= array.shape[0]:
        k, i = array.shape[1], int(row.group(2)) - 1
        return d, variable, (k,), array.scalars[i * k : (i + 1) * k]
    problems.append(
        f"{at}: {component} ({d.path.name}) has no variable '{variable}'"
        + did_you_mean(variable, table)
    )
    return None


_ROW = re.compile(r"^(.*)\[([0-9]+)\]$")


def _is_slot_table(d, shape: tuple, scalars: list) -> bool:
    """Whether a variable of ``d`` is a table of slots: an optional input of shape (n, k),
    one source a row."""
    first = scalars[0]
    optional = d.optional_inputs is not None and first.name in d.optional_inputs
    return first.causality == "input" and len(shape) == 2 and optional


def _slots(d, name: str, shape: tuple, scalars: list, size: int):
    """The slot table ``name`` (shape) when a connection of ``size`` scalars names it whole
    and fills whole rows of it, else None."""
    if not _is_slot_table(d, shape, scalars) or size == len(scalars):
        return None
    return shape if size % shape[1] == 0 and size < len(scalars) else None


def _free_rows(component: str, scalars: list, shape: tuple, count: int, fed: set):
    """(first row, its scalars) of the first ``count`` consecutive rows of a slot table
    none of whose scalars is ``fed``; None if there are none."""
    k = shape[1]
    for first in range(shape[0] - count + 1):
        rows = scalars[first * k : (first + count) * k]
        if not any((component, v.name) in fed for v in rows):
            return first, rows
    return None


def _shape(shape) -> str:
    return "a scalar" if not shape else "×".join(map(str, shape))


def _whole(name: str, scalars: list):
    """The variable ``name`` for the connection checks: its elements' causality, type and
    unit when they share them (else the first element's, whose messages then name it)."""
    first = scalars[0]
    same = all(
        (v.causality, v.type, v.unit) == (first.causality, first.type, first.unit) for v in scalars
    )
    if not same:
        return first
    return SimpleNamespace(name=name, causality=first.causality, type=first.type, unit=first.unit)


def _report(file: str, problems: list[str]) -> str:
    return f"{file}: {len(problems)} problem(s):\n  " + "\n  ".join(problems)


def _fmu(fmu, file: str, where: str) -> str:
    """A component's FMU as stored: our FMU's name, or an absolute path (a relative one is
    relative to the directory of ``file``, the file that names it; ``where``: the call
    that does, for the message about an FMU that is none of ours)."""
    text = os.fspath(fmu)
    path, cls = text.rsplit(":", 1) if ".py:" in text else (text, "")
    if Path(path).suffix not in (".fmu", ".py"):
        from ...fmus import FMUS

        if os.sep in text or "/" in text:
            raise ValueError(f"{text}: an FMU is one of ours by name, an .fmu file or a model .py")
        if text not in FMUS:  # said here, not at the first connection to it
            raise SystemFileError(
                f"{where}: unknown FMU {text!r}"
                + did_you_mean(text, FMUS)
                + f" (ours: {', '.join(FMUS)}; or the path of an .fmu file or a model .py)"
            )
        return text
    base = Path(file).parent if os.path.isfile(file) else Path.cwd()
    absolute = str((base / path).resolve())
    return f"{absolute}:{cls}" if cls else absolute


def fmu_file(fmu: str, build: bool = True) -> Path:
    """The FMU file of a component (see :meth:`System.add`): ours built if ``build`` and
    missing or stale, a model ``.py`` built the same way (:mod:`agilesat.fmus.user_models`),
    an ``.fmu`` as it is."""
    path, cls = fmu.rsplit(":", 1) if ".py:" in fmu else (fmu, "")
    if path.endswith(".fmu"):
        if not Path(path).is_file():
            raise FileNotFoundError(f"no FMU file {path}")
        return Path(path)
    if path.endswith(".py"):
        from ...fmus.user_models import model_fmu

        return model_fmu(Path(path), cls or None, build=build)
    from ...fmus import FMUS
    from ...fmus.build import BUILD_DIR, build_fmu

    if fmu not in FMUS:
        raise KeyError(
            f"unknown FMU {fmu!r}" + did_you_mean(fmu, FMUS) + f" (ours: {', '.join(FMUS)}; "
            "or give the path of an .fmu file or of a model .py)"
        )
    if build:
        return build_fmu(fmu)
    target = BUILD_DIR / f"{fmu}.fmu"
    if not target.is_file():
        raise FileNotFoundError(f"{target} is not built (agilesat build {fmu})")
    return target
