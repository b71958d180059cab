"""A run or a campaign holds its output directory: a second one on the same ``--out`` is
refused before it touches a file there, instead of both writing results.csv and results.npz
(or a campaign's journal and summary) at once.

The lock is ``flock`` on the directory itself (Linux allows it on a directory's
descriptor): no file is left behind, and the kernel releases it when the process ends,
however it ends (``kill -9`` included), so a lock is never stale.  Re-entrant within a
process (the runner holds it around the master, which holds it around its recorder).

What a process killed while it held the directory (``kill -9``, a power cut) leaves there
besides its records: the raw rows' scratch file (``.results.f64``) and the temporary files
written files are renamed from (``.NAME.PID.partial``).  The next process to hold the
directory removes them, saying so on stderr: nobody else can be writing them.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import re
import sys
import threading
from pathlib import Path

from .recorder import RAW, make_directory

_held: dict[Path, list] = {}  # directory -> [descriptor, depth]
_lock = threading.Lock()
_PARTIAL = re.compile(r"^\.[^/]+\.\d+\.partial$")  # recorder.write_text's temporary names


class OutputInUse(RuntimeError):
    """Another process is writing the output directory."""


@contextlib.contextmanager
def holding(directory):
    """Hold ``directory`` (created if need be) while inside; OutputInUse if another
    process holds it."""
    directory = make_directory(Path(directory).resolve())
    with _lock:
        held = _held.get(directory)
        if held is None:
            descriptor = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
            try:
                fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                os.close(descriptor)
                holder = _holder(directory)
                raise OutputInUse(
                    f"{directory} is being written by another run or campaign"
                    + (f" (process {holder}{_command(holder)})" if holder else "")
                    + ": wait for it to end, or give another --out"
                ) from None
            held = _held[directory] = [descriptor, 0]
            _remove_leftovers(directory)
        held[1] += 1
    try:
        yield directory
    finally:
        with _lock:
            held[1] -= 1
            if not held[1]:
                del _held[directory]
                os.close(held[0])  # releases the lock


def _remove_leftovers(directory: Path) -> None:
    """The scratch and temporary files of a killed process (module docstring)."""
    found = [p for p in directory.iterdir() if p.name == RAW or _PARTIAL.match(p.name)]
    for path in found:
        path.unlink(missing_ok=True)
    if found:
        print(
            f"agilesat: removed what a killed run or campaign left in {directory}: "
            + ", ".join(sorted(p.name for p in found)),
            file=sys.stderr,
        )


def _holder(directory: Path) -> str:
    """The process holding the lock on ``directory``, from /proc/locks ('' if unknown)."""
    stat = os.stat(directory)
    inode = f"{os.major(stat.st_dev):02x}:{os.minor(stat.st_dev):02x}:{stat.st_ino}"
    try:
        for line in Path("/proc/locks").read_text().splitlines():
            fields = line.split()
            if len(fields) > 5 and fields[1] == "FLOCK" and fields[5] == inode:
                return fields[4]
    except OSError:
        pass
    return ""


def _command(pid: str) -> str:
    """': the command line' of process ``pid`` ('' where it cannot be read)."""
    try:
        words = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:
        return ""
    text = " ".join(" ".join(w.decode(errors="replace") for w in words).split())
    return f": {text[:120]}{'...' * (len(text) > 120)}" if text else ""
