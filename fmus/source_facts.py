"""What the build reads off our modules' sources, parsed once per content.

The FMU registry (``FMUS``: which module defines ``class <Name>(Model)``) and the build's
staleness check (the modules an FMU packs, followed through relative imports) read every
component module with :mod:`ast`: ~0.2 s of each ``agilesat run``, for sources that do not
change between runs.  :func:`facts` parses a source once and keeps what it found in the
cache (``source_facts.json`` under :func:`components.jit.cache_root`), keyed on the
SHA-256 of the source: a changed file is parsed again, an unchanged one never.  The cache
is only a memo: if it cannot be read or written, sources are parsed as before, with the
same answers.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import json
import os
import uuid
from pathlib import Path

#: this module's own content: a changed parser ignores what an older one kept (every
#: checkout and installed version shares the cache)
VERSION = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:16]
#: entries kept (the oldest are dropped): our ~60 modules, each in a few versions
MAX_ENTRIES = 1000


def facts(source: str, filename: str) -> dict:
    """{"classes": [[name, [base names]], ...] (top-level classes), "imports": [[level,
    module, [names]], ...] (relative ``from … import``)} of a module's source."""
    key = hashlib.sha256(source.encode()).hexdigest()
    known = _memo()
    if not _well_formed(known.get(key)):
        known[key] = _parse(source, filename)
        while len(known) > MAX_ENTRIES:
            del known[next(iter(known))]
        _save(known)
    return known[key]


def _parse(source: str, filename: str) -> dict:
    tree = ast.parse(source, filename)
    return {
        "classes": [
            [node.name, [base.id for base in node.bases if isinstance(base, ast.Name)]]
            for node in tree.body
            if isinstance(node, ast.ClassDef)
        ],
        "imports": [
            [node.level, node.module, [alias.name for alias in node.names]]
            for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom) and node.level
        ],
    }


def _well_formed(entry) -> bool:
    """An entry of :func:`_parse`'s shape, down to its strings (the file is anyone's)."""

    def names(value) -> bool:
        return isinstance(value, list) and all(isinstance(n, str) for n in value)

    try:
        return all(
            isinstance(cls, str) and names(bases) for cls, bases in entry["classes"]
        ) and all(
            type(level) is int and (module is None or isinstance(module, str)) and names(imported)
            for level, module, imported in entry["imports"]
        )
    except (TypeError, KeyError, ValueError):  # not a dict, a key missing, a row's length
        return False


def _path() -> Path:
    from ..components.jit import cache_root

    return cache_root() / "source_facts.json"


@functools.cache
def _memo() -> dict:
    """The cache's entries (read once per process; empty if there is none or it is not
    ours)."""
    try:
        data = json.loads(_path().read_text())
    except (OSError, ValueError):
        return {}
    if not isinstance(data, dict) or data.get("version") != VERSION:
        return {}
    known = data.get("facts")
    return dict(known) if isinstance(known, dict) else {}


def _save(known: dict) -> None:
    """Write the entries atomically (a new file renamed over the old: parallel runs
    never read half a file; the last writer wins, and a lost entry is parsed again)."""
    path = _path()
    partial = path.with_name(f"{path.name}.{uuid.uuid4().hex}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        partial.write_text(json.dumps({"version": VERSION, "facts": known}))
        os.replace(partial, path)
    except OSError:  # a memo only: parsed again next time
        with contextlib.suppress(OSError):
            partial.unlink(missing_ok=True)
