"""Two rigid payloads on roll-then-pitch gimbals ([Chang 2015] §1.1, §1.3).

Frames (paper §1.1, Fig. 2): body B; support r, turned by the roll φ about body x; payload
m (principal axes, origin at its centre of mass), turned by the pitch θ about the support's
y.  Both gimbal axes pass through the payload's centre of mass, so its motion relative to
the body is a pure rotation and its momentum relative to the body is J Ω (no transfer
term).  With the paper's passive matrices (eq. 2; R_mr and R_rb)::

    R_mb = R_mr R_rb = R_y(θ) R_x(φ) = rot2(θ) rot1(φ)     (rotations.py conventions)

which maps B-coordinates to payload coordinates.  Differentiating, Ṙ_mb = −[Ω×] R_mb with
the payload's angular velocity relative to the body, in payload axes (eq. 1)::

    Ω = R_y(θ) (φ̇, 0, 0) + (0, θ̇, 0) = (φ̇ cos θ, θ̇, φ̇ sin θ)
    Ω̇ = (φ̈ cos θ − φ̇ θ̇ sin θ,  θ̈,  φ̈ sin θ + φ̇ θ̇ cos θ)

Momentum relative to the body (eq. 1 and eq. 2), J = diag(Jx, Jy, Jz) = ``J_payload``::

    h_m = J Ω,    h_b = R_mbᵀ J Ω
        = (φ̇ (Jx cos²θ + Jz sin²θ),
           Jy θ̇ cos φ − (Jz − Jx) φ̇ sin θ cos θ sin φ,
           Jy θ̇ sin φ + (Jz − Jx) φ̇ sin θ cos θ cos φ)

and its time derivative as seen in B (d/dt of R_mbᵀ J Ω with Ṙ_mbᵀ = R_mbᵀ [Ω×])::

    ḣ_b = R_mbᵀ (J Ω̇ + Ω × J Ω)

The paper's eq. (2), ḣ_b = R_mbᵀ ḣ_m, drops the transport term R_mbᵀ (Ω × JΩ).  The
outputs are the sums over the two payloads (eq. 3): h = h_b1 + h_b2, hdot = ḣ_b1 + ḣ_b2;
the payloads exert −hdot − w_BI_B × h on the body (DESIGN.md §2; eq. 4's u).

Symmetric pair (payload 2 at (−φ, −θ) with negated rates and accelerations): h_b,x is odd
in φ̇ and even in θ, h_b,y is odd in (φ, θ, φ̇, θ̇) jointly, so both cancel exactly
(floating-point sin, cos are odd/even); h_b,z is even and doubles::

    h   = (0, 0, h_z),   h_z = 2 [Jy θ̇ sin φ + (Jz − Jx) φ̇ sin θ cos θ cos φ]
    ḣ_z = 2 [Jy (θ̈ sin φ + φ̇ θ̇ cos φ)
             + (Jz − Jx) (φ̈ sin θ cos θ cos φ + φ̇ θ̇ cos 2θ cos φ − φ̇² sin θ cos θ sin φ)]

(φ, θ: payload 1).  With the paper's values (Jy = 35.8, Jz − Jx = −8.8 kg·m², φ̇ = ±6 °/s,
θ̇ = ±0.6 °/s): the φ̇ term of h_z reaches ±0.89 N·m·s at θ = ±45° and |h_z| ≤ 1.07 N·m·s;
at constant rates |ḣ_z| ≤ 0.10 N·m; but every roll reversal (φ̇: +r → −r) swings h_z by
4 |Jz − Jx| r |sin θ cos θ| cos A ≤ 1.78 N·m·s, so its yaw torque is about that swing
divided by the turnaround time (1.89 N·m peak for τ = 1 s; an impulse for the ideal
triangle wave), and a pitch reversal swings it by 4 Jy θ̇ |sin φ| ≤ 0.39 N·m·s.

Boresight: each payload's +z axis, in B: ``los_B = R_mbᵀ (0, 0, 1) = (sin θ, −sin φ cos θ,
cos φ cos θ)``.  With B ≈ O (z nadir, x along track, y to the right of the track), +θ looks
forward and +φ to the left, as the paper's §1.2 (1) describes payload 1 at (15°, 45°).

Servo.  ``bandwidth`` ωn = 0: ideal tracking, angles and rates equal the commands exactly,
and so do the accelerations φ̈, θ̈ in ḣ when ``accel_inputs`` is true (the sweep planner
supplies them; an extension of DESIGN.md's interface, without which ḣ would be one step
late at every reversal — and the feedforward of a compensating controller with it).
Otherwise they are the change of the rate command over the last step divided by its length
(zero before the first step): exact while the commanded rate is piecewise linear and the
last step lay in one piece, one step late at a change of commanded acceleration, and a
one-step pulse of area Δφ̇ where the commanded rate jumps (the triangle wave's reversal).

ωn > 0: each of the four axes is a second-order servo with rate feedforward::

    θ̈ = ωn² (θ_cmd − θ) + 2 ζ ωn (θ̇_cmd − θ̇)

Across a step the inputs are held as given at its start and the angle command moves with
the commanded rate, θ_cmd(s) = θ_cmd + θ̇_cmd s (so a ramp is tracked without error).  The
error e = θ − θ_cmd(s) then obeys ë + 2ζωn ė + ωn² e = 0, integrated in closed form
(matrix exponential, valid for any step)::

    e(s) = E (C e0 + S (σ e0 + ė0)),   ė(s) = E (C ė0 − S (ωn² e0 + σ ė0))
    σ = ζ ωn,  E = e^{−σ s},  λ² = ωn² (ζ² − 1),
    C = cosh λs, S = sinh(λs)/λ   (ζ > 1;  cos ωd s and sin(ωd s)/ωd with ωd² = −λ² if
    ζ < 1;  series in λ²s² near ζ = 1)

The accelerations in ḣ are the servo law evaluated with the current inputs.  The servo
state starts at the commands at t0 (the payloads are parked at the sweep's start).
"""

