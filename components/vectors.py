"""Small-vector algebra on tuples, the one copy every model uses: 3-vectors, 4-vectors
(quaternions as plain 4-vectors: their product is :func:`.rotations.qmul`) and 3×3
matrices as tuples of rows.

Models call these once or several times per step on 3- and 4-vectors, where NumPy's
per-call cost would dominate; they compute on Python floats and are compiled into the
kernels (``@jitable``).  Every sum is written out in index order, ``(x₀ + x₁) + x₂``, and
each function states what it computes in that order: the results are bit for bit those of
the same expression written out by hand, so a model may use them wherever it computes that
expression (compiled and Python alike).
"""

from __future__ import annotations

import math

from .runtime.jit import floats, jitable


# -- 3-vectors ---------------------------------------------------------------------------
@jitable
def add(a, b) -> tuple:
    """a + b."""
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@jitable
def sub(a, b) -> tuple:
    """a − b."""
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@jitable
def scale(k: float, a) -> tuple:
    """k a."""
    return (k * a[0], k * a[1], k * a[2])


@jitable
def divide(a, k: float) -> tuple:
    """a / k, each element divided (not multiplied by 1/k)."""
    return (a[0] / k, a[1] / k, a[2] / k)


@jitable
def combine(a: float, x, b: float, y) -> tuple:
    """a x + b y."""
    return (a * x[0] + b * y[0], a * x[1] + b * y[1], a * x[2] + b * y[2])


@jitable
def total(vectors) -> tuple:
    """Σ v over the 3-vectors, accumulated from 0.0 in order."""
    x = y = z = 0.0
    for v in vectors:
        x += v[0]
        y += v[1]
        z += v[2]
    return x, y, z


@jitable
def dot(a, b) -> float:
    """a · b, summed in order (a₀b₀ + a₁b₁) + a₂b₂."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@jitable
def cross(a, b) -> tuple:
    """a × b (np.cross is ten times slower on tiny arrays)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@jitable
def norm(v) -> float:
    """|v| = √(v · v)."""
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


# -- 4-vectors ---------------------------------------------------------------------------
@jitable
def quat_dot(p, q) -> float:
    """p · q of quaternions (any 4-vectors), summed in order: negative where q is nearer
    −p than p (its sign, flipped, keeps a quaternion continuous in time)."""
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3]


@jitable
def quat_norm(q) -> float:
    """|q| of a quaternion (any 4-vector)."""
    return math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])


# -- 3×3 matrices (tuples of rows) -------------------------------------------------------
@jitable
def identity() -> tuple:
    """The 3×3 identity."""
    return ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@jitable
def cross_matrix(v) -> tuple:
    """[v×], so that [v×] u = v × u."""
    return ((0.0, -v[2], v[1]), (v[2], 0.0, -v[0]), (-v[1], v[0], 0.0))


@jitable
def rotate(M, v) -> tuple:
    """M v (a rotation matrix such as ``rotations.dcm(q)``, or any 3×3), each row's
    products summed in order."""
    v0, v1, v2 = floats(v)
    return (
        M[0][0] * v0 + M[0][1] * v1 + M[0][2] * v2,
        M[1][0] * v0 + M[1][1] * v1 + M[1][2] * v2,
        M[2][0] * v0 + M[2][1] * v1 + M[2][2] * v2,
    )


@jitable
def rotate_back(M, v) -> tuple:
    """Mᵀ v."""
    v0, v1, v2 = floats(v)
    return (
        M[0][0] * v0 + M[1][0] * v1 + M[2][0] * v2,
        M[0][1] * v0 + M[1][1] * v1 + M[2][1] * v2,
        M[0][2] * v0 + M[1][2] * v1 + M[2][2] * v2,
    )


@jitable
def transpose(M) -> tuple:
    """Mᵀ."""
    return ((M[0][0], M[1][0], M[2][0]), (M[0][1], M[1][1], M[2][1]), (M[0][2], M[1][2], M[2][2]))


@jitable
def matmul(X, Y) -> tuple:
    """X Y: element (i, j) = (X_i0 Y_0j + X_i1 Y_1j) + X_i2 Y_2j."""
    return (
        (
            X[0][0] * Y[0][0] + X[0][1] * Y[1][0] + X[0][2] * Y[2][0],
            X[0][0] * Y[0][1] + X[0][1] * Y[1][1] + X[0][2] * Y[2][1],
            X[0][0] * Y[0][2] + X[0][1] * Y[1][2] + X[0][2] * Y[2][2],
        ),
        (
            X[1][0] * Y[0][0] + X[1][1] * Y[1][0] + X[1][2] * Y[2][0],
            X[1][0] * Y[0][1] + X[1][1] * Y[1][1] + X[1][2] * Y[2][1],
            X[1][0] * Y[0][2] + X[1][1] * Y[1][2] + X[1][2] * Y[2][2],
        ),
        (
            X[2][0] * Y[0][0] + X[2][1] * Y[1][0] + X[2][2] * Y[2][0],
            X[2][0] * Y[0][1] + X[2][1] * Y[1][1] + X[2][2] * Y[2][1],
            X[2][0] * Y[0][2] + X[2][1] * Y[1][2] + X[2][2] * Y[2][2],
        ),
    )


