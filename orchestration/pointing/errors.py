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
    p0, pv = p[..., :1], p[..., 1:]
    q0, qv = q[..., :1], q[..., 1:]
    scalar = p0 * q0 - np.sum(pv * qv, axis=-1, keepdims=True)
    return np.concatenate((scalar, p0 * qv + q0 * pv + np.cross(pv, qv)), axis=-1)


def rotation_vector(q: np.ndarray) -> np.ndarray:
    """Rotation vector ``θ n`` of unit quaternions ``(cos θ/2, sin θ/2 n)``, θ ∈ [0, π]."""
    q = np.where(q[..., :1] < 0.0, -q, q)  # ±q: the same attitude; the shorter rotation
    sine = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(sine, q[..., :1])
    scale = np.divide(angle, sine, out=np.full_like(sine, 2.0), where=sine > 0.0)
    return scale * q[..., 1:]


def rotation_quaternion(phi: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(cos θ/2, sin θ/2 n)`` of rotation vectors ``θ n`` (last axis)."""
    phi = np.asarray(phi, dtype=float)
    angle = np.linalg.norm(phi, axis=-1, keepdims=True)
    axis = np.divide(phi, angle, out=np.zeros_like(phi), where=angle > 0.0)
    return np.concatenate((np.cos(angle / 2), np.sin(angle / 2) * axis), axis=-1)


def _unit_quaternions(q, name: str) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    if q.ndim == 2:
        q = q[None]
    if q.ndim != 3 or q.shape[-1] != 4:
        raise ValueError(f"{name}: expected (samples, 4) or (runs, samples, 4), got {q.shape}")
    norm = np.sqrt(np.einsum("...i,...i->...", q, q))
    bad = ~(np.abs(norm - 1.0) <= UNIT_NORM_TOLERANCE)  # NaN is bad too
    if bad.any():
        run, sample = np.argwhere(bad)[0]
        raise ValueError(
            f"{name} is not a unit quaternion at run {run}, sample {sample}: "
            f"|q| = {norm[run, sample]} (expected 1 within {UNIT_NORM_TOLERANCE})"
        )
    return q


def _error_rotation(q_x: np.ndarray, q_y: np.ndarray) -> np.ndarray:
    q_x = q_x / np.linalg.norm(q_x, axis=-1, keepdims=True)
    conjugate = q_y * (np.array([1.0, -1.0, -1.0, -1.0]) / np.linalg.norm(q_y, axis=-1)[..., None])
    return rotation_vector(quaternion_product(conjugate, q_x))


def attitude_error(q_XI, q_YI, t, kind: str) -> ErrorHistory:
    """Rotation vector of ``q_XY = q_YI* ⊗ q_XI`` (frame Y to frame X), body axes."""
    q_x = _unit_quaternions(q_XI, "q_XI")
    q_y = _unit_quaternions(q_YI, "q_YI")
    if q_x.shape != q_y.shape:
        raise ValueError(f"quaternion histories differ in shape: {q_x.shape} and {q_y.shape}")
    return ErrorHistory(by_blocks(_error_rotation, q_x.shape[:-1] + (3,), q_x, q_y), t, kind)


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
        values = self._rotation_vectors("an error about an axis") @ a
        signal = f"about axis {describe(a)}"
        return ErrorHistory(values[..., None], self.t, self.kind, signal)

    def line_of_sight(self, boresight) -> ErrorHistory:
        """The line-of-sight error ``ε`` of ``boresight`` (body axes): ``|ε|`` is the half-cone
        angle between the target direction ``b`` and the actual one ``b' = Rot(φ) b``,
        ``ε = ∠(b, b') (b × b')/|b × b'|``."""
        b = direction(boresight, "boresight")
        phi = self._rotation_vectors("a line-of-sight error")
        epsilon = by_blocks(lambda block: _line_of_sight(block, b), phi.shape, phi)
        signal = f"line of sight of {describe(b)}, half-cone"
        return ErrorHistory(epsilon, self.t, self.kind, signal)

    def runs_between(self, start: int, stop: int) -> ErrorHistory:
        """The runs ``start`` to ``stop − 1``."""
        return ErrorHistory(self.values[start:stop], self.t, self.kind, self.signal)


def _line_of_sight(phi: np.ndarray, b: np.ndarray) -> np.ndarray:
    angle = np.linalg.norm(phi, axis=-1, keepdims=True)
    n = np.divide(phi, angle, out=np.zeros_like(phi), where=angle > 0.0)
    turned = (  # Rodrigues: b rotated by φ
        b * np.cos(angle)
        + np.cross(n, b) * np.sin(angle)
        + n * (n @ b)[..., None] * (1 - np.cos(angle))
    )
    normal = np.cross(b, turned)
    sine = np.linalg.norm(normal, axis=-1, keepdims=True)
    cosine = turned @ b
    if np.any((sine[..., 0] == 0.0) & (cosine < 0.0)):
        raise ValueError("the line of sight is reversed (a 180° error): no half-cone axis")
    scale = np.divide(
        np.arctan2(sine, cosine[..., None]), sine, out=np.ones_like(sine), where=sine > 0.0
    )
    return scale * normal


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
    q_x = np.stack([columns[c] for c in quaternion_columns(attitude)], axis=-1)
    if callable(reference):
        q_y = np.asarray(reference(columns))
    else:
        q_y = np.stack([columns[c] for c in quaternion_columns(reference)], axis=-1)
    return (performance_error if kind == "performance" else knowledge_error)(
        q_x[..., rows, :], q_y[..., rows, :], t[rows]
    )


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
