"""Eigenaxis slews: the time-optimal jerk-limited angle profile, and the blend of two moving
frames that a slew between guidance segments follows (components/slew_guidance.py).

Angle profile ([Biagiotti 2008] §3.4, the "double S" for rest-to-rest motion).  The slew
angle p(τ) goes from 0 to Θ in the least time T with |ṗ| ≤ ω, |p̈| ≤ α and |p⃛| ≤ j:
seven phases of jerk +j, 0, −j, 0, −j, 0, +j lasting τ_j, τ_c, τ_j, τ_v, τ_j, τ_c, τ_j.
With ω_p the peak rate and α_p = j τ_j the peak acceleration::

    ω ≥ α²/j:  τ_j = α/j,  τ_c = ω/α − α/j     (else τ_j = √(ω/j), τ_c = 0)
    τ_v = Θ/ω − (2 τ_j + τ_c) ≥ 0:  T = Θ/ω + 2 τ_j + τ_c  = Θ/ω + ω/α + α/j (both reached)

and, when Θ is too short to reach ω (τ_v < 0; no coast), ω_p is the root of
ω_p (ω_p/α + α/j) = Θ if that root is ≥ α²/j, else τ_j = (Θ/2j)^⅓, τ_c = 0, T = 4 τ_j.
With j = ∞ (no jerk limit) τ_j = 0 and these are the bang-coast-bang times
T = Θ/ω + ω/α for Θ ≥ ω²/α, else 2 √(Θ/α) (DESIGN.md §3.2).  The jerk limit adds α/j
to T whenever α is reached (else less) and makes p̈ continuous: a reference acceleration
without steps at the slew's start and end.

Blend of two frames.  A slew from frame A (attitude q_A(t), rate ω_A in A axes, ω̇_A)
into frame B, which both move, follows::

    q_D = q_A* ⊗ q_B = q_BA,   L = log q_D  (rotation vector, |L| = θ the angle left)
    q_R = q_A ⊗ exp(ψ),        ψ = s(t) L,   s = p(t − t_s)/Θ from 0 to 1

a rotation about the eigenaxis of B relative to A by the fraction s of the angle between
them.  With ṡ = s̈ = 0 at both ends, q_R, its rate and its acceleration equal A's at the
start and B's at the end (continuity of q, ω, ω̇ at both switches); between two frames at
rest (inertial holds) it is the eigenaxis slew with the profile p itself.  Kinematics,
with J(ψ) the right Jacobian of SO(3) (q̇ = ½ q ⊗ (0, J(ψ) ψ̇) for q = exp ψ: the
rotation vector's kinematics)::

    J(ψ) v = v − a(x) ψ × v + b(x) ψ × (ψ × v),  a = (1 − cos x)/x², b = (x − sin x)/x³,
    J⁻¹(ψ) v = v + ½ ψ × v + c(x) ψ × (ψ × v),   c = 1/x² − (1 + cos x)/(2 x sin x)
    (x = |ψ|)
    ω_BA = ω_B − C_BA ω_A,   ω̇_BA = ω̇_B − C_BA ω̇_A + ω_BA × C_BA ω_A     (in B axes)
    L̇ = J⁻¹(L) ω_BA,         L̈ = J⁻¹(L) (ω̇_BA − J̇(L, L̇) L̇)
    ψ̇ = ṡ L + s L̇,           ψ̈ = s̈ L + 2 ṡ L̇ + s L̈
    ω_R = C_RA ω_A + J(ψ) ψ̇
    ω̇_R = C_RA ω̇_A − J(ψ) ψ̇ × C_RA ω_A + J(ψ) ψ̈ + J̇(ψ, ψ̇) ψ̇

(C_RA = C(exp ψ); J̇(ψ, ψ̇) = dJ/dt; L̈ from differentiating J(L) L̇ = ω_BA).  Near x = 0
the coefficients a, b, c and the derivatives' ȧ/(ψ·ψ̇), ḃ/(ψ·ψ̇) are their Taylor series.
"""

from __future__ import annotations

