"""A system file read once per content, for runs that repeat (a campaign's worker, a pytest
session): :func:`system_file`."""

from __future__ import annotations

import hashlib
import threading
from pathlib import Path

from lxml import etree

from .ssp import NS, SystemFile, read_system

_systems: dict[tuple, SystemFile] = {}  # content key -> the system read from it
_systems_lock = threading.Lock()
_SYSTEMS_KEPT = 8


def system_file(path) -> SystemFile:
    """:func:`read_system` once per content: a run of a campaign worker (or any repeated
    run) takes the system read before when the file, and every ``.ssv`` file its parameter
    bindings name, hold the same bytes (SHA-256; an edited file is read again).  Reading
    and checking an ``.ssd`` against the SSP schema takes about as long as the first 2 s
    of a scan_pitch run; the systems of the last :data:`_SYSTEMS_KEPT` contents are kept
    (an ``.ssp``'s with its unpacked FMUs)."""
    path = Path(path).resolve()
    key = _content_key(path)
    if key is None:
        return read_system(path)  # which says what is wrong
    with _systems_lock:
        system = _systems.get(key)
    if system is None:
        system = read_system(path)
        with _systems_lock:
            if len(_systems) >= _SYSTEMS_KEPT:
                _systems.pop(next(iter(_systems)))
            _systems[key] = system
    return system


def _content_key(path: Path) -> tuple | None:
    """(path, SHA-256 of its bytes and of each .ssv it binds); None if a file is missing
    or the XML malformed."""
    try:
        data = path.read_bytes()
    except OSError:
        return None
    key = [str(path), hashlib.sha256(data).hexdigest()]
    if path.suffix != ".ssp":  # an .ssp holds its .ssv files
        try:
            root = etree.fromstring(data)
        except etree.XMLSyntaxError:
            return None
        for binding in root.iterfind(".//ssd:ParameterBinding[@source]", NS):
            ssv = (path.parent / binding.get("source")).resolve()
            try:
                key.append(hashlib.sha256(ssv.read_bytes()).hexdigest())
            except OSError:
                return None
    return tuple(key)