from __future__ import annotations

import math

import numpy as np

from .flat import StateTable
from .jit import floats, jitable, output_kernel, step_kernel
from .model import Model, ModelError
from .variables import Layout, input_, output, parameter

_COMMANDS = ("roll_cmd", "pitch_cmd", "roll_rate_cmd", "pitch_rate_cmd")
_ACCELERATIONS = ("roll_accel_cmd", "pitch_accel_cmd")
_NEAR_CRITICAL = 1e-6  # |λ² s²| below which C, S are taken from series


@jitable
def payload_momentum(J, phi, theta, phi_dot, theta_dot, phi_ddot, theta_ddot):
    """(h_b, ḣ_b, boresight) of one payload, in B, as tuples (eqs 1–2 with transport).

    h_b = R_mbᵀ J Ω, ḣ_b = R_mbᵀ (J Ω̇ + Ω × J Ω), boresight = R_mbᵀ (0, 0, 1), with
    R_mb = R_y(θ) R_x(φ) and Ω = (φ̇ cos θ, θ̇, φ̇ sin θ).
    """
    Jx, Jy, Jz = J
    cf, sf = math.cos(phi), math.sin(phi)
    c, s = math.cos(theta), math.sin(theta)
    wx, wy, wz = phi_dot * c, theta_dot, phi_dot * s  # Ω (eq. 1)
    hx, hy, hz = Jx * wx, Jy * wy, Jz * wz  # h_m = J Ω
    pq = phi_dot * theta_dot
    dx = Jx * (phi_ddot * c - pq * s) + wy * hz - wz * hy  # J Ω̇ + Ω × J Ω
    dy = Jy * theta_ddot + wz * hx - wx * hz
    dz = Jz * (phi_ddot * s + pq * c) + wx * hy - wy * hx
    # R_mbᵀ v = R_x(φ)ᵀ (R_y(θ)ᵀ v)
    hx, hz = c * hx + s * hz, c * hz - s * hx
    dx, dz = c * dx + s * dz, c * dz - s * dx
    return (
        (hx, cf * hy - sf * hz, sf * hy + cf * hz),
        (dx, cf * dy - sf * dz, sf * dy + cf * dz),
        (s, -sf * c, cf * c),
    )