import math

from .rotations import dcm, qmul
from .vectors import add, combine, cross, dot, norm, rotate, scale, sub, total

SERIES_BELOW = 0.2  # rad: the Jacobians' coefficients from their Taylor series below it


# -- the angle profile ---------------------------------------------------------------------
def profile(angle: float, rate: float, accel: float, jerk: float) -> tuple:
    """The phases (duration, acceleration at its start, jerk) of the least-time rest-to-rest
    profile of ``angle`` under the three limits (module docstring); ``jerk`` may be inf."""
    if not angle > 0.0:
        return ()
    smooth = math.isfinite(jerk)
    k = accel / jerk if smooth else 0.0  # α/j: the time to reach α
    if rate >= accel * k:
        t_j, t_c = k, rate / accel - k
    else:
        t_j, t_c = math.sqrt(rate / jerk), 0.0
    coast = angle / rate - (2.0 * t_j + t_c)
    if coast < 0.0:  # the rate limit is not reached: no coast
        coast = 0.0
        peak = 0.5 * accel * (math.sqrt(k * k + 4.0 * angle / accel) - k)
        if peak >= accel * k:
            t_j, t_c = k, peak / accel - k
        else:
            t_j, t_c = (angle / (2.0 * jerk)) ** (1.0 / 3.0), 0.0
    a_p, j = (jerk * t_j, jerk) if smooth else (accel, 0.0)
    return (
        (t_j, 0.0, j), (t_c, a_p, 0.0), (t_j, a_p, -j), (coast, 0.0, 0.0),
        (t_j, 0.0, -j), (t_c, -a_p, 0.0), (t_j, -a_p, j),
    )  # fmt: skip


def duration(phases) -> float:
    """T: the sum of the phases' durations."""
    return sum(phase[0] for phase in phases)


def minimum_time(angle: float, rate: float, accel: float, jerk: float = math.inf) -> float:
    """The least time of a rest-to-rest eigenaxis slew of ``angle`` (rad) under the rate,
    acceleration and jerk limits (rad/s, rad/s², rad/s³; module docstring)."""
    return duration(profile(angle, rate, accel, jerk))


def at(phases, tau: float) -> tuple:
    """(p, ṗ, p̈) at time τ ≥ 0 from the start (after the end: the end's)."""
    p = v = 0.0
    for length, a, j in phases:
        if tau <= length:
            return (
                p + tau * (v + tau * (a / 2.0 + tau * j / 6.0)),
                v + tau * (a + tau * j / 2.0),
                a + j * tau,
            )
        p += length * (v + length * (a / 2.0 + length * j / 6.0))
        v += length * (a + length * j / 2.0)
        tau -= length
    return p, 0.0, 0.0


# -- SO(3): exp, log and the right Jacobian ------------------------------------------------
def exp_q(psi) -> tuple:
    """The unit quaternion of rotation vector ψ."""
    x = norm(psi)
    k = 0.5 - x * x / 48.0 if x < 1e-4 else math.sin(0.5 * x) / x
    return (math.cos(0.5 * x), k * psi[0], k * psi[1], k * psi[2])


def log_q(q) -> tuple:
    """The rotation vector of q: 2 atan2(|q_v|, q0) q_v/|q_v| (an angle up to 2π when
    q0 < 0: the sign of q chooses the way round)."""
    s = math.sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    k = 2.0 * math.atan2(s, q[0]) / s if s > 0.0 else 2.0 / q[0]
    return (k * q[1], k * q[2], k * q[3])


