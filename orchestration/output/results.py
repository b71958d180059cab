"""Results of a run: one row per communication point, one named column per variable.

Columns are ``time`` and ``<instance>.<variable>`` (e.g. ``SatelliteDynamics.q_BI[1]``),
every value SI in the unit of its model description (``units``).  Written as CSV
(``results.csv``, readable by ``fmpy.util.read_csv``; the units in the sidecar
``results.units.json``), NumPy's ``.npz`` (units inside) and MATLAB's ``.mat``.  While a
run is going, :mod:`.recorder` appends each row to the CSV, so a run that fails (or is
killed) leaves everything recorded up to the failure on disk.
"""

from __future__ import annotations

import csv
import difflib
import functools
import json
import re
from pathlib import Path

import numpy as np

from ..system.units import to_degrees

_ELEMENT = re.compile(r"^(.*)\[([0-9,]+)\]$")


class ColumnError(KeyError):
    """No such column; the message names the closest ones."""

    def __str__(self):
        return str(self.args[0])


def units_path(csv_path) -> Path:
    """The units sidecar of a CSV file: results.csv -> results.units.json."""
    return Path(csv_path).with_suffix(".units.json")


class Results:
    """The recorded outputs of a run.

    ``r["SatelliteDynamics.w_BI_B[2]"]`` is one column (N,); ``r["SatelliteDynamics.w_BI_B"]``
    (or ``r.vector(...)``) all elements of an array variable (N, size); ``r.get(name,
    deg=True)`` the same in degrees where the unit is an angle.  ``r.time``, ``r.units``
    ({column: unit}), ``r.unit(name)``, ``r.select(*names, start=, stop=)`` (a new Results
    with those variables over a time window), ``r.to_pandas()``, ``to_csv``/``to_npz``/
    ``to_mat`` and ``from_csv``/``from_npz``.  ``meta`` holds the settings and FMU log.
    :meth:`derived` keeps what is computed from the records (:func:`per_results`).
    """

    def __init__(self, names: list[str], data: np.ndarray, meta: dict | None = None):
        if data.ndim != 2 or data.shape[1] != len(names):
            raise ValueError(f"data {data.shape} does not match {len(names)} columns")
        self.names = [str(n) for n in names]
        self.data = data
        self.meta = dict(meta or {})
        self._index = {n: i for i, n in enumerate(self.names)}
        self._bases: dict[str, list[int]] = {}
        self._derived: dict = {}
        for i, n in enumerate(self.names):
            match = _ELEMENT.match(n)
            if match:
                self._bases.setdefault(match.group(1), []).append(i)

    @property
    def time(self) -> np.ndarray:
        return self.data[:, self._index["time"]]

    @property
    def units(self) -> dict[str, str]:
        """{column: unit} as the model descriptions give them ("time": "s")."""
        return {"time": "s", **self.meta.get("units", {})}

    def __len__(self):
        return self.data.shape[0]

    def __contains__(self, name):
        return name in self._index or name in self._bases

    def __repr__(self):
        instances = sorted({n.split(".")[0] for n in self.names if "." in n})
        span = f"t = {self.time[0]:g} … {self.time[-1]:g} s" if len(self) else "no rows"
        step = f", step {self.meta['step']:g} s" if "step" in self.meta else ""
        return (
            f"<Results: {len(self)} rows, {span}{step}; {len(self.names) - 1} columns "
            f"of {', '.join(instances)}>"
        )

    def columns(self, name: str) -> list[str]:
        """The columns of a variable: [name] for a scalar, its elements for an array."""
        if name in self._index:
            return [name]
        if name in self._bases:
            return [self.names[i] for i in self._bases[name]]
        raise self._missing(name)

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self._index:
            return self.data[:, self._index[name]]
        if name in self._bases:
            return self.data[:, self._bases[name]]
        raise self._missing(name)

    def vector(self, name: str) -> np.ndarray:
        """All elements of an array variable as an (N, size) array: vector('X.w_BI_B')."""
        if name not in self._bases:
            raise self._missing(name, "array variable")
        return self.data[:, self._bases[name]]

    def derived(self, key, compute):
        """``compute()``, computed once for ``key`` (hashable) on these results and kept
        with them (it goes when they go: no other Results sees it).  Arrays in what it
        returns are made read-only: every caller gets the same ones.  It assumes the
        records are not changed in place after (``data`` is a run's)."""
        kept = self.__dict__.setdefault("_derived", {})
        if key not in kept:
            kept[key] = _read_only(compute())
        return kept[key]

    def __getstate__(self) -> dict:
        """Pickled (a copy, another process) without what was derived: computed again."""
        return {k: v for k, v in self.__dict__.items() if k != "_derived"}

    def get(self, name: str, deg: bool = False) -> np.ndarray:
        """A column or a whole array variable; with ``deg``, angles (rad, rad/s, rad/s2)
        in degrees."""
        values = self[name]
        return values * to_degrees(self.unit(name))[0] if deg else values

    def unit(self, name: str) -> str | None:
        """The unit of a column or an array variable (None if the run did not record it)."""
        return self.units.get(self.columns(name)[0])

    def select(self, *names: str, start: float | None = None, stop: float | None = None) -> Results:
        """A new Results with ``time`` and the named variables (all, if none are named),
        rows with start <= time <= stop."""
        t = self.time
        rows = np.ones(len(t), bool)
        if start is not None:
            rows &= t >= start - 1e-12
        if stop is not None:
            rows &= t <= stop + 1e-12
        chosen = (
            ["time"] + [c for n in names for c in self.columns(n) if c != "time"]
            if names
            else self.names
        )
        units = self.units
        meta = dict(self.meta, units={c: units[c] for c in chosen if c in units})
        return Results(chosen, self.data[rows][:, [self._index[c] for c in chosen]], meta)

    def _missing(self, name: str, what: str = "column") -> ColumnError:
        known = self.names + list(self._bases)
        close = difflib.get_close_matches(name, known, n=5, cutoff=0.6)
        if not close:  # the right variable of another instance, or the right instance
            tail = name.split(".")[-1].split("[")[0]
            close = [k for k in self._bases if k.endswith("." + tail)][:5] or sorted(
                {k for k in known if k.split(".")[0] == name.split(".")[0] and "[" not in k}
            )[:8]
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        return ColumnError(f"no {what} {name!r} in these results{hint}")

    def to_pandas(self, deg: bool = False):
        """A ``pandas.DataFrame`` indexed by time (``pip install agilesat[pandas]``); the
        units in ``frame.attrs["units"]``."""
        try:
            import pandas
        except ImportError:
            raise ImportError(
                "Results.to_pandas needs pandas: pip install 'agilesat[pandas]'"
            ) from None
        units = self.units
        columns = [n for n in self.names if n != "time"]
        data = self.data[:, [self._index[c] for c in columns]]
        if deg:
            factors = [to_degrees(units.get(c)) for c in columns]
            data = data * np.array([f for f, _ in factors])
            units = {c: u for c, (_, u) in zip(columns, factors)}
        frame = pandas.DataFrame(data, columns=columns, index=pandas.Index(self.time, name="time"))
        frame.attrs["units"] = {c: units.get(c) for c in columns}
        return frame

    def to_csv(self, path) -> Path:
        """CSV with a header row of column names; the units in :func:`units_path`."""
        path = Path(path)
        with path.open("w", newline="") as stream:
            writer = csv.writer(stream)
            writer.writerow(self.names)
            writer.writerows(self.data.tolist())
        self.write_units(units_path(path))
        return path

    def write_units(self, path) -> Path:
        """{column: unit} as JSON (the sidecar of results.csv)."""
        Path(path).write_text(json.dumps(self.units, indent=1, ensure_ascii=False) + "\n")
        return Path(path)

    def to_npz(self, path) -> Path:
        units = self.units
        np.savez_compressed(
            path,
            names=np.array(self.names),
            data=self.data,
            units=np.array([units.get(n) or "" for n in self.names]),
        )
        return Path(path)

    def to_mat(self, path) -> Path:
        """A MATLAB .mat file (``scipy.io``): ``time`` (N×1)
        and one struct per instance with a field per variable, arrays as N×size matrices
        (``SatelliteDynamics.w_BI_B(:, 2)``); ``units`` the same structs of unit strings."""
        from scipy.io import savemat

        content = {"time": self.time.reshape(-1, 1), "units": {"time": "s"}}
        for name in [n for n in self.names if "." in n and not _ELEMENT.match(n)] + list(
            self._bases
        ):
            instance, variable = name.split(".", 1)
            content.setdefault(instance, {})[variable] = self[name].reshape(len(self), -1)
            content["units"].setdefault(instance, {})[variable] = self.unit(name) or ""
        savemat(path, content, long_field_names=True, do_compression=True)
        return Path(path)

    @classmethod
    def from_csv(cls, path) -> Results:
        """Read a results CSV (and its units sidecar, if there is one)."""
        with Path(path).open() as stream:
            names = next(csv.reader(stream))
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        sidecar = units_path(path)
        meta = {"units": json.loads(sidecar.read_text())} if sidecar.exists() else {}
        return cls(names, data, meta)

    @classmethod
    def from_npz(cls, path) -> Results:
        archive = np.load(path)
        names = [str(n) for n in archive["names"]]
        meta = {}
        if "units" in archive:
            meta["units"] = {n: str(u) for n, u in zip(names, archive["units"]) if str(u)}
        return cls(names, archive["data"], meta)

    @classmethod
    def load(cls, directory) -> Results:
        """The results of a run directory: results.npz, else results.csv.  A
        :class:`ResultsFileError` names the file when it is not a whole run's: one the
        library cannot read (cut, damaged), without a first column ``time`` (not a run's
        of ours), with time not increasing, or with fewer or more rows than the run's
        summary.json says it recorded."""
        directory = Path(directory)
        path = directory / "results.npz"
        if not path.exists():
            path = directory / "results.csv"
        if not path.exists():
            raise FileNotFoundError(
                f"{directory}: no results.npz or results.csv (not a run directory of "
                "`agilesat run`?)"
            )
        read = cls.from_npz if path.suffix == ".npz" else cls.from_csv
        try:
            results = read(path)
        except Exception as exc:  # noqa: BLE001 - what the library says of a damaged file
            raise ResultsFileError(
                f"{path}: not a whole results file ({type(exc).__name__}: {exc}): cut or damaged"
            ) from None
        problem = _not_whole(results, directory / "summary.json")
        if problem:
            raise ResultsFileError(f"{path}: {problem}")
        return results


