"""Error histories: what the ECSS indices are computed on.

An :class:`ErrorHistory` holds the error of one or many runs on one uniform time grid:
``values[run, sample, component]`` in SI (rad), with the kind of error it is
([Ecss 2008] §3.2):

- *performance error*: the actual attitude relative to the target (reference) one,
  :func:`performance_error` (truth, reference);
- *knowledge error*: the known (estimated) attitude relative to the actual one,
  :func:`knowledge_error` (estimate, truth).

From attitude quaternions (DESIGN.md §2: scalar first, Hamilton, ``q_XI`` maps I to X) the
error is the rotation vector ``φ`` of ``q_XY = q_YI* ⊗ q_XI``, the rotation that takes the
frame Y (truth or reference) to X (estimate or truth): ``|φ|`` is the error angle and
``φ/|φ|`` its axis.  The components of a rotation vector are the same in X and Y axes, so
``φ`` is stated in body axes B.  Signs follow "result minus what it should be"; every
index is compared to its bound in magnitude, so the sign does not change a verdict.

The indices then act on one of three error signals:

- ``φ`` itself (three components): the index is a vector, its magnitude the 3-axis angle;
- :meth:`ErrorHistory.about`: ``φ·a``, the error about one body axis (per axis);
- :meth:`ErrorHistory.line_of_sight`: the line-of-sight error of a boresight ``b`` (body
  axes), the rotation vector ``ε`` that turns the target direction of ``b`` into the actual
  one.  ``|ε|`` is the half-cone angle between them, exactly; ``ε ⊥ b``, so an index of
  ``ε`` (a 2-D vector in the plane normal to ``b``) has the half-cone angle as magnitude
  ([Esa 2011] treats a line of sight this way: two tilt axes, combined at the end).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KINDS = ("performance", "knowledge")
#: tolerated deviation of a recorded quaternion's norm from 1 (it is then normalised)
UNIT_NORM_TOLERANCE = 1e-6
#: tolerated relative spread of the time steps of a uniform grid
UNIFORM_STEP_TOLERANCE = 1e-6
#: runs computed at a time: bounds the temporaries of a long campaign's arrays
BLOCK = 64


def by_blocks(function, shape: tuple, *arrays: np.ndarray) -> np.ndarray:
    """``function`` of the arrays' blocks of ``BLOCK`` runs (axis 0), into one ``shape``."""
    out = np.empty(shape)
    for start in range(0, shape[0], BLOCK):
        out[start : start + BLOCK] = function(*(a[start : start + BLOCK] for a in arrays))
    return out