def _coefficients(x: float) -> tuple:
    """(a, b, a'/x, b'/x) of J at x = |ψ| (module docstring)."""
    x2 = x * x
    if x < SERIES_BELOW:
        return (
            0.5 - x2 * (1.0 / 24.0 - x2 * (1.0 / 720.0 - x2 / 40320.0)),
            1.0 / 6.0 - x2 * (1.0 / 120.0 - x2 * (1.0 / 5040.0 - x2 / 362880.0)),
            -1.0 / 12.0 + x2 * (1.0 / 180.0 - x2 * (1.0 / 6720.0 - x2 / 453600.0)),
            -1.0 / 60.0 + x2 * (1.0 / 1260.0 - x2 * (1.0 / 60480.0 - x2 / 4989600.0)),
        )
    c, s = math.cos(x), math.sin(x)
    return (
        (1.0 - c) / x2,
        (x - s) / (x2 * x),
        (x * s - 2.0 * (1.0 - c)) / (x2 * x2),
        (3.0 * s - 2.0 * x - x * c) / (x2 * x2 * x),
    )


def jacobian(psi, v) -> tuple:
    """J(ψ) v."""
    a, b, _, _ = _coefficients(norm(psi))
    u = cross(psi, v)
    return add(v, combine(-a, u, b, cross(psi, u)))


def jacobian_inverse(psi, v) -> tuple:
    """J⁻¹(ψ) v (|ψ| < 2π)."""
    x = norm(psi)
    x2 = x * x
    if x < SERIES_BELOW:
        c = 1.0 / 12.0 + x2 * (
            1.0 / 720.0 + x2 * (1.0 / 30240.0 + x2 * (1.0 / 1209600.0 + x2 / 47900160.0))
        )
    else:
        c = 1.0 / x2 - (1.0 + math.cos(x)) / (2.0 * x * math.sin(x))
    u = cross(psi, v)
    return add(v, combine(0.5, u, c, cross(psi, u)))


def jacobian_rate(psi, dpsi, v) -> tuple:
    """J̇ v, J̇ = dJ/dt along ψ(t) with rate ψ̇::

    J̇ v = −ȧ ψ × v − a ψ̇ × v + ḃ ψ × (ψ × v) + b (ψ̇ × (ψ × v) + ψ × (ψ̇ × v))

    with ȧ = (a'/x) ψ·ψ̇, ḃ = (b'/x) ψ·ψ̇."""
    a, b, a1, b1 = _coefficients(norm(psi))
    rate = dot(psi, dpsi)
    u, du = cross(psi, v), cross(dpsi, v)
    return total(
        (
            combine(-a1 * rate, u, -a, du),
            scale(b1 * rate, cross(psi, u)),
            scale(b, add(cross(dpsi, u), cross(psi, du))),
        )
    )


def relative(a, b, q_D) -> tuple:
    """(L, L̇, L̈) of B relative to A for the frames a = (q_A, ω_A, ω̇_A) and
    b = (q_B, ω_B, ω̇_B) (rates in their own axes) and q_D = ±(q_A* ⊗ q_B), the sign
    chosen by the caller (module docstring)."""
    C_BA = dcm(q_D)
    w_A = rotate(C_BA, a[1])
    w_BA = sub(b[1], w_A)
    dw_BA = add(sub(b[2], rotate(C_BA, a[2])), cross(w_BA, w_A))
    L = log_q(q_D)
    dL = jacobian_inverse(L, w_BA)
    ddL = jacobian_inverse(L, sub(dw_BA, jacobian_rate(L, dL, dL)))
    return L, dL, ddL


def blend(a, L, dL, ddL, s: float, ds: float, dds: float) -> tuple:
    """(q_R, ω_R, ω̇_R) of the frame turned from frame a = (q_A, ω_A, ω̇_A) by the
    fraction s (with ṡ, s̈) of the relative rotation (L, L̇, L̈) (module docstring)."""
    psi = scale(s, L)
    dpsi = combine(ds, L, s, dL)
    ddpsi = add(combine(dds, L, 2.0 * ds, dL), scale(s, ddL))
    E = exp_q(psi)
    C_RA = dcm(E)
    w_A = rotate(C_RA, a[1])
    w_RA = jacobian(psi, dpsi)
    dw = total(
        (
            rotate(C_RA, a[2]),
            cross(w_A, w_RA),
            jacobian(psi, ddpsi),
            jacobian_rate(psi, dpsi, dpsi),
        )
    )
    return qmul(a[0], E), add(w_A, w_RA), dw
