"""Time and two-line element sets: UTC epochs, Greenwich mean sidereal time, TLE checks.

An epoch is an ISO 8601 UTC string, "YYYY-MM-DDTHH:MM:SS[.ffffff]" with an optional
trailing "Z" (or a datetime).  The Earth rotation angle θ_E(t) used by
:class:`.orbit.OrbitEnvironment` with an epoch is the Greenwich mean sidereal time of
epoch + t, IAU-82
(Vallado, 4th ed., eq. 3-47), with T = Julian centuries of UT1 from J2000.0 (2000-01-01
12:00:00 UT1, JD 2451545.0)::

    θ_GMST = 67310.54841 s + (876600 h + 8640184.812866 s) T + 0.093104 s T² − 6.2e-6 s T³

(seconds of time; 86400 s = 2π).  The (876600 h) T term is 86400 s per elapsed day, i.e.
whole turns plus the time of day, which is how it is evaluated here (no precision lost
in 3.2e9 T), and the change from t = 0 is evaluated on its own so that θ_E(t) is smooth
to ≈ 1e-15 rad.  θ̇_E is the exact time derivative of this polynomial (7.2921158553e-5
rad/s in 2016, ω_E + 8.6e-12).  **UT1 is taken equal to UTC** (|UT1 − UTC| < 0.9 s,
i.e. < 6.6e-5 rad of Earth angle, < 0.42 km on the equator); leap seconds (":60") are
not accepted.  R3(GMST) turns TEME, the frame of SGP4, into the pseudo-Earth-fixed frame
(Vallado et al., "Revisiting Spacetrack Report #3", AIAA 2006-6753); polar motion
(≈ 10 m) is ignored.

Two-line element sets are checked (length, line numbers, checksums, catalogue numbers,
numeric fields) before the ``sgp4`` package reads them, so that a corrupted set is
reported with what is wrong.
"""

from __future__ import annotations

import ctypes
import datetime
import math
import re

import numpy as np

from .model import ModelError
from .runtime.flat import fmod
from .runtime.jit import compiled_twin, jitable

TWO_PI = 2.0 * math.pi
DAY = 86400.0  # s
#: J2000.0, 2000-01-01 12:00:00 (JD 2451545.0), taken as UT1 = UTC
J2000 = datetime.datetime(2000, 1, 1, 12, 0, 0)
# IAU-82 GMST, Vallado (4th ed.) eq. 3-47, seconds of time, T in Julian centuries of UT1
_GMST0, _GMST1, _GMST2, _GMST3 = 67310.54841, 8640184.812866, 0.093104, -6.2e-6
_CENTURY = 36525.0  # days
_EPOCH_FORMAT = re.compile(r"(\d{4})-(\d{2})-(\d{2})T(\d{2}):(\d{2}):(\d{2})(?:\.(\d{1,6}))?Z?")


@jitable
def wrap_2pi(angle: float) -> float:
    """Angle wrapped to [0, 2π)."""
    wrapped = angle % TWO_PI
    return 0.0 if wrapped >= TWO_PI else wrapped  # -tiny % 2π rounds to 2π


# -- time --------------------------------------------------------------------------------
def parse_epoch(epoch) -> datetime.datetime:
    """UTC epoch as a naive datetime, from "YYYY-MM-DDTHH:MM:SS[.ffffff][Z]" or a datetime
    (naive = UTC; aware ones are converted to UTC).  ModelError if malformed."""
    if isinstance(epoch, datetime.datetime):
        if epoch.tzinfo is not None:
            epoch = epoch.astimezone(datetime.timezone.utc).replace(tzinfo=None)
        return epoch
    if not isinstance(epoch, str):
        raise ModelError(f"epoch must be an ISO-8601 string or a datetime, got {epoch!r}")
    match = _EPOCH_FORMAT.fullmatch(epoch.strip())
    if match is None:
        raise ModelError(f"epoch {epoch!r} is not ISO-8601 UTC 'YYYY-MM-DDTHH:MM:SS[.ffffff]'")
    year, month, day, hour, minute, second, fraction = match.groups()
    try:
        return datetime.datetime(
            int(year),
            int(month),
            int(day),
            int(hour),
            int(minute),
            int(second),
            int((fraction or "0").ljust(6, "0")),
        )
    except ValueError as exc:  # month 13, Feb 30, second 60 (leap seconds not supported)
        raise ModelError(f"epoch {epoch!r}: {exc}") from None


def format_epoch(epoch) -> str:
    """The ``epoch`` parameter string of a datetime (UTC)."""
    epoch = parse_epoch(epoch)
    return epoch.isoformat(timespec="microseconds" if epoch.microsecond else "seconds")