def quaternion_product(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p ⊗ q`` of arrays of quaternions (scalar first, last axis)."""
    p, q = np.asarray(p, dtype=float), np.asarray(q, dtype=float)
    return _joined(_product(_split(p), _split(q)), np.broadcast_shapes(p.shape, q.shape))


def rotation_vector(q: np.ndarray) -> np.ndarray:
    """Rotation vector ``θ n`` of unit quaternions ``(cos θ/2, sin θ/2 n)``, θ ∈ [0, π]."""
    q = np.asarray(q, dtype=float)
    return _joined(_rotation_vector(_split(q)), q.shape[:-1] + (3,))


# Component by component: each a (runs, samples) array, the operations NumPy's vector
# functions make (norms and dot products summed in the components' order, np.cross's
# products), without their temporaries of the whole (..., 3) and (..., 4) arrays.
def _split(a: np.ndarray) -> tuple:
    return tuple(a[..., i] for i in range(a.shape[-1]))


def _joined(components, shape: tuple) -> np.ndarray:
    out = np.empty(shape)
    for i, c in enumerate(components):
        out[..., i] = c
    return out


def _norm(components) -> np.ndarray:
    """As np.linalg.norm along the components."""
    total = components[0] * components[0]
    for c in components[1:]:
        total += c * c
    return np.sqrt(total)


def _cross(a, b) -> tuple:
    """As np.cross."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _product(p, q) -> tuple:
    """``p ⊗ q``: (p0 q0 − p_v·q_v, p0 q_v + q0 p_v + p_v × q_v)."""
    dot = p[1] * q[1] + p[2] * q[2] + p[3] * q[3]
    cross = _cross(p[1:], q[1:])
    return (p[0] * q[0] - dot, *(p[0] * q[k] + q[0] * p[k] + cross[k - 1] for k in (1, 2, 3)))


def _rotation_vector(q) -> tuple:
    """±q: the same attitude; the shorter rotation (q0 ≥ 0): ``2 atan2(|q_v|, |q0|) q_v/|q_v|``
    (2 q_v where q_v = 0)."""
    negative = q[0] < 0.0
    sine = _norm(q[1:])
    angle = 2.0 * np.arctan2(sine, np.where(negative, -q[0], q[0]))
    scale = np.divide(angle, sine, out=np.full_like(sine, 2.0), where=sine > 0.0)
    np.negative(scale, out=scale, where=negative)
    return tuple(scale * c for c in q[1:])


def rotation_quaternion(phi: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(cos θ/2, sin θ/2 n)`` of rotation vectors ``θ n`` (last axis)."""
    phi = np.asarray(phi, dtype=float)
    angle = np.linalg.norm(phi, axis=-1, keepdims=True)
    axis = np.divide(phi, angle, out=np.zeros_like(phi), where=angle > 0.0)
    return np.concatenate((np.cos(angle / 2), np.sin(angle / 2) * axis), axis=-1)


def _quaternions(q, name: str) -> np.ndarray:
    """``q`` as (runs, samples, 4)."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 2:
        q = q[None]
    if q.ndim != 3 or q.shape[-1] != 4:
        raise ValueError(f"{name}: expected (samples, 4) or (runs, samples, 4), got {q.shape}")
    return q


def _check_unit(name: str, norm: np.ndarray, first_run: int = 0) -> None:
    """``norm`` (runs, samples) of quaternions ``name``, the first of them run ``first_run``:
    each 1 within :data:`UNIT_NORM_TOLERANCE`, else an error naming the run and sample."""
    bad = ~(np.abs(norm - 1.0) <= UNIT_NORM_TOLERANCE)  # NaN is bad too
    if bad.any():
        run, sample = np.argwhere(bad)[0]
        raise ValueError(
            f"{name} is not a unit quaternion at run {first_run + run}, sample {sample}: "
            f"|q| = {norm[run, sample]} (expected 1 within {UNIT_NORM_TOLERANCE})"
        )


def _error_components(x, y, norm_x, norm_y) -> tuple:
    """The components of the rotation vector of ``y* ⊗ x`` (quaternions by component, of
    norms ``norm_x`` and ``norm_y``), each normalised."""
    inverse_y = 1.0 / norm_y
    x = tuple(c / norm_x for c in x)
    conjugate = (y[0] * inverse_y, *(c * -inverse_y for c in y[1:]))
    return _rotation_vector(_product(conjugate, x))


def attitude_error(q_XI, q_YI, t, kind: str) -> ErrorHistory:
    """Rotation vector of ``q_XY = q_YI* ⊗ q_XI`` (frame Y to frame X), body axes."""
    q_x, q_y = _quaternions(q_XI, "q_XI"), _quaternions(q_YI, "q_YI")
    norm_x, norm_y = _norm(_split(q_x)), _norm(_split(q_y))
    _check_unit("q_XI", norm_x)
    _check_unit("q_YI", norm_y)
    if q_x.shape != q_y.shape:
        raise ValueError(f"quaternion histories differ in shape: {q_x.shape} and {q_y.shape}")

    def block(x, y, nx, ny):
        return _joined(_error_components(_split(x), _split(y), nx, ny), x.shape[:-1] + (3,))

    shape = q_x.shape[:-1] + (3,)
    return ErrorHistory(by_blocks(block, shape, q_x, q_y, norm_x, norm_y), t, kind)


def knowledge_error(q_est, q_true, t) -> ErrorHistory:
    """Knowledge error: estimated attitude ``q_B̂I`` relative to the true ``q_BI``."""
    return attitude_error(q_est, q_true, t, "knowledge")


def performance_error(q_true, q_ref, t) -> ErrorHistory:
    """Performance error: true attitude ``q_BI`` relative to the reference ``q_RI``."""
    return attitude_error(q_true, q_ref, t, "performance")


def direction(v, name: str) -> np.ndarray:
    """The unit vector along ``v`` (a non-zero 3-vector)."""
    v = np.asarray(v, dtype=float)
    norm = np.linalg.norm(v) if v.shape == (3,) else 0.0
    if not norm > 0.0 or not np.isfinite(norm):
        raise ValueError(f"{name} must be a non-zero 3-vector in body axes, got {v.tolist()}")
    return v / norm


def describe(v) -> str:
    """``(0, 0, 1)``."""
    return f"({', '.join(f'{c:g}' for c in v)})"


@dataclass(frozen=True, eq=False)
class ErrorHistory:
    """The error of ``runs`` runs on one uniform grid ``t`` (s), SI values (rad).

    ``values`` is ``(runs, samples, components)``; one run may be given as ``(samples,)``
    or ``(samples, components)``.  Components: 3 (a rotation vector, body axes) or 1 (a
    scalar error).  ``signal`` says what the components are, for reports.
    """

    values: np.ndarray
    t: np.ndarray
    kind: str = "performance"
    signal: str | None = None  # default: "rotation vector, body axes" or "scalar"

    def __post_init__(self):
        values = np.asarray(self.values, dtype=float)
        t = np.asarray(self.t, dtype=float)
        if values.ndim == 1:
            values = values[None, :, None]
        elif values.ndim == 2:
            values = values[None]
        if values.ndim != 3 or values.shape[-1] not in (1, 3):
            raise ValueError(
                "error values: expected (samples,), (samples, 1 or 3) or "
                f"(runs, samples, 1 or 3), got {np.shape(self.values)}"
            )
        if self.kind not in KINDS:
            raise ValueError(f"error kind {self.kind!r}: expected one of {KINDS}")
        if t.ndim != 1 or t.size != values.shape[1] or t.size < 2:
            raise ValueError(
                f"t: expected one time per sample ({values.shape[1]}, at least 2), "
                f"got shape {t.shape}"
            )
        steps = np.diff(t)
        step = (t[-1] - t[0]) / (t.size - 1)
        if not step > 0.0 or np.any(np.abs(steps - step) > UNIFORM_STEP_TOLERANCE * step):
            raise ValueError(
                "t must be uniformly sampled and increasing: steps from "
                f"{steps.min()} to {steps.max()} s"
            )
        bad = ~np.isfinite(values).all(axis=-1)
        if bad.any():
            run, sample = np.argwhere(bad)[0]
            raise ValueError(f"{self.kind} error of run {run} is not finite at t = {t[sample]} s")
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "t", t)
        if self.signal is None:
            scalar = values.shape[-1] == 1
            object.__setattr__(self, "signal", "scalar" if scalar else "rotation vector, body axes")

    @property
    def dt(self) -> float:
        """The sample period (s)."""
        return float((self.t[-1] - self.t[0]) / (self.t.size - 1))

    @property
    def runs(self) -> int:
        return int(self.values.shape[0])

    def _rotation_vectors(self, what: str) -> np.ndarray:
        if self.values.shape[-1] != 3:
            raise ValueError(f"{what} needs a rotation-vector error (3 components), not a scalar")
        return self.values

    def about(self, axis) -> ErrorHistory:
        """The error about ``axis`` (body axes): the component ``φ·a`` of the rotation vector."""
        a = direction(axis, "axis")
        return self._kept(("about", *a.tolist()), lambda: self._about(a))

    def _about(self, a: np.ndarray) -> ErrorHistory:
        values = self._rotation_vectors("an error about an axis") @ a
        signal = f"about axis {describe(a)}"
        return ErrorHistory(values[..., None], self.t, self.kind, signal)

    def line_of_sight(self, boresight) -> ErrorHistory:
        """The line-of-sight error ``ε`` of ``boresight`` (body axes): ``|ε|`` is the half-cone
        angle between the target direction ``b`` and the actual one ``b' = Rot(φ) b``,
        ``ε = ∠(b, b') (b × b')/|b × b'|``."""
        b = direction(boresight, "boresight")
        return self._kept(("line of sight", *b.tolist()), lambda: self._line_of_sight(b))

    def _line_of_sight(self, b: np.ndarray) -> ErrorHistory:
        phi = self._rotation_vectors("a line-of-sight error")
        epsilon = by_blocks(lambda block: _line_of_sight(block, b), phi.shape, phi)
        signal = f"line of sight of {describe(b)}, half-cone"
        return ErrorHistory(epsilon, self.t, self.kind, signal)

    def runs_between(self, start: int, stop: int) -> ErrorHistory:
        """The runs ``start`` to ``stop − 1`` (itself, if those are all of its runs)."""
        if start == 0 and stop >= self.runs:
            return self
        return ErrorHistory(self.values[start:stop], self.t, self.kind, self.signal)

    def _kept(self, key: tuple, compute) -> ErrorHistory:
        """``compute()`` once per history and ``key``: a run's requirements on the same
        error and signal (an APE and an RPE of one line of sight) compute it once."""
        kept = self.__dict__.setdefault("_signals", {})
        if key not in kept:
            kept[key] = compute()
        return kept[key]


def _line_of_sight(phi: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``ε`` of the rotation vectors ``phi`` (runs, samples, 3) for the boresight ``b``."""
    components = _split(phi)
    angle = _norm(components)
    n = np.divide(phi, angle[..., None], out=np.zeros_like(phi), where=angle[..., None] > 0.0)
    cosine_angle, sine_angle = np.cos(angle), np.sin(angle)
    along, versine = n @ b, 1 - cosine_angle
    across = _cross(_split(n), b)
    turned = _joined(  # Rodrigues: b rotated by φ
        (
            b[k] * cosine_angle + across[k] * sine_angle + n[..., k] * along * versine
            for k in range(3)
        ),
        phi.shape,
    )
    normal = _cross(b, _split(turned))
    sine = _norm(normal)
    cosine = turned @ b
    if np.any((sine == 0.0) & (cosine < 0.0)):
        raise ValueError("the line of sight is reversed (a 180° error): no half-cone axis")
    scale = np.divide(np.arctan2(sine, cosine), sine, out=np.ones_like(sine), where=sine > 0.0)
    return _joined((scale * c for c in normal), phi.shape)


def quaternion_columns(name: str) -> tuple[str, ...]:
    """The four recorded columns of a quaternion output."""
    return tuple(f"{name}[{i}]" for i in range(1, 5))


def recorded_error(
    columns,
    t: np.ndarray,
    attitude: str,
    reference,
    kind: str = "performance",
    start=None,
    stop=None,
):
    """The :class:`ErrorHistory` of the recorded quaternion ``attitude`` against ``reference``
    (a recorded quaternion, or a function of the columns: a scenario's
    :class:`..mission.requirements.Pointing`) over [``start``, ``stop``]: ``columns[name]``
    is (points,) for a run, (runs, points) for a campaign, at times ``t``;
    :class:`.indices.NotEvaluable` with fewer than 2 samples, or a window the records do
    not cover (to the nearest sample: :func:`not_covered`)."""
    from .indices import NotEvaluable

    gap = not_covered(t, start, stop)
    if gap:
        raise NotEvaluable(gap)
    rows = np.ones(len(t), bool)
    if start is not None:
        rows &= t >= start - 1e-12
    if stop is not None:
        rows &= t <= stop + 1e-12
    if rows.sum() < 2:
        raise NotEvaluable(f"fewer than 2 samples in [{start}, {stop}] s")
    window = slice(int(np.argmax(rows)), len(rows) - int(np.argmax(rows[::-1])))
    runs = np.shape(columns[quaternion_columns(attitude)[0]])
    if len(runs) == 1:  # one run
        values = _recorded_block(columns, attitude, reference, window, 0)[0]
    else:
        values = np.empty((runs[0], window.stop - window.start, 3))
        for first in range(0, runs[0], BLOCK):
            block = _Runs(columns, slice(first, first + BLOCK))
            values[first : first + BLOCK] = _recorded_block(
                block, attitude, reference, window, first
            )
    return ErrorHistory(values, t[window], kind)


class _Runs:
    """``columns[name]`` of the runs ``runs`` (a slice) only."""

    def __init__(self, columns, runs: slice):
        self.columns, self.runs = columns, runs

    def __getitem__(self, name: str) -> np.ndarray:
        return np.asarray(self.columns[name])[self.runs]


def _recorded_block(columns, attitude: str, reference, window: slice, first: int):
    """The error rotation vectors (runs, samples, 3) of :func:`recorded_error` over the
    samples ``window`` of ``columns`` (runs from ``first``), component by component."""
    x = tuple(np.atleast_2d(columns[c])[:, window] for c in quaternion_columns(attitude))
    if callable(reference):
        q_y = np.asarray(reference(columns), dtype=float)
        y = tuple(np.atleast_2d(q_y[..., i])[:, window] for i in range(4))
    else:
        y = tuple(np.atleast_2d(columns[c])[:, window] for c in quaternion_columns(reference))
    if x[0].shape != y[0].shape:
        raise ValueError(
            f"quaternion histories differ in shape: {x[0].shape + (4,)} and {y[0].shape + (4,)}"
        )
    norm_x, norm_y = _norm(x), _norm(y)
    _check_unit("q_XI", norm_x, first)
    _check_unit("q_YI", norm_y, first)
    return _joined(_error_components(x, y, norm_x, norm_y), x[0].shape + (3,))


def not_covered(t: np.ndarray, start=None, stop=None, what: str = "the window") -> str:
    """Why records at times ``t`` do not cover ``what``, [``start``, ``stop``] (None: the
    records' own end), to the nearest sample; "" if they do."""
    if not len(t):
        return "no records"
    half = float(t[1] - t[0]) / 2 if len(t) > 1 else 0.0
    first, last = float(t[0]), float(t[-1])
    if start is not None and start > last + half:
        return f"the records end at {last:g} s, before {what}'s start {start:g} s"
    if start is not None and start < first - half:
        return f"the records begin at {first:g} s, after {what}'s start {start:g} s"
    if stop is not None and stop > last + half:
        return f"the records end at {last:g} s, before {what}'s end {stop:g} s"
    return ""
