"""agilesat's cache directory, and its entries sealed so that a damaged file never passes.

Everything in the cache (:func:`cache_root`: unpacked FMUs and their compiled Python, the
compiled master loop, numba's compiled kernels) is written under a temporary name and
renamed (:func:`.toolchain.replacing`), so a process killed while writing never leaves a
torn entry.  A file damaged
afterwards (a disk error, a truncation, an edit) would still be loaded, and loading bad
machine code or bytecode crashes the process.  So each entry carries the SHA-256 of what
was written, checked before anything is loaded from it:

- a file: ``seal`` puts the digest in front of the bytes, ``unseal`` gives them back only
  if they match (numba's index and data files, :mod:`.jit`);
- a file that must stay as it is (a shared library): its digest beside it, in
  ``<name>.sha256`` (:func:`write_digest`, :func:`damage_of_file`);
- a directory (an unpacked FMU): a manifest of every file's digest, ``MANIFEST``
  (:func:`write_manifest`, :func:`damage_of_tree`).

A damaged entry is rebuilt with a warning naming it (:func:`warn`).
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from pathlib import Path

from .switches import value
from .toolchain import replacing

MANIFEST = ".agilesat-manifest.json"
_DIGEST = 32


def cache_root() -> Path:
    """agilesat's cache: $AGILESAT_CACHE_DIR, else $XDG_CACHE_HOME/agilesat, else
    ~/.cache/agilesat (kernels in ``numba/``, the master's loop in ``loop/``, unpacked FMUs
    in ``fmus/``)."""
    root = value("AGILESAT_CACHE_DIR")
    if root:
        return Path(root)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base, "agilesat")


def digest(path) -> str:
    """The SHA-256 of a file (hex)."""
    sha = hashlib.sha256()
    with open(path, "rb") as stream:
        for chunk in iter(lambda: stream.read(1 << 20), b""):
            sha.update(chunk)
    return sha.hexdigest()


def seal(body: bytes) -> bytes:
    return hashlib.sha256(body).digest() + body


def unseal(data: bytes) -> bytes | None:
    """The body of sealed ``data``, or None if it is not what was sealed."""
    body = data[_DIGEST:]
    intact = len(data) >= _DIGEST and hashlib.sha256(body).digest() == data[:_DIGEST]
    return body if intact else None


def write_digest(path: Path, content: Path) -> None:
    """``<path>.sha256``: the digest of the file ``content`` (written atomically, before
    ``content`` is renamed to ``path``)."""
    with replacing(Path(f"{path}.sha256")) as partial:
        partial.write_text(digest(content) + "\n")


def damage_of_file(path: Path) -> str:
    """'' if ``path`` is what its ``.sha256`` says, else what is wrong."""
    try:
        recorded = Path(f"{path}.sha256").read_text().strip()
    except OSError:
        return "its SHA-256 (.sha256) is missing"
    return "" if digest(path) == recorded else "its content does not match its SHA-256"


def write_manifest(root: Path) -> None:
    """``root/MANIFEST``: the digest of every file under ``root``."""
    files = {
        path.relative_to(root).as_posix(): digest(path)
        for path in sorted(root.rglob("*"))
        if path.is_file() and path.name != MANIFEST
    }
    (root / MANIFEST).write_text(json.dumps(files, indent=0) + "\n")


def damage_of_tree(root: Path) -> str:
    """'' if every file ``root``'s manifest lists is there as listed, else what is not.
    (Files it does not list, such as bytecode Python writes later, are not checked.)"""
    try:
        files = json.loads((root / MANIFEST).read_text())
        if not isinstance(files, dict):
            raise ValueError("not an object")
    except (OSError, ValueError) as exc:
        return f"its manifest {MANIFEST} is unreadable ({exc})"
    for name, recorded in files.items():
        try:
            if digest(root / name) != recorded:
                return f"{name} does not match its SHA-256"
        except OSError:
            return f"{name} is missing"
    return ""


def warn(entry, what: str, action: str = "rebuilding it") -> None:
    """The one warning about a damaged cache entry."""
    warnings.warn(f"agilesat: the cache entry {entry} is damaged ({what}): {action}", stacklevel=3)
