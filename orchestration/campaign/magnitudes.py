"""Each run's index magnitudes of the pointing requirements judged over a campaign, made
in the worker that made the run, so that the verdict over the campaign judges them
(:meth:`..pointing.PointingRequirement.judge`) instead of computing every run's error
history and magnitudes again, in one process after the runs (at verification scale the
most of the summary's time and memory).

A requirement's magnitudes ``m[time]`` of a run are those its own verdict on the run
computed (its error history is kept on the run's Results, :meth:`..mission.requirements.
Pointing.run_magnitudes`); the verdict over the campaign stacks them (the magnitudes of
runs computed together are those computed one by one, bit for bit: tests/orchestration/
campaign/test_magnitudes.py).  A t random in Δt requirement's (times × window positions
per run) are not kept: judged from ``signals.npy`` as before.

Kept in ``magnitudes/<name>-<key>.npy``, float64 (runs, 1 + times): column 0 is 1 once
the row is written (a row never written reads 0: its disk blocks are taken when the file
is made, nothing written), the rest the run's magnitudes; a row is written before the
run's signals, so every run whose kept signals reached the end has its row, unless it was
made without one (an older campaign; a requirement changed: ``key`` hashes the
requirement's definition, so a changed one has a file of its own).  Where a run that
reached the end has no row, or the first such run's row is not what its signals give,
the verdict computes every run's magnitudes from ``signals.npy`` instead
(:meth:`Store.stacked`: None).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

FOLDER = "magnitudes"


def kept_for(requirements) -> list:
    """The requirements of ``requirements`` (judged over the campaign) whose runs'
    magnitudes are kept: the pointing ones with one value per run and time."""
    from ..mission.requirements import Pointing

    return [
        r
        for r in requirements
        if isinstance(r, Pointing) and r.requirement.t_in_window != "random"  # type: ignore[attr-defined]
    ]


def key(requirement) -> str:
    """12 hex digits of the SHA-256 of ``requirement``'s definition (a function by its
    module and name)."""

    def text(value) -> str:
        if callable(value):
            return f"{getattr(value, '__module__', '')}.{getattr(value, '__qualname__', value)}"
        return repr(value)

    fields = {n: getattr(requirement, n) for n in requirement.__dataclass_fields__}
    fields.pop("origin", None)
    return hashlib.sha256(
        text(sorted((n, text(v)) for n, v in fields.items())).encode()
    ).hexdigest()[:12]


def run_rows(requirements, results) -> dict[str, np.ndarray]:
    """In a worker: {name: m[time]} of the run's ``results`` for each requirement of
    :func:`kept_for` ``requirements`` it can be evaluated on (one that cannot, or that
    raises, has none: the verdict over the campaign computes its magnitudes from
    ``signals.npy``, and says what is wrong there)."""
    rows = {}
    for r in kept_for(requirements):
        try:
            rows[r.name] = r.run_magnitudes(results)[1][0]
        except Exception:  # noqa: BLE001 - the run's record says it; the verdict computes them
            continue
    return rows


def _allocated(path: Path, size: int) -> None:
    """The disk blocks of ``path``'s ``size`` bytes taken now (they read as zeros): a
    write through the memory map to a sparse file on a full disk would kill the process
    (SIGBUS) instead of raising."""
    from ..output.recorder import file_error

    fd = os.open(path, os.O_RDWR)
    try:
        os.posix_fallocate(fd, 0, size)
    except OSError as exc:
        raise file_error(path, exc, f" ({size / 2**30:.3g} GiB of magnitudes)") from None
    finally:
        os.close(fd)


class Store:
    """The ``magnitudes/`` folder of a campaign's directory ``out`` with ``total`` runs."""

    def __init__(self, out: Path, requirements, total: int):
        self.folder, self.total = Path(out) / FOLDER, total
        self.keys = {r.name: key(r) for r in kept_for(requirements)}
        self.files: dict = {}

    def put(self, index: int, rows: dict) -> None:
        """Run ``index``'s rows (before its signals are written)."""
        for name, row in rows.items():
            if name not in self.keys:
                continue
            memory = self._file(name, row.size)
            memory[index, 1:] = row
            memory[index, 0] = 1.0

    def flush(self) -> None:
        for memory in self.files.values():
            memory.flush()

    def _path(self, name: str) -> Path:
        return self.folder / f"{name}-{self.keys[name]}.npy"

    def _file(self, name: str, size: int):
        """The memory map of ``name``'s file for rows of ``size`` magnitudes."""
        memory = self.files.get(name)
        if memory is None or memory.shape[1] != size + 1:
            memory = self.files[name] = self._opened(name, size)
        return memory

    def _opened(self, name: str, size: int):
        path, shape = self._path(name), (self.total, size + 1)
        old = np.load(path, mmap_mode="r") if path.exists() else None
        if old is not None and old.shape[0] >= shape[0] and old.shape[1] == shape[1]:
            memory = np.load(path, mmap_mode="r+")
        else:  # none yet, or fewer runs (the campaign extended) or other times: made anew
            kept = None if old is None or old.shape[1] != shape[1] else np.array(old)
            del old
            self.folder.mkdir(exist_ok=True)
            memory = np.lib.format.open_memmap(path, mode="w+", dtype=np.float64, shape=shape)
            _allocated(path, memory.offset + memory.nbytes)
            if kept is not None:
                memory[: len(kept)] = kept
        return memory

    def stacked(self, name: str, complete: np.ndarray) -> np.ndarray | None:
        """m[run, time] of the runs where ``complete`` (a boolean per run), or None where
        one of them has no row."""
        path = self._path(name) if name in self.keys else None
        if path is None or not path.exists() or not complete.any():
            return None
        memory = np.load(path, mmap_mode="r")
        if memory.shape[0] < complete.size:
            return None
        rows = np.asarray(memory[: complete.size][complete])
        return rows[:, 1:] if np.all(rows[:, 0] == 1.0) else None
