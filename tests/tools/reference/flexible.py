r"""Independent monolithic reference of a flexible hub with imbalanced rotors (DESIGN.md §3.2).

Written from the equations below only; it imports nothing from ``components/``, ``fmus/`` or
``orchestration/`` (from tests/tools/reference/scan_pitch.py it takes the quaternion helpers,
the orbit frame, the CMG cluster, its steering and the scan_pitch controller, all documented
and tested there).  The co-simulation's hub integrates the total angular momentum H_I and the
modal momenta (components/satellite_dynamics.py); this reference integrates the body rate and
the modal velocities instead, through the mass matrix, with scipy's DOP853 at a tight
tolerance, so that the two share no formulation.

Hybrid coordinates (Likins 1970; mass-normalised constrained modes)
--------------------------------------------------------------------
Hub inertia ``I`` (the whole undeformed spacecraft about its centre of mass), devices' angular
momentum relative to the body ``h`` (in B) with its rate as seen in B ``ḣ``, external torque
``τ``, n modes with frequencies ω_k (constrained: appendage clamped to a fixed hub), damping
ratios ζ_k and rotational participation factors ``L_k`` (rows of L, kg^½·m)::

    I ω̇ + Lᵀ η̈ = τ − ḣ − ω × (I ω + h + Lᵀ η̇)
    η̈ + 2 ζ ω_k η̇ + ω_k² η + L ω̇ = 0

i.e. ``M [ω̇; η̈] = [τ − ḣ − ω × H_B; −2ζω_k η̇ − ω_k² η]`` with the constant mass matrix
``M = [[I, Lᵀ], [L, 1]]``, ``H_B = I ω + h + Lᵀ η̇`` the total angular momentum in B, and
``q̇_BI = ½ q_BI ⊗ (0, ω)``.  Conserved: ``H_I = C_BIᵀ H_B`` (τ = 0) and, undamped with h
constant and τ = 0, ``E = ½ [ω; η̇]ᵀ M [ω; η̇] + ½ Σ ω_k² η_k²``.  Linearised at rest, the
unconstrained (free-free) frequencies are the roots of det(K − λ M) with
``K = diag(0, 0, 0, ω_k²)``; for one mode on one axis ``ω_u = ω_k / √(1 − L_k I⁻¹ L_kᵀ)``.

Rotor imbalance (the convention of Basilisk's JitterSimple, reactionWheelStateEffector.cpp)
--------------------------------------------------------------------------------------------
A rotor spinning at Ω about the unit axis σ, centred at r from the centre of mass, with static
imbalance U_s (kg·m), dynamic imbalance U_d (kg·m²) and angle φ (φ̇ = Ω) has the rotating
unit vector ``e = u cos φ + v sin φ`` (u ⊥ σ its reference direction, v = σ × u).  The body
feels the force and torque (about the centre of mass)::

    F = U_s Ω² e,      τ = U_d Ω² e + r × F

which are minus the rate, at constant Ω and axis, of the imbalance's angular momentum
relative to the body ``h_u = Ω (U_d w + U_s r × w)``, ``w = σ × e`` (the dynamic imbalance's
product of inertia and the static imbalance mass's moment of momentum about the centre of
mass).  This reference carries h_u as a device momentum (exact conservation of H_I), with
``ḣ_u = Ω (U_d ẇ + U_s r × ẇ) + Ω̇ (U_d w + U_s r × w)``, ``ẇ = −Ω e + ν × w`` where ν is
the angular velocity of the rotor's housing relative to the body (a CMG's δ̇ g).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from . import scan_pitch

RTOL, ATOL = 1e-11, 1e-13
ZERO = (0.0, 0.0, 0.0)


# --- hybrid coordinates ---------------------------------------------------------------------
def mass_matrix(inertia, coupling) -> np.ndarray:
    """M = [[I, Lᵀ], [L, 1]] for the participation factors ``coupling`` (n × 3)."""
    L = np.atleast_2d(np.asarray(coupling, dtype=float))
    n = L.shape[0]
    M = np.eye(3 + n)
    M[:3, :3] = inertia
    M[:3, 3:] = L.T
    M[3:, :3] = L
    return M


def unconstrained_frequencies(inertia, coupling, frequency) -> np.ndarray:
    """The free-free modal frequencies (rad/s, ascending) of the linearised hub and modes:
    √λ of det(K − λ M) = 0, K = diag(0, 0, 0, ω_k²), without the three rigid-body zeros."""
    M = mass_matrix(inertia, coupling)
    K = np.zeros_like(M)
    K[3:, 3:] = np.diag(np.asarray(frequency, dtype=float) ** 2)
    lam = np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)
    return np.sqrt(lam[3:])


def single_mode_frequency(frequency: float, coupling, inertia) -> float:
    """ω_u = ω_c / √(1 − L I⁻¹ Lᵀ) of one mode (DESIGN.md §3.2)."""
    L = np.asarray(coupling, dtype=float)
    return frequency / math.sqrt(1.0 - L @ np.linalg.solve(inertia, L))


class Hub:
    """The equations of the module docstring for given constants; ``devices(t)`` returns
    (h, ḣ) in B and ``torque(t)`` τ in B (both default zero)."""

    def __init__(self, inertia, coupling, frequency, damping, devices=None, torque=None):
        self.I = np.asarray(inertia, dtype=float)
        self.L = np.atleast_2d(np.asarray(coupling, dtype=float))
        self.n = self.L.shape[0]
        self.w2 = np.asarray(frequency, dtype=float) ** 2
        self.c = 2.0 * np.asarray(damping, dtype=float) * np.asarray(frequency, dtype=float)
        self.M_inv = np.linalg.inv(mass_matrix(self.I, self.L))
        zero = np.zeros(3)
        self.devices = devices or (lambda t: (zero, zero))
        self.torque = torque or (lambda t: zero)

    def split(self, x):
        """(q, ω, η, η̇) of a state vector."""
        n = self.n
        return x[:4], x[4:7], x[7 : 7 + n], x[7 + n :]

    def state(self, q, w, eta, eta_dot) -> np.ndarray:
        return np.concatenate([q, w, eta, eta_dot]).astype(float)

    def rhs(self, t, x):
        q, w, eta, eta_dot = self.split(x)
        h, hdot = self.devices(t)
        H_B = self.I @ w + h + self.L.T @ eta_dot
        accel = self.M_inv @ np.concatenate(
            [self.torque(t) - hdot - np.cross(w, H_B), -self.c * eta_dot - self.w2 * eta]
        )
        q_dot = 0.5 * np.array(scan_pitch.qmul(q, (0.0, *w)))
        return np.concatenate([q_dot, accel[:3], eta_dot, accel[3:]])

    def rk4(self, x0, t0, t1, steps) -> np.ndarray:
        """The state at t1 from x0 at t0 by ``steps`` classical Runge-Kutta steps (for
        inputs that turn too fast for DOP853's step control to be cheap: rotors)."""
        x, h = np.asarray(x0, dtype=float), (t1 - t0) / steps
        for k in range(steps):
            t = t0 + k * h
            k1 = self.rhs(t, x)
            k2 = self.rhs(t + h / 2, x + h / 2 * k1)
            k3 = self.rhs(t + h / 2, x + h / 2 * k2)
            k4 = self.rhs(t + h, x + h * k3)
            x = x + h / 6 * (k1 + 2 * (k2 + k3) + k4)
        return x

    def run(self, x0, times, max_step=np.inf) -> np.ndarray:
        """States at ``times`` (rows) from x0 at times[0]."""
        sol = solve_ivp(
            self.rhs,
            (times[0], times[-1]),
            np.asarray(x0, dtype=float),
            method="DOP853",
            t_eval=times,
            rtol=RTOL,
            atol=ATOL,
            max_step=max_step,
        )
        if not sol.success:
            raise RuntimeError(sol.message)
        return sol.y.T

    def momentum_I(self, x, h=ZERO) -> np.ndarray:
        """H_I = C_BIᵀ (I ω + h + Lᵀ η̇)."""
        q, w, _, eta_dot = self.split(x)
        return scan_pitch.dcm(q).T @ (self.I @ w + h + self.L.T @ eta_dot)

    def energy(self, x) -> float:
        """½ [ω; η̇]ᵀ M [ω; η̇] + ½ Σ ω_k² η_k² (devices excluded)."""
        _, w, eta, eta_dot = self.split(x)
        v = np.concatenate([w, eta_dot])
        return 0.5 * v @ np.linalg.solve(self.M_inv, v) + 0.5 * self.w2 @ (eta * eta)


# --- rotor imbalance ------------------------------------------------------------------------
def imbalance(U_s, U_d, r, spin, u, Omega, phi, housing_rate=ZERO, Omega_dot=0.0):
    """(h_u, ḣ_u, F, τ) of one rotor (module docstring); ``housing_rate`` ν, the angular
    velocity of its housing relative to B (a CMG's gimbal: δ̇ g), carries σ, u, v along."""
    spin, u, r = (np.asarray(x, dtype=float) for x in (spin, u, r))
    v = np.cross(spin, u)
    e = u * math.cos(phi) + v * math.sin(phi)
    w = np.cross(spin, e)
    w_dot = -Omega * e + np.cross(housing_rate, w)
    moment = U_d * w + U_s * np.cross(r, w)
    h = Omega * moment
    h_dot = Omega * (U_d * w_dot + U_s * np.cross(r, w_dot)) + Omega_dot * moment
    F = U_s * Omega * Omega * e
    return h, h_dot, F, U_d * Omega * Omega * e + np.cross(r, F)


def steady_jitter(inertia, coupling, h_u, h_u_dot, Omega):
    """The body's steady response to rotating momenta far above the modes (module docstring
    of components/satellite_dynamics.py: the appendages stay inertial, the hub alone of
    inertia I − LᵀL counter-rotates): (θ̃, ω̃) = (M⁻¹ ḣ_u / Ω², −M⁻¹ h_u)."""
    L = np.atleast_2d(np.asarray(coupling, dtype=float))
    M = np.asarray(inertia, dtype=float) - L.T @ L
    return np.linalg.solve(M, h_u_dot) / Omega**2, -np.linalg.solve(M, h_u)


# --- scan_pitch with appendages and imbalanced CMG rotors ---------------------------------------
def cmg_rotors(delta, rate, rotors, t):
    """(h_u, ḣ_u) of the six CMG rotors at gimbal angles ``delta`` and rates ``rate``
    (``rotors``: static, dynamic imbalance, position rows, speed Ω, phase0 rows), the
    reference direction of each rotor's angle being its gimbal axis g_i: :func:`imbalance`
    of the six at once (``housing_rate`` δ̇_i g_i)."""
    if rotors is None:
        return np.zeros(3), np.zeros(3)
    Omega = rotors["speed"]
    G = scan_pitch.G_AX.T
    spin = scan_pitch.S_AX.T * np.cos(delta)[:, None] + scan_pitch.T_AX.T * np.sin(delta)[:, None]
    phi = np.asarray(rotors["phase0"]) + Omega * t
    e = G * np.cos(phi)[:, None] + np.cross(spin, G) * np.sin(phi)[:, None]
    w = np.cross(spin, e)
    w_dot = -Omega * e + np.cross(np.asarray(rate)[:, None] * G, w)
    us, ud = np.asarray(rotors["static"])[:, None], np.asarray(rotors["dynamic"])[:, None]
    r = np.asarray(rotors["position"])
    h = Omega * (ud * w + us * np.cross(r, w)).sum(axis=0)
    return h, Omega * (ud * w_dot + us * np.cross(r, w_dot)).sum(axis=0)


def scan_pitch_closed_loop(stop, modes, rotors=None, control_period=0.05, rk4_steps=0):
    """scan_pitch (tests/tools/reference/scan_pitch.py: orbit, cluster, pseudo-inverse
    steering, the five-phase controller, the 956 kg·m² hub) with the appendages ``modes``
    (``frequency``, ``damping``, ``coupling`` rows, ``eta0``, ``eta_dot0``) and the CMG rotors'
    imbalances ``rotors`` (:func:`cmg_rotors`; None: balanced), as a sampled-data system:
    controller and steering at ``control_period``, their commands held, the plant (the hub
    with its modes, the exact gimbal servo, the rotors' imbalance momentum) integrated
    together by DOP853 or, with ``rk4_steps``, that many classical RK4 steps a control
    period (the rotors resolved: DOP853 would take as many steps at twelve evaluations).
    The body starts in the rotors' steady jitter (:func:`steady_jitter`) about the
    scenario's initial state.  Returns arrays at t = j·control_period: ``time``, ``q_BI``,
    ``w_BI_B``, ``q_BO``, ``w_BO_B``, ``pitch``, ``eta``, ``eta_dot``, ``h`` (gimbals),
    ``H_I`` (C_BIᵀ H_B with every momentum) and ``tau_cmd``."""
    I = scan_pitch.J_HUB * np.eye(3)
    L = np.atleast_2d(np.asarray(modes["coupling"], dtype=float))
    n_steps = int(round(stop / control_period))
    state = {"delta": np.array(scan_pitch.DELTA0), "rate": np.zeros(6), "cmd": np.zeros(6)}
    start = {"t": 0.0}

    def gimbals(t):
        return scan_pitch.servo(state["delta"], state["rate"], state["cmd"], t - start["t"])

    def devices(t):
        angles, rates = gimbals(t)
        h = scan_pitch.H_ROTOR * (
            scan_pitch.S_AX @ np.cos(angles) + scan_pitch.T_AX @ np.sin(angles)
        )
        h_dot = scan_pitch.H_ROTOR * (scan_pitch.jacobian(angles) @ rates)
        h_u, h_u_dot = cmg_rotors(angles, rates, rotors, t)
        return h + h_u, h_dot + h_u_dot

    hub = Hub(I, L, modes["frequency"], modes["damping"], devices=devices)
    q_bo = scan_pitch.euler123_to_q(0.0, scan_pitch.THETA0, 0.0)
    q = np.array(scan_pitch.qmul(scan_pitch.q_oi(0.0), q_bo))
    w = scan_pitch.dcm(q_bo) @ np.array(scan_pitch.W_OI_O)
    eta, eta_dot = np.array(modes["eta0"], float), np.array(modes["eta_dot0"], float)
    if rotors is not None:
        theta, w_jitter = steady_jitter(
            I, L, *cmg_rotors(state["delta"], state["rate"], rotors, 0.0), rotors["speed"]
        )
        q = np.array(scan_pitch.qmul(q, (1.0, *(0.5 * theta))))
        q /= np.linalg.norm(q)
        w, eta, eta_dot = w + w_jitter, eta - L @ theta, eta_dot - L @ w_jitter
    x = hub.state(q, w, eta, eta_dot)
    rows = []
    for j in range(n_steps + 1):
        t = j * control_period
        q, w, eta, eta_dot = hub.split(x)
        q_oi = scan_pitch.q_oi(t)
        q_bo = scan_pitch.qmul(scan_pitch.qconj(q_oi), q)
        w_bo = w - scan_pitch.dcm(q_bo) @ np.array(scan_pitch.W_OI_O)
        theta, tau = scan_pitch.control(scan_pitch.phase_of(t), q_bo, w_bo)
        h_gimbal = scan_pitch.cluster_momentum(state["delta"])
        start["t"] = t  # the gimbals' state is at t: the servo from there
        h_all, _ = devices(t)
        H_I = scan_pitch.dcm(q).T @ (I @ w + h_all + L.T @ eta_dot)
        rows.append((t, *q, *w, *q_bo, *w_bo, theta, *eta, *eta_dot, *h_gimbal, *H_I, *tau))
        if j == n_steps:
            break
        state["cmd"] = scan_pitch.steering(tau, w, h_gimbal, state["delta"])
        if rk4_steps:
            x = hub.rk4(x, t, t + control_period, rk4_steps)
        else:
            x = hub.run(x, np.array([t, t + control_period]))[-1]
        x[:4] /= np.linalg.norm(x[:4])
        state["delta"], state["rate"] = gimbals(t + control_period)
    a, n = np.array(rows), L.shape[0]
    columns = {"time": 1, "q_BI": 4, "w_BI_B": 3, "q_BO": 4, "w_BO_B": 3, "pitch": 1,
               "eta": n, "eta_dot": n, "h": 3, "H_I": 3, "tau_cmd": 3}  # fmt: skip
    out, at = {}, 0
    for name, width in columns.items():
        out[name] = a[:, at] if width == 1 and name in ("time", "pitch") else a[:, at : at + width]
        at += width
    return out