def j2000_parts(epoch) -> tuple[int, float]:
    """(whole days, seconds in [0, 86400)) of an epoch since J2000.0 (UT1 = UTC)."""
    delta = parse_epoch(epoch) - J2000
    return delta.days, delta.seconds + 1e-6 * delta.microseconds


def sidereal_base(days: int, seconds: float) -> tuple[float, float]:
    """(GMST in seconds of time, reduced to [0, 86400), T) at ``days`` + ``seconds`` after
    J2000.0; of the (876600 h) T term, 86400 s per day are whole turns plus ``seconds``."""
    T = (days + seconds / DAY) / _CENTURY
    g = _GMST0 + seconds + T * (_GMST1 + T * (_GMST2 + T * _GMST3))
    return math.fmod(g, DAY) % DAY, T


@jitable
def sidereal_time(g0: float, T0: float, t: float) -> tuple[float, float]:
    """GMST (rad, [0, 2π)) and its rate (rad/s) ``t`` seconds after the base (g0, T0).

    The increment of eq. 3-47 is evaluated on its own (τ = t / 36525 days), so that θ
    is smooth in t to the round-off of g0 + Δg (≈ 1e-15 rad), not of 8.6e6 T (1e-14)."""
    tau = t / (DAY * _CENTURY)
    dg = t + tau * (
        _GMST1 + _GMST2 * (2.0 * T0 + tau) + _GMST3 * (3.0 * T0 * T0 + tau * (3.0 * T0 + tau))
    )
    T = T0 + tau
    rate = (
        TWO_PI / DAY * (1.0 + (_GMST1 + T * (2.0 * _GMST2 + 3.0 * _GMST3 * T)) / (_CENTURY * DAY))
    )
    return wrap_2pi(fmod(g0 + dg, DAY) * (TWO_PI / DAY)), rate


def gmst(epoch, t: float = 0.0) -> float:
    """Greenwich mean sidereal time (rad, [0, 2π)) at ``epoch`` + ``t`` seconds, IAU-82
    (Vallado eq. 3-47); ``epoch`` an ISO-8601 UTC string or a datetime, UT1 = UTC."""
    return sidereal_time(*sidereal_base(*j2000_parts(epoch)), t)[0]


# -- two-line elements -------------------------------------------------------------------
_TLE_FIELDS = {  # 0-based column slices of the numeric fields (CelesTrak/NORAD format)
    1: (("epoch", 18, 32), ("mean motion derivative", 33, 43)),
    2: (
        ("inclination", 8, 16),
        ("right ascension of the node", 17, 25),
        ("eccentricity", 26, 33),
        ("argument of perigee", 34, 42),
        ("mean anomaly", 43, 51),
        ("mean motion", 52, 63),
    ),
}


def tle_checksum(line: str) -> int:
    """Modulo-10 checksum of a TLE line: digits at face value, '-' as 1, the rest 0."""
    return sum(int(c) if c.isdigit() else c == "-" for c in line[:68]) % 10


def load_tle(line1: str, line2: str):
    """An SGP4 satellite record (WGS-72) from a two-line element set, checked first.

    ModelError names the problem: wrong length or line number, checksum, different
    catalogue numbers, unreadable numeric field, missing ``sgp4`` package, or the SGP4
    initialisation error code.
    """
    lines = (line1.strip(), line2.strip())
    for k, line in enumerate(lines, start=1):
        name = f"tle_line{k}"
        if not line.isascii() or len(line) != 69:
            raise ModelError(
                f"{name} must be 69 ASCII characters (TLE format), got {len(line)}: {line!r}"
            )
        if not line.startswith(f"{k} "):
            raise ModelError(
                f"{name} must start with '{k} ', got {line[:2]!r}"
                + (" (lines swapped?)" if line.startswith(f"{3 - k} ") else "")
            )
        expected = tle_checksum(line)
        if line[68] != str(expected):
            raise ModelError(
                f"{name} checksum: the last digit is {line[68]!r} but the line "
                f"sums to {expected} (mod 10): a corrupted element set"
            )
        for field, start, stop in _TLE_FIELDS[k]:
            text = line[start:stop].strip()
            try:
                float("." + text if field == "eccentricity" else text)
            except ValueError:
                raise ModelError(
                    f"{name}: {field} (columns {start + 1}-{stop}) is not a "
                    f"number: {line[start:stop]!r}"
                ) from None
    if lines[0][2:7] != lines[1][2:7]:
        raise ModelError(
            f"tle_line1 and tle_line2 are of different satellites "
            f"({lines[0][2:7].strip()!r} and {lines[1][2:7].strip()!r})"
        )
    if not float(lines[1][52:63]) > 0.0:
        raise ModelError(f"tle_line2: mean motion must be > 0 rev/day, got {lines[1][52:63]!r}")
    try:
        from sgp4.api import SGP4_ERRORS, WGS72, Satrec
    except ImportError:
        raise ModelError("a TLE needs the sgp4 package (pip install sgp4)") from None
    try:
        satrec = Satrec.twoline2rv(*lines, WGS72)
    except (ValueError, RuntimeError) as exc:
        raise ModelError(f"the TLE could not be read: {exc}") from None
    if satrec.error:
        raise ModelError(
            f"the TLE is rejected by SGP4: error {satrec.error}, "
            f"{SGP4_ERRORS.get(satrec.error, 'unknown error')}"
        )
    return satrec


