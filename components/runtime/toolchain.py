"""The C compiler, and files written atomically: what the FMU build (the shim), the
master's compiled loop and the cache share."""

from __future__ import annotations

import contextlib
import os
import shutil
import uuid
from collections.abc import Iterator
from pathlib import Path


def c_compiler() -> str | None:
    """The C compiler: $CC, else cc or gcc on the PATH (None: none found)."""
    return os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")


def partial(target: Path) -> Path:
    """A temporary name beside ``target``, unique to this process and call."""
    return target.with_name(f".{target.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.partial")


@contextlib.contextmanager
def replacing(target: Path) -> Iterator[Path]:
    """``with replacing(target) as path:`` write ``path`` (a :func:`partial` name); at the
    block's end it is renamed to ``target`` in one step, so that a reader (another process,
    parallel builds) never sees a torn file.  Removed instead if the block raises."""
    path = partial(target)
    try:
        yield path
        os.replace(path, target)
    finally:
        path.unlink(missing_ok=True)
