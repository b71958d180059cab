"""Recording a run's rows as they come: memory independent of the run length.

With an output directory every row goes to disk at once, as one ``os.write`` of whole lines:
text to ``results.csv`` and raw float64 to a scratch file ``.results.f64`` beside it (the
compiled loop hands over its rows a chunk of a few milliseconds at a time,
:meth:`Recorder.append_block`, written the same way).  A process that is killed (even
``kill -9``) loses at most the rows being written, and the CSV never ends in a torn row:
a short write (disk full) is cut back to the last whole row, in both files, and the error
names the file.  :meth:`Recorder.close` (also after a failure or
an interrupt) writes ``results.npz`` from the raw rows in chunks, under a temporary name
renamed when complete, and hands back :class:`Results` that map the raw rows from disk
(copy-on-write: the caller may modify them) instead of holding them in memory.

Without an output directory the caller gets the rows in memory: a buffer of the rows
``expected`` (the run's, from its plan: filled once, handed over without a copy), grown by
doubling if more come.

A recording replaces an earlier run's records in its directory: as it starts it truncates
``results.csv`` and removes the files that describe those rows (:data:`REPLACED`), so a
run killed before it writes its own leaves none of another run's beside its rows.

A run may record some of the columns (``keep``) at every ``every``-th communication point:
the rows offered are numbered from 0, and row n is recorded when n is a multiple of
``every``.
"""

from __future__ import annotations

import contextlib
import errno
import os
import zipfile
from functools import partial
from pathlib import Path

import numpy as np

from .results import Results

RAW = ".results.f64"
#: what an earlier run left that describes its rows: a recording in the same directory
#: removes them as it starts (results.csv it truncates)
REPLACED = ("results.npz", "results.units.json", "summary.json", "log.txt")


class Recorder:
    """Rows of ``columns`` (time first) recorded one communication point at a time
    (``expected``: how many will be, if known: the memory for them at once)."""

    def __init__(
        self, columns: list[str], out_dir=None, keep=None, every: int = 1, expected: int = 64
    ):
        self.keep = None if keep is None else np.asarray(keep, dtype=np.intp)
        self.columns = [columns[k] for k in keep] if keep is not None else list(columns)
        self.every, self.offered, self.rows = every, 0, 0
        self.out_dir = None if out_dir is None else Path(out_dir)
        self._memory = np.empty((max(1, expected) if out_dir is None else 0, len(self.columns)))
        self._files = []
        if self.out_dir is not None:
            for old in (self.out_dir / name for name in REPLACED):  # none beside these rows
                _checked(old, partial(old.unlink, missing_ok=True))
            header = (",".join(map(_csv_field, self.columns)) + "\n").encode()
            self.csv = _File(self.out_dir / "results.csv", header)
            # its errors name the file a person knows: results.csv, whose rows it holds
            self.raw = _File(self.out_dir / RAW, b"", self.out_dir / "results.csv")
            self._files = [self.raw, self.csv]

    def append(self, row: np.ndarray) -> None:
        """Record one row; an OSError (disk full) names the file and keeps every whole row."""
        self.offered += 1
        if (self.offered - 1) % self.every:
            return
        if self.keep is not None:
            row = row[self.keep]
        self._append(row)

    def _append(self, row: np.ndarray) -> None:
        if not self._files:
            if self.rows == len(self._memory):
                self._memory = np.concatenate([self._memory, np.empty_like(self._memory)])
            self._memory[self.rows] = row
        else:
            self.raw.write(np.ascontiguousarray(row, dtype="<f8").tobytes(), self.rows)
            try:
                self.csv.write((",".join(map(repr, row.tolist())) + "\n").encode(), self.rows)
            except OSError:
                self.raw.truncate()
                raise
            self.raw.commit()
            self.csv.commit()
        self.rows += 1

    def append_block(self, rows: np.ndarray, text: bytes | None = None) -> None:
        """Record several rows at once, as :meth:`append` would one by one (a failed write
        is retried row by row: every whole row that fits is kept).  ``text``: their CSV
        lines as :meth:`append` writes them, if the caller has them already."""
        offered = len(rows)
        if self.keep is not None or self.every > 1:
            rows = rows[(self.offered + np.arange(offered)) % self.every == 0]
            rows = rows if self.keep is None else rows[:, self.keep]
            text = None
        self.offered += offered
        if not len(rows):
            return
        if not self._files:
            while self.rows + len(rows) > len(self._memory):
                self._memory = np.concatenate([self._memory, np.empty_like(self._memory)])
            self._memory[self.rows : self.rows + len(rows)] = rows
            self.rows += len(rows)
            return
        if text is None:
            text = "".join(",".join(map(repr, row)) + "\n" for row in rows.tolist()).encode()
        try:
            self.raw.write(np.ascontiguousarray(rows, dtype="<f8").tobytes(), self.rows)
            try:
                self.csv.write(text, self.rows)
            except OSError:
                self.raw.truncate()
                raise
        except OSError:
            for row in rows:
                self._append(row)
            return
        self.raw.commit()
        self.csv.commit()
        self.rows += len(rows)

    def close(self, meta: dict) -> tuple[Results, list[str]]:
        """(the rows recorded, problems writing the files); writes results.npz."""
        if not self._files:
            rows = self._memory[: self.rows]
            full = self.rows == len(self._memory)  # as ``expected``: the buffer is the rows
            return Results(self.columns, rows if full else rows.copy(), meta), []
        assert self.out_dir is not None  # files are only written into an output directory
        problems = []
        for f in self._files:
            f.close()
        results = Results(self.columns, _map(self.raw.path, self.rows, len(self.columns)), meta)
        try:
            write_npz(
                self.out_dir / "results.npz",
                self.columns,
                self.raw.path,
                self.rows,
                [results.units.get(n) or "" for n in self.columns],
            )
        except OSError as exc:
            problems.append(str(exc))
        self.raw.path.unlink(missing_ok=True)  # mapped already (POSIX keeps the pages)
        return results, problems