#: the C++ function the sgp4 package computes SGP4 with: ``bool SGP4Funcs::sgp4(elsetrec &,
#: double tsince, double r[3], double v[3])`` (its extension exports it; Vallado's code)
_SGP4_SYMBOL = "_ZN9SGP4Funcs4sgp4ER8elsetrecdPdS2_"
_SGP4_CALL = ctypes.CFUNCTYPE(
    ctypes.c_bool, ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p
)
_CHECK_TSINCE = 123.456  # min: the time sgp4_entry checks the direct call at


def sgp4_entry(satrec, probe) -> tuple[int, int]:
    """(address of SGP4Funcs::sgp4, address of ``satrec``'s elsetrec) for :func:`sgp4_at`,
    which the compiled kernels call directly: the same function ``satrec.sgp4_tsince``
    calls, so the same bits.  The record is the C++ struct inside the Python object, after
    its header; checked on ``probe``, another record of the same TLE (a call changes the
    deep-space integrator's state): a call at a test time must give sgp4_tsince's results
    and leave that time in the record (``probe.t``).  (0, 0) where any of it fails (the
    sgp4 package without its extension, another layout): the kernels then leave SGP4 to
    the Python."""
    try:
        from sgp4 import vallado_cpp

        function = ctypes.cast(
            getattr(ctypes.CDLL(vallado_cpp.__file__), _SGP4_SYMBOL), ctypes.c_void_p
        ).value
        if not function:
            return 0, 0
        expected = probe.sgp4_tsince(_CHECK_TSINCE)
        got = np.full(6, np.nan)
        at = id(probe) + object.__basicsize__  # after PyObject_HEAD
        ok = _SGP4_CALL(function)(at, _CHECK_TSINCE, got.ctypes.data, got.ctypes.data + 24)
        same = (int(not ok), *got.tolist()) == (expected[0], *expected[1], *expected[2])
        if same and probe.t == _CHECK_TSINCE:
            return function, id(satrec) + object.__basicsize__
    except (ImportError, OSError, AttributeError, TypeError, ValueError):
        pass
    return 0, 0


def _sgp4_intrinsic(numba):
    """sgp4_at compiled: an indirect call through the function's address."""
    from llvmlite import ir
    from numba.core import types
    from numba.extending import intrinsic

    @intrinsic
    def call(typingctx, function, record, tsince, out, at):
        def codegen(context, builder, signature, args):
            function, record, tsince, out, at = args
            data = context.make_array(signature.args[3])(context, builder, out).data
            double_p, byte_p, i64 = (
                ir.DoubleType().as_pointer(),
                ir.IntType(8).as_pointer(),
                ir.IntType(64),
            )
            kind = ir.FunctionType(ir.IntType(8), (byte_p, ir.DoubleType(), double_p, double_p))
            callee = builder.inttoptr(builder.fptoui(function, i64), kind.as_pointer())
            result = builder.call(
                callee,
                (
                    builder.inttoptr(builder.fptoui(record, i64), byte_p),
                    tsince,
                    builder.gep(data, [at]),
                    builder.gep(data, [builder.add(at, ir.Constant(at.type, 3))]),
                ),
            )
            return builder.icmp_unsigned("!=", result, ir.Constant(ir.IntType(8), 0))

        return types.boolean(types.float64, types.float64, types.float64, out, types.intp), codegen

    return call


@compiled_twin(_sgp4_intrinsic)
def sgp4_at(function: float, record: float, tsince: float, out, at: int) -> bool:
    """SGP4 of the record (addresses from :func:`sgp4_entry`) at ``tsince`` minutes: r
    (km) and v (km/s) into out[at : at + 6]; False on an SGP4 error (its code then in the
    record: ``satrec.error``)."""
    base = out.ctypes.data + 8 * at
    return _SGP4_CALL(int(function))(int(record), tsince, base, base + 24)


def tle_epoch(satrec) -> tuple[int, float]:
    """(whole days, seconds in [0, 86400)) of a TLE's epoch (UTC) since J2000.0."""
    offset = satrec.jdsatepoch - 2451545.0
    days = math.floor(offset)
    seconds = ((offset - days) + satrec.jdsatepochF) * DAY
    extra = math.floor(seconds / DAY)
    return days + extra, seconds - extra * DAY