def per_results(function):
    """Decorator: ``function(results, *args)`` computed once per :class:`Results` and
    ``args`` (hashable), kept by the results (:meth:`Results.derived`); anything else
    given as ``results`` (a campaign's columns) is computed each call."""

    @functools.wraps(function)
    def once(results, *args):
        if not isinstance(results, Results):
            return function(results, *args)
        return results.derived((once, *args), lambda: function(results, *args))

    return once


def _read_only(value):
    """``value`` with its arrays (itself, in a tuple or list, or an object's array
    attributes) made read-only."""
    if isinstance(value, np.ndarray):
        value.flags.writeable = False
    elif isinstance(value, (tuple, list)):
        for item in value:
            _read_only(item)
    elif isinstance(value, dict):
        for item in value.values():
            _read_only(item)
    elif hasattr(value, "__dict__"):
        for item in vars(value).values():
            if isinstance(item, np.ndarray):
                item.flags.writeable = False
    return value


class ResultsFileError(ValueError):
    """A run directory's results file that is not a whole run's (:meth:`Results.load`)."""


def _not_whole(results: Results, summary: Path) -> str:
    """What is wrong with a run's results (read from a file), or ""."""
    if results.names[:1] != ["time"]:
        return (
            f"its first column is {results.names[0]!r}, not 'time': not the results of an "
            "agilesat run (columns time, Instance.variable, ...)"
        )
    t = results.time
    back = np.flatnonzero(~(np.diff(t) > 0))
    if len(back):
        return (
            f"time does not increase from row {back[0] + 1} to {back[0] + 2} (t = "
            f"{t[back[0]]:g} s, then {t[back[0] + 1]:g} s): rows of two runs, or damaged"
        )
    try:
        rows = json.loads(summary.read_text(encoding="utf-8")).get("rows")
    except (OSError, ValueError, AttributeError):
        return ""  # no summary (a killed run's), or not ours: nothing to compare with
    if isinstance(rows, int) and rows != len(results):
        return (
            f"{len(results)} rows, but {summary} says the run recorded {rows}: the file is "
            "cut, or another run's"
        )
    return ""
