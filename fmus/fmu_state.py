"""FMU states as data: a versioned, self-describing binary format, validated on the way in.

A host hands ``fmi2DeSerializeFMUstate`` arbitrary bytes, so decoding them must never run
code (no pickle: a crafted pickle executes anything).  Layout, little-endian::

    b"AGILESAT-FMU-STATE" u16 version  str identity  u64 payload length  payload  [NUL padding]

``identity`` names the FMU (its packed package, which carries the content hash the GUID
is derived from, and the class): a state of another FMU, or of another build of it, is
refused.  The payload is one value, a tag byte then its body:

    N None   T True   F False   i int64   f float64   s str (u32 length, UTF-8)
    l list / t tuple / z frozenset / d dict: u32 count, then the items (dict: key, value)
    a ndarray: dtype (str, one of _DTYPES), u8 ndim, u64 dims, raw C-order bytes
    g numpy scalar: dtype, raw bytes     S slice: start, stop, step
    o object of one of the FMU's own plain classes: module (str), class name (str),
      attribute dict; rebuilt without running any constructor (``object.__new__`` and the
      instance dict), and only for a class already imported from the FMU's own package.

Every length is checked against the bytes left, nesting is limited, and any error gives
:class:`StateError` with the reason.
"""

from __future__ import annotations

import struct
import sys

import numpy as np

MAGIC = b"AGILESAT-FMU-STATE"
VERSION = 1
_MAX_DEPTH = 64
_DTYPES = {
    np.dtype(d).str: np.dtype(d)
    for d in ("<f8", "<f4", "<i8", "<i4", "<i2", "|i1", "<u8", "<u4", "<u2", "|u1", "|b1", "<c16")
}


class StateError(ValueError):
    """The bytes are not a state of this FMU."""


def encode(identity: str, value, package: str) -> bytes:
    """The bytes of ``value`` (raises StateError for a type the format does not hold);
    objects only of classes of the module prefix ``package``."""
    out = bytearray()
    _encode(value, out, 0, package)
    head = bytearray(MAGIC + struct.pack("<H", VERSION))
    _string(identity, head)
    return bytes(head + struct.pack("<Q", len(out)) + out)


def decode(identity: str, data: bytes, package: str):
    """The value in ``data``, checked to be a state of the FMU ``identity``; objects only of
    classes of the module prefix ``package``."""
    reader = _Reader(memoryview(data), package)
    if bytes(reader.take(len(MAGIC))) != MAGIC:
        raise StateError("not an agilesat FMU state (bad magic bytes)")
    (version,) = reader.unpack("<H")
    if version != VERSION:
        raise StateError(f"state format version {version}, this FMU reads version {VERSION}")
    theirs = reader.string()
    if theirs != identity:
        raise StateError(f"a state of FMU {theirs!r}, not of this FMU {identity!r}")
    (length,) = reader.unpack("<Q")
    if length > reader.left():
        raise StateError(f"truncated: the payload is {length} bytes, {reader.left()} given")
    end = reader.pos + length
    try:
        value = reader.value(0)
    except StateError:
        raise
    except (ValueError, TypeError, OverflowError, MemoryError, RecursionError) as exc:
        raise StateError(f"malformed payload near byte {reader.pos}: {exc}") from None
    if reader.pos != end:
        raise StateError("the payload length does not match its content")
    if any(bytes(reader.data[end:])):
        raise StateError(f"{len(data) - end} trailing bytes after the state")
    return value


def _string(text: str, out: bytearray) -> None:
    raw = text.encode()
    out += struct.pack("<I", len(raw)) + raw


def _encode(x, out: bytearray, depth: int, package: str) -> None:
    if depth > _MAX_DEPTH:
        raise StateError("state nested too deeply")
    if x is None:
        out += b"N"
    elif x is True or x is False:
        out += b"T" if x else b"F"
    elif type(x) is int:
        out += b"i" + struct.pack("<q", x)
    elif type(x) is float:
        out += b"f" + struct.pack("<d", x)
    elif type(x) is str:
        out += b"s"
        _string(x, out)
    elif type(x) in (list, tuple, frozenset, dict):
        out += {list: b"l", tuple: b"t", frozenset: b"z", dict: b"d"}[type(x)]
        out += struct.pack("<I", len(x))
        for item in x.items() if type(x) is dict else x:
            for part in item if type(x) is dict else (item,):
                _encode(part, out, depth + 1, package)
    elif type(x) is np.ndarray and x.dtype.str in _DTYPES:
        out += b"a"
        _string(x.dtype.str, out)
        out += struct.pack(f"<B{x.ndim}Q", x.ndim, *x.shape) + np.ascontiguousarray(x).tobytes()
    elif isinstance(x, np.generic) and x.dtype.str in _DTYPES:
        out += b"g"
        _string(x.dtype.str, out)
        out += x.tobytes()
    elif type(x) is slice:
        out += b"S"
        for part in (x.start, x.stop, x.step):
            _encode(part, out, depth + 1, package)
    elif (
        type(x).__module__.startswith(package + ".")
        and _plain_class(type(x))
        and hasattr(x, "__dict__")
    ):
        out += b"o"
        _string(type(x).__module__, out)
        _string(type(x).__qualname__, out)
        _encode(dict(vars(x)), out, depth + 1, package)
    else:
        raise StateError(
            f"cannot store a {type(x).__module__}.{type(x).__qualname__} in an FMU state"
        )


