"""A run holds its output directory: a second run on the same ``--out`` is refused before
it touches a file there, instead of both writing results.csv and results.npz at once.

The lock is ``flock`` on the directory itself (Linux allows it on a directory's
descriptor): no file is left behind, and the kernel releases it when the process ends,
however it ends (``kill -9`` included), so a lock is never stale.  Re-entrant within a
process (the runner holds it around the master, which holds it around its recorder).
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import threading
from pathlib import Path

_held: dict[Path, list] = {}  # directory -> [descriptor, depth]
_lock = threading.Lock()


class OutputInUse(RuntimeError):
    """Another process is writing the output directory."""


@contextlib.contextmanager
def holding(directory):
    """Hold ``directory`` (created if need be) while inside; OutputInUse if another
    process holds it."""
    directory = Path(directory).resolve()
    directory.mkdir(parents=True, exist_ok=True)
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
                    f"{directory} is being written by another run"
                    + (f" (process {holder})" if holder else "")
                    + ": wait for it to end, or give another --out"
                ) from None
            held = _held[directory] = [descriptor, 0]
        held[1] += 1
    try:
        yield directory
    finally:
        with _lock:
            held[1] -= 1
            if not held[1]:
                del _held[directory]
                os.close(held[0])  # releases the lock


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