class _File:
    """An append-only file written in whole records with os.write; its errors name
    ``said`` (default ``path``), and ``path`` after it if they differ."""

    def __init__(self, path: Path, header: bytes, said: Path | None = None):
        self.path = path
        self.said = said or path
        self.fd = _checked(
            path, lambda: os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        )
        self.size = 0  # bytes of whole records
        self.write(header, 0)
        self.commit()

    def write(self, data: bytes, rows: int) -> None:
        self.pending = self.size + len(data)
        view = memoryview(data)
        try:
            while view:
                view = view[os.write(self.fd, view) :]
        except OSError as exc:
            self.truncate()
            also = "" if self.said == self.path else f" (writing its rows to {self.path.name})"
            raise file_error(
                self.said, exc, f"{also}; kept the {rows} complete rows written before"
            ) from None

    def commit(self) -> None:
        self.size = self.pending

    def truncate(self) -> None:
        """Back to the last whole record (a torn one is cut off)."""
        try:
            os.ftruncate(self.fd, self.size)
            os.lseek(self.fd, self.size, os.SEEK_SET)
        except OSError:
            pass

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


def file_error(path, exc: OSError, note: str = "") -> OSError:
    """An OSError whose message starts with the file's name."""
    error = OSError(f"{path}: {exc.strerror or exc}{note}")
    error.errno = exc.errno
    return error


def write_text(path: Path, text: str) -> None:
    """Write under a temporary name, then rename (:func:`atomically`)."""
    with atomically(path) as temporary:
        temporary.write_text(text, encoding="utf-8")


@contextlib.contextmanager
def atomically(path: Path):
    """A temporary name beside ``path`` to write, renamed to ``path`` when the block ends
    (a kill leaves the old file or the new, never half of one); on an OSError (a full
    disk, a read-only directory) the temporary is removed and the error names ``path``."""
    path = Path(path)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        yield temporary
        os.replace(temporary, path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            temporary.unlink(missing_ok=True)
        raise file_error(path, exc, "; not written") from None


def make_directory(path: Path) -> Path:
    """``path`` created (with its parents) if need be; an OSError names it."""
    try:
        Path(path).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise file_error(path, exc, " (the output directory: it cannot be created)") from None
    return Path(path)


def _checked(path, action):
    try:
        return action()
    except OSError as exc:
        raise file_error(path, exc) from None


def _csv_field(name: str) -> str:
    """A header field as CSV has it: quoted when it holds a comma (``los_B[1,2]``)."""
    return '"' + name.replace('"', '""') + '"' if "," in name or '"' in name else name


def _map(raw: Path, rows: int, n: int) -> np.ndarray:
    if rows == 0:
        return np.empty((0, n))
    return np.memmap(raw, dtype="<f8", mode="c", shape=(rows, n))


def write_npz(
    path: Path, names: list[str], raw: Path, rows: int, units: list[str], chunk: int = 1 << 20
) -> None:
    """results.npz (``names``, ``data``, ``units`` as :meth:`Results.to_npz` writes them) from
    the raw float64 rows in ``raw``, copied in chunks; written to a temporary name, then
    renamed."""
    n = len(names)
    with atomically(path) as temporary:
        with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED, allowZip64=True) as archive:
            with archive.open("names.npy", "w") as stream:
                np.lib.format.write_array(stream, np.array(names))
            with archive.open("units.npy", "w") as stream:
                np.lib.format.write_array(stream, np.array(units))
            with (
                archive.open("data.npy", "w", force_zip64=True) as stream,
                open(raw, "rb") as source,
            ):
                np.lib.format.write_array_header_1_0(
                    stream, {"descr": "<f8", "fortran_order": False, "shape": (rows, n)}
                )
                left = rows * n * 8
                while left:
                    block = source.read(min(chunk, left))
                    if not block:
                        raise OSError(errno.EIO, f"{raw}: shorter than {rows} rows")
                    stream.write(block)
                    left -= len(block)