@jitable
def servo_step(angle, rate, command, rate_command, dt, omega, zeta):
    """Angle and rate after ``dt`` of θ̈ = ωn² (θc + θ̇c s − θ) + 2ζωn (θ̇c − θ̇), exactly."""
    e0, de0 = angle - command, rate - rate_command
    sigma = zeta * omega
    omega2 = omega * omega
    lam2 = omega2 * (zeta * zeta - 1.0)
    x = lam2 * dt * dt
    decay = math.exp(-sigma * dt)
    if abs(x) < _NEAR_CRITICAL:  # cosh/cos and sinh/sin near ζ = 1, to O(x³)
        C = decay * (1.0 + x / 2.0 + x * x / 24.0)
        S = decay * dt * (1.0 + x / 6.0 + x * x / 120.0)
    elif x < 0.0:  # under-damped
        wd = math.sqrt(-lam2)
        C = decay * math.cos(wd * dt)
        S = decay * math.sin(wd * dt) / wd
    else:  # over-damped: e^{−σs} cosh λs without overflow
        lam = math.sqrt(lam2)
        slow = math.exp(-omega2 / (sigma + lam) * dt)  # e^{(λ − σ) s}, λ − σ = −ωn²/(σ + λ)
        fast = math.exp(-(sigma + lam) * dt)
        C = 0.5 * (slow + fast)
        S = 0.5 * (slow - fast) / lam
    e = C * e0 + S * (sigma * e0 + de0)
    de = C * de0 - S * (omega2 * e0 + sigma * de0)
    return command + rate_command * dt + e, rate_command + de