def _plain_class(cls) -> bool:
    """A class whose instances are plain data: no custom construction or pickling hooks."""
    return (
        cls.__new__ is object.__new__
        and "__setstate__" not in vars(cls)
        and "__reduce__" not in vars(cls)
        and "__reduce_ex__" not in vars(cls)
        and "__slots__" not in vars(cls)
    )


class _Reader:
    def __init__(self, data: memoryview, package: str):
        self.data, self.pos, self.package = data, 0, package

    def left(self) -> int:
        return len(self.data) - self.pos

    def take(self, n: int) -> memoryview:
        if n > self.left():
            raise StateError(f"truncated at byte {self.pos}: {n} bytes needed, {self.left()} left")
        chunk = self.data[self.pos : self.pos + n]
        self.pos += n
        return chunk

    def unpack(self, fmt: str):
        return struct.unpack(fmt, self.take(struct.calcsize(fmt)))

    def string(self) -> str:
        (n,) = self.unpack("<I")
        try:
            return bytes(self.take(n)).decode()
        except UnicodeDecodeError as exc:
            raise StateError(f"invalid UTF-8 in a string: {exc}") from None

    def dtype(self) -> np.dtype:
        name = self.string()
        if name not in _DTYPES:
            raise StateError(f"array type {name!r} is not allowed")
        return _DTYPES[name]

    def value(self, depth: int):
        if depth > _MAX_DEPTH:
            raise StateError("state nested too deeply")
        tag = bytes(self.take(1))
        if tag in (b"N", b"T", b"F"):
            return {b"N": None, b"T": True, b"F": False}[tag]
        if tag == b"i":
            return self.unpack("<q")[0]
        if tag == b"f":
            return self.unpack("<d")[0]
        if tag == b"s":
            return self.string()
        if tag in (b"l", b"t", b"z", b"d"):
            (n,) = self.unpack("<I")
            if n > self.left():
                raise StateError(f"a container of {n} items in {self.left()} bytes")
            if tag == b"d":
                items = [(self.value(depth + 1), self.value(depth + 1)) for _ in range(n)]
                return self._hashed(dict, items)
            items = [self.value(depth + 1) for _ in range(n)]
            return (
                self._hashed(frozenset, items)
                if tag == b"z"
                else tuple(items)
                if tag == b"t"
                else items
            )
        if tag == b"a":
            dtype = self.dtype()
            (ndim,) = self.unpack("<B")
            if ndim > 32:
                raise StateError(f"an array of {ndim} dimensions")
            shape = self.unpack(f"<{ndim}Q")
            count = 1
            for n in shape:
                count *= n
            if count * dtype.itemsize > self.left():
                raise StateError(f"an array of shape {shape} in {self.left()} bytes")
            raw = self.take(count * dtype.itemsize)
            return np.frombuffer(raw, dtype=dtype).reshape(shape).copy()
        if tag == b"g":
            dtype = self.dtype()
            return np.frombuffer(self.take(dtype.itemsize), dtype=dtype)[0]
        if tag == b"S":
            parts = [self.value(depth + 1) for _ in range(3)]
            if not all(p is None or type(p) is int for p in parts):
                raise StateError("a slice of non-integers")
            return slice(*parts)
        if tag == b"o":
            cls = self._class(self.string(), self.string())
            fields = self.value(depth + 1)
            if type(fields) is not dict or not all(type(k) is str for k in fields):
                raise StateError(
                    f"the attributes of a {cls.__qualname__} must be a dict keyed by name"
                )
            obj = object.__new__(cls)
            vars(obj).update(fields)
            return obj
        raise StateError(f"unknown tag {tag!r} at byte {self.pos - 1}")

    def _class(self, module: str, name: str):
        """One of the FMU's own plain classes, already imported (nothing is imported)."""
        if not module.startswith(self.package + "."):
            raise StateError(f"class {module}.{name} is not one of this FMU's")
        cls = getattr(sys.modules.get(module), name, None)
        if not isinstance(cls, type) or cls.__module__ != module or not _plain_class(cls):
            raise StateError(f"class {module}.{name} is not a plain data class of this FMU")
        return cls

    @staticmethod
    def _hashed(kind, items):
        try:
            return kind(items)
        except TypeError as exc:
            raise StateError(f"unhashable key or set item: {exc}") from None
