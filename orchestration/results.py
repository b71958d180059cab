"""Results of a run: one row per communication point, one named column per variable.

Columns are ``time`` and ``<instance>.<variable>`` (e.g. ``SatelliteDynamics.q_BI[1]``).
Written as CSV (``results.csv``) and as NumPy's binary ``.npz``.  While a run is going,
:mod:`.recorder` appends each row to the CSV, so a run that fails (or is killed) leaves
everything recorded up to the failure on disk.
"""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np


class Results:
    def __init__(self, names: list[str], data: np.ndarray, meta: dict | None = None):
        if data.ndim != 2 or data.shape[1] != len(names):
            raise ValueError(f"data {data.shape} does not match {len(names)} columns")
        self.names = list(names)
        self.data = data
        self.meta = dict(meta or {})
        self._index = {n: i for i, n in enumerate(self.names)}

    @property
    def time(self) -> np.ndarray:
        return self.data[:, self._index["time"]]

    def __len__(self):
        return self.data.shape[0]

    def __contains__(self, name):
        return name in self._index

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.data[:, self._index[name]]
        except KeyError:
            raise KeyError(f"no column {name!r}; columns like it: "
                           f"{[n for n in self.names if name.split('[')[0] in n][:8]}") from None

    def vector(self, name: str) -> np.ndarray:
        """All elements of an array variable as an (N, size) array: vector('X.w_BI_B')."""
        columns = [i for n, i in self._index.items()
                   if n.startswith(name + "[") and n.endswith("]")]
        if not columns:
            raise KeyError(f"no array variable {name!r}")
        return self.data[:, columns]

    def to_csv(self, path) -> Path:
        path = Path(path)
        with path.open("w", newline="") as stream:
            writer = csv.writer(stream)
            writer.writerow(self.names)
            writer.writerows(self.data.tolist())
        return path

    def to_npz(self, path) -> Path:
        np.savez_compressed(path, names=np.array(self.names), data=self.data)
        return Path(path)

    @classmethod
    def from_csv(cls, path) -> Results:
        with Path(path).open() as stream:
            names = next(csv.reader(stream))
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        return cls(names, data)

    @classmethod
    def from_npz(cls, path) -> Results:
        archive = np.load(path)
        return cls(list(archive["names"]), archive["data"])