class PayloadGimbals(Model):
    """Two payloads, each on a roll-then-pitch gimbal: momentum relative to the body."""

    VARIABLES = (
        parameter(
            "J_payload",
            (45.5, 35.8, 36.7),
            "kg.m2",  # [Chang 2015] §2
            "principal inertia (Jx, Jy, Jz) of each payload about its centre of mass",
            shape=(3,),
        ),
        parameter(
            "bandwidth",
            0.0,
            "rad/s",
            "servo natural frequency of each gimbal axis (0 = ideal tracking)",
        ),
        parameter("damping", 1.0, "1", "servo damping ratio"),
        parameter(
            "accel_inputs",
            False,
            "1",
            "ideal tracking: take the accelerations from "
            "roll_accel_cmd and pitch_accel_cmd (else from the rate commands' change)",
            type="Boolean",
        ),
        input_(
            "roll_cmd",
            "rad",
            "commanded roll (about body x) of payloads 1 and 2",
            shape=(2,),
            display_unit="deg",
        ),
        input_(
            "pitch_cmd",
            "rad",
            "commanded pitch (about the support's y) of payloads 1 and 2",
            shape=(2,),
            display_unit="deg",
        ),
        input_(
            "roll_rate_cmd",
            "rad/s",
            "commanded roll rate of payloads 1 and 2",
            shape=(2,),
            display_unit="deg/s",
        ),
        input_(
            "pitch_rate_cmd",
            "rad/s",
            "commanded pitch rate of payloads 1 and 2",
            shape=(2,),
            display_unit="deg/s",
        ),
        input_(
            "roll_accel_cmd",
            "rad/s2",
            "commanded roll acceleration of payloads 1 and 2 (used with accel_inputs)",
            shape=(2,),
            display_unit="deg/s2",
            optional="zero: unused unless accel_inputs (then no roll acceleration)",
        ),
        input_(
            "pitch_accel_cmd",
            "rad/s2",
            "commanded pitch acceleration of payloads 1 and 2 (used with accel_inputs)",
            shape=(2,),
            display_unit="deg/s2",
            optional="zero: unused unless accel_inputs (then no pitch acceleration)",
        ),
        output(
            "roll",
            "rad",
            "roll of payloads 1 and 2",
            shape=(2,),
            depends=("roll_cmd",),
            display_unit="deg",
        ),
        output(
            "pitch",
            "rad",
            "pitch of payloads 1 and 2",
            shape=(2,),
            depends=("pitch_cmd",),
            display_unit="deg",
        ),
        output(
            "roll_rate",
            "rad/s",
            "roll rate of payloads 1 and 2",
            shape=(2,),
            depends=("roll_rate_cmd",),
            display_unit="deg/s",
        ),
        output(
            "pitch_rate",
            "rad/s",
            "pitch rate of payloads 1 and 2",
            shape=(2,),
            depends=("pitch_rate_cmd",),
            display_unit="deg/s",
        ),
        output(
            "h",
            "N.m.s",
            "angular momentum of both payloads relative to the body, in B",
            shape=(3,),
            depends=_COMMANDS,
        ),
        output(
            "hdot",
            "N.m",
            "time derivative of h as seen in B",
            shape=(3,),
            depends=_COMMANDS + _ACCELERATIONS,
            derivative_of="h",
        ),
        output(
            "los_B",
            "1",
            "unit boresight (payload +z axis) of payloads 1 and 2 in B (rows)",
            shape=(2, 3),
            depends=("roll_cmd", "pitch_cmd"),
        ),
    )
    INITIAL_STATE_DEPENDS = _COMMANDS

    def initialize(self, t0):
        p = self.p
        J = p.J_payload.tolist()
        Jx, Jy, Jz = J
        if not (
            all(math.isfinite(j) and j > 0 for j in J)
            and Jx <= Jy + Jz
            and Jy <= Jx + Jz
            and Jz <= Jx + Jy
        ):
            raise ModelError(
                f"J_payload must be the positive principal moments of a rigid "
                f"body (each <= the sum of the other two), got {J}"
            )
        if not (math.isfinite(p.bandwidth) and p.bandwidth >= 0):
            raise ModelError(f"bandwidth must be >= 0 (0 = ideal tracking), got {p.bandwidth}")
        if not (math.isfinite(p.damping) and p.damping > 0):
            raise ModelError(f"damping must be > 0, got {p.damping}")
        self.state = STATE.zeros()
        self.state[J_PAYLOAD : J_PAYLOAD + 3] = J
        self.state[[OMEGA, ZETA, IDEAL, ACCEL_INPUTS]] = (
            p.bandwidth,
            p.damping,
            p.bandwidth == 0.0,
            p.accel_inputs,
        )
        self.state[ANGLES : ANGLES + 8] = self.values[U_COMMANDS : U_COMMANDS + 8]
        self.t = t0
        if p.bandwidth != 0.0:  # ideal tracking: the state is the commands, no initial state
            self.remember_initial_inputs()

    def initial_input_jumps(self, used, dt):
        """Servo mode: an angle command moves by at most 4 |rate command| dt in a step (a
        host that passed nothing in initialisation jumps from 0 to the sweep's start);
        rate commands are not bounded (accelerations are not always given)."""
        u, jumps = self.u, {}
        for angle, rate in (("roll_cmd", "roll_rate_cmd"), ("pitch_cmd", "pitch_rate_cmd")):
            change = np.abs(getattr(u, angle) - used[angle])
            bound = 4.0 * np.maximum(np.abs(getattr(u, rate)), np.abs(used[rate])) * dt + 1e-9
            if np.any(change > bound):
                jumps[angle] = f"changed by {np.degrees(change).round(4).tolist()} deg"
        return jumps

    def step(self, t, dt):
        self.check_initial_inputs(dt)
        gimbals_step(self.values, self.state, self.t, dt)
        self.t = t + dt

    def output(self):
        gimbals_output(self.values, self.state, self.t)