@jitable
def mat_add(X, Y) -> tuple:
    """X + Y."""
    return (
        (X[0][0] + Y[0][0], X[0][1] + Y[0][1], X[0][2] + Y[0][2]),
        (X[1][0] + Y[1][0], X[1][1] + Y[1][1], X[1][2] + Y[1][2]),
        (X[2][0] + Y[2][0], X[2][1] + Y[2][1], X[2][2] + Y[2][2]),
    )


@jitable
def mat_combine(a: float, X, b: float, Y) -> tuple:
    """a X + b Y."""
    return (
        (a * X[0][0] + b * Y[0][0], a * X[0][1] + b * Y[0][1], a * X[0][2] + b * Y[0][2]),
        (a * X[1][0] + b * Y[1][0], a * X[1][1] + b * Y[1][1], a * X[1][2] + b * Y[1][2]),
        (a * X[2][0] + b * Y[2][0], a * X[2][1] + b * Y[2][1], a * X[2][2] + b * Y[2][2]),
    )


@jitable
def plus_diagonal(X, d: float) -> tuple:
    """X + d I."""
    return (
        (X[0][0] + d, X[0][1], X[0][2]),
        (X[1][0], X[1][1] + d, X[1][2]),
        (X[2][0], X[2][1], X[2][2] + d),
    )


@jitable
def symmetric(X) -> tuple:
    """½ X + ½ Xᵀ (X made exactly symmetric)."""
    return mat_combine(0.5, X, 0.5, transpose(X))


@jitable
def gram(columns) -> tuple:
    """Σ a aᵀ over the 3-vectors ``columns``, accumulated from 0.0 in order (rows)."""
    m00 = m01 = m02 = m11 = m12 = m22 = 0.0
    for a0, a1, a2 in columns:
        m00 += a0 * a0
        m01 += a0 * a1
        m02 += a0 * a2
        m11 += a1 * a1
        m12 += a1 * a2
        m22 += a2 * a2
    return (m00, m01, m02), (m01, m11, m12), (m02, m12, m22)


@jitable
def outer_sum(xs, ys) -> tuple:
    """Σ x_i y_iᵀ over paired 3-vectors, accumulated from 0.0 in order (rows)."""
    m = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    for x, y in zip(xs, ys):
        for j in range(3):
            for k in range(3):
                m[j][k] += x[j] * y[k]
    return (m[0][0], m[0][1], m[0][2]), (m[1][0], m[1][1], m[1][2]), (m[2][0], m[2][1], m[2][2])


@jitable
def det3(M) -> float:
    """det M by its first row: a (ei − fh) − b (di − fg) + c (dh − eg)."""
    (a, b, c), (d, e, f), (g, h, i) = M
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


@jitable
def adjugate(M) -> tuple:
    """adj(M), the transposed cofactors: M adj(M) = det(M) I."""
    (a, b, c), (d, e, f), (g, h, i) = M
    return (
        (e * i - f * h, c * h - b * i, b * f - c * e),
        (f * g - d * i, a * i - c * g, c * d - a * f),
        (d * h - e * g, b * g - a * h, a * e - b * d),
    )


@jitable
def inv3(M) -> tuple:
    """M⁻¹ = adj(M) / det M, each cofactor divided by :func:`det3`."""
    (A0, A1, A2), (B0, B1, B2), (C0, C1, C2) = adjugate(M)
    det = det3(M)
    return (
        (A0 / det, A1 / det, A2 / det),
        (B0 / det, B1 / det, B2 / det),
        (C0 / det, C1 / det, C2 / det),
    )


@jitable
def inv3_reciprocal(M) -> tuple:
    """M⁻¹ = adj(M) · (1 / det M): one division, the cofactors multiplied by its result
    (det M by the first row's cofactors, M₀₀ A₀₀ + M₀₁ A₁₀ + M₀₂ A₂₀)."""
    (A0, A1, A2), (B0, B1, B2), (C0, C1, C2) = adjugate(M)
    k = 1.0 / (M[0][0] * A0 + M[0][1] * B0 + M[0][2] * C0)
    return (A0 * k, A1 * k, A2 * k), (B0 * k, B1 * k, B2 * k), (C0 * k, C1 * k, C2 * k)


@jitable
def trace_product(X, Y) -> float:
    """tr(X Y), the diagonal of :func:`matmul` summed in order."""
    return (
        (X[0][0] * Y[0][0] + X[0][1] * Y[1][0] + X[0][2] * Y[2][0])
        + (X[1][0] * Y[0][1] + X[1][1] * Y[1][1] + X[1][2] * Y[2][1])
        + (X[2][0] * Y[0][2] + X[2][1] * Y[1][2] + X[2][2] * Y[2][2])
    )