# -- kernels (components/jit.py) ------------------------------------------------------
_LAYOUT = Layout(PayloadGimbals.VARIABLES)  # offsets in PayloadGimbals.values
#: the inputs in table order: angle, rate and acceleration commands, each (roll 1, roll 2,
#: pitch 1, pitch 2); the outputs in table order
U_COMMANDS, Y_OUTPUTS = _LAYOUT.range["input"].start, _LAYOUT.range["output"].start
#: the state array: the servo's angles and rates (as the commands), the rate commands at
#: the last step and its length (ideal tracking; 1 once stepped), the payload inertia, ωn,
#: ζ, 1 for ideal tracking, 1 with accel_inputs
STATE = StateTable(
    angles=4, rates=4, last_rate_cmd=4, last_dt=1, stepped=1, J_payload=3, omega=1, zeta=1,
    ideal=1, accel_inputs=1,
)  # fmt: skip
ANGLES, RATES, LAST_RATE_CMD, LAST_DT, STEPPED, J_PAYLOAD = STATE.offsets[:6]
OMEGA, ZETA, IDEAL, ACCEL_INPUTS = STATE.offsets[6:]


@step_kernel(PayloadGimbals)
def gimbals_step(values, state, t, dt):
    """Ideal tracking: the state is the commands (and the rate commands are kept for the
    accelerations); a servo: :func:`servo_step` of each axis over ``dt``."""
    commands, s = floats(values[U_COMMANDS : U_COMMANDS + 8]), floats(state)
    if s[IDEAL] != 0.0:
        for i in range(8):
            state[ANGLES + i] = commands[i]
        for i in range(4):
            state[LAST_RATE_CMD + i] = commands[4 + i]
        state[LAST_DT], state[STEPPED] = dt, 1.0
    else:
        for i in range(4):
            state[ANGLES + i], state[RATES + i] = servo_step(
                s[ANGLES + i], s[RATES + i], commands[i], commands[4 + i], dt, s[OMEGA], s[ZETA]
            )
    return 0


@output_kernel(PayloadGimbals)
def gimbals_output(values, state, t):
    """Angles and rates, h, ḣ (eq. 3: the sums over the two payloads) and the boresights."""
    commands, s = floats(values[U_COMMANDS : U_COMMANDS + 12]), floats(state)
    if s[IDEAL] != 0.0:
        angles, rates = commands[:4], commands[4:8]
        if s[ACCEL_INPUTS] != 0.0:
            accels = [commands[8 + i] for i in range(4)]
        elif s[STEPPED] == 0.0:
            accels = [0.0, 0.0, 0.0, 0.0]
        else:
            k = 1.0 / s[LAST_DT]
            accels = [(rates[i] - s[LAST_RATE_CMD + i]) * k for i in range(4)]
    else:
        angles, rates = s[ANGLES : ANGLES + 4], s[RATES : RATES + 4]
        w2, d = s[OMEGA] * s[OMEGA], 2.0 * s[ZETA] * s[OMEGA]
        accels = [
            w2 * (commands[i] - angles[i]) + d * (commands[4 + i] - rates[i]) for i in range(4)
        ]
    J = (s[J_PAYLOAD], s[J_PAYLOAD + 1], s[J_PAYLOAD + 2])
    h1, d1, l1 = payload_momentum(J, angles[0], angles[2], rates[0], rates[2], accels[0], accels[2])
    h2, d2, l2 = payload_momentum(J, angles[1], angles[3], rates[1], rates[3], accels[1], accels[3])
    for i in range(4):
        values[Y_OUTPUTS + i], values[Y_OUTPUTS + 4 + i] = angles[i], rates[i]
    for k in range(3):
        values[Y_OUTPUTS + 8 + k] = h1[k] + h2[k]
        values[Y_OUTPUTS + 11 + k] = d1[k] + d2[k]
        values[Y_OUTPUTS + 14 + k], values[Y_OUTPUTS + 17 + k] = l1[k], l2[k]
    return 0
