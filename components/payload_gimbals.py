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

Interpolated commands (FMI 2.0 input derivatives, components/model.py; servo mode, the
only one that integrates its inputs): the angle command moves at its slope a (the
derivative a host set for it, else the rate command: :meth:`Model.slope`) and the rate
command at its derivative β, θ_cmd(s) = θ_cmd + a s, θ̇_cmd(s) = θ̇_cmd + β s.  The error
e = θ − θ_cmd(s) then obeys ë + 2ζωn ė + ωn² e = 2ζωn ((θ̇_cmd − a) + β s), whose solution
is the particular e_p = p0 + p1 s (p1 = 2ζβ/ωn, p0 = (2ζωn (θ̇_cmd − a) − 2ζωn p1)/ωn²) plus
the homogeneous motion above from e0 − p0, ė0 − p1.  Ideal tracking takes the commands at
the communication points (nothing to interpolate).

Output derivatives at the current time (the model's own angles θ, rates θ̇, accelerations
θ̈ and jerks θ⃛: in servo mode θ⃛ = ωn² (a − θ̇) + 2ζωn (β − θ̈); in ideal tracking the
derivatives of the acceleration commands with ``accel_inputs``, else zero, the
accelerations being held over the step): the angles' θ̇, the rates' θ̈, ḣ, ḧ_b = R_mbᵀ (J Ω̈
+ Ω̇ × J Ω + 2 Ω × J Ω̇ + Ω × (Ω × J Ω)) and the boresights' R_mbᵀ (Ω × ẑ).
"""

from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .runtime.flat import state_table
from .runtime.jit import floats, jitable, output_kernel, step_kernel
from .variables import input_, output, parameter

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


def payload_momentum_rate(J, angles, rates, accels, jerks):
    """(ḧ_b, boresight rate) of one payload, in B (module docstring); each argument a
    (roll, pitch) pair of the angles and their first three derivatives."""
    (phi, theta), (pd, td), (pdd, tdd), (pddd, tddd) = angles, rates, accels, jerks
    Jx, Jy, Jz = J
    c, s = math.cos(theta), math.sin(theta)
    w = np.array([pd * c, td, pd * s])  # Ω, Ω̇, Ω̈ (eq. 1 differentiated)
    w_dot = np.array([pdd * c - pd * td * s, tdd, pdd * s + pd * td * c])
    k = 2.0 * pdd * td + pd * tdd
    w_ddot = np.array(
        [pddd * c - k * s - pd * td * td * c, tddd, pddd * s + k * c - pd * td * td * s]
    )
    inertia = np.array([Jx, Jy, Jz])
    h, h_dot = inertia * w, inertia * w_dot
    v = inertia * w_ddot + np.cross(w_dot, h) + 2.0 * np.cross(w, h_dot)
    v += np.cross(w, np.cross(w, h))
    return _to_body(phi, theta, v), _to_body(phi, theta, (w[1], -w[0], 0.0))


def _to_body(phi, theta, v):
    """R_mbᵀ v = R_x(φ)ᵀ (R_y(θ)ᵀ v)."""
    cf, sf, c, s = math.cos(phi), math.sin(phi), math.cos(theta), math.sin(theta)
    x, y, z = c * v[0] + s * v[2], v[1], c * v[2] - s * v[0]
    return (x, cf * y - sf * z, sf * y + cf * z)


def servo_step(angle, rate, command, rate_command, dt, omega, zeta, slope=None, rate_slope=0.0):
    """Angle and rate after ``dt`` of θ̈ = ωn² (θc + a s − θ) + 2ζωn (θ̇c + β s − θ̇),
    exactly; a = ``slope`` (None: θ̇c), β = ``rate_slope`` (module docstring)."""
    a = rate_command if slope is None else slope
    return servo_move(angle, rate, command, rate_command, dt, omega, zeta, a, rate_slope)


@jitable
def servo_move(angle, rate, command, rate_command, dt, omega, zeta, a, rate_slope):
    """:func:`servo_step` with the angle command's slope ``a`` given (θ̇c where none was
    set: the command held along its rate, the particular solution zero)."""
    if a == rate_command and rate_slope == 0.0:
        e, de = _free(angle - command, rate - rate_command, dt, omega, zeta)
        return command + rate_command * dt + e, rate_command + de
    p1 = 2.0 * zeta * rate_slope / omega
    p0 = (2.0 * zeta * omega * (rate_command - a) - 2.0 * zeta * omega * p1) / (omega * omega)
    e, de = _free(angle - command - p0, rate - a - p1, dt, omega, zeta)
    return command + a * dt + e + p0 + p1 * dt, a + de + p1


@jitable
def _free(e0, de0, dt, omega, zeta):
    """e, ė after ``dt`` of ë + 2ζωn ė + ωn² e = 0 from e0, ė0."""
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
    return e, de


class PayloadGimbals(Model):
    """Two payloads, each on a roll-then-pitch gimbal: momentum relative to the body."""

    INTERPOLATES_INPUTS = True
    OUTPUT_DERIVATIVES = True

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
        self.state = S.zeros()
        self.state[S.J_payload : S.J_payload + 3] = J
        self.state[[S.omega, S.zeta, S.ideal, S.accel_inputs]] = (
            p.bandwidth,
            p.damping,
            p.bandwidth == 0.0,
            p.accel_inputs,
        )
        self.state[S.angles : S.angles + 8] = self.values[U.roll_cmd : U.roll_cmd + 8]
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
        if gimbals_step(self.values, self.state, self.t, dt) == SLOPE_CONFLICT:
            conflicts = [
                text
                for angle, rate in (("roll_cmd", "roll_rate_cmd"), ("pitch_cmd", "pitch_rate_cmd"))
                for text in self.slope_conflicts(angle, rate)
            ]
            self.warnings.append(
                f"t={t:.6g} s: {'; '.join(conflicts)}: the derivative a host sets for an "
                "angle command (fmi2SetRealInputDerivatives) is its slope over the "
                "step, the rate command only where none was set (reported once)"
            )
        self.t = t + dt

    def _command_rates(self) -> tuple[list, list]:
        """Per axis (roll 1, roll 2, pitch 1, pitch 2): the angle command's slope (None:
        the rate command, no derivative set) and the rate command's derivative."""
        slopes = []
        for angle in ("roll_cmd", "pitch_cmd"):
            given = self._given(angle).tolist()
            rate = self.input_rate(angle).tolist()
            slopes += [x if g else None for g, x in zip(given, rate)]
        rate_slopes = [*self.input_rate("roll_rate_cmd"), *self.input_rate("pitch_rate_cmd")]
        return slopes, [float(x) for x in rate_slopes]

    def output(self):
        gimbals_output(self.values, self.state, self.t)

    def output_derivatives(self):
        """See the module docstring: d/dt of the outputs at ``self.t``."""
        s = self.state
        commands = self.values[U.roll_cmd : U.roll_cmd + 12].tolist()
        angles, rates, accels = _motion(commands, s.tolist())
        if s[S.ideal] != 0.0:
            jerks = [0.0] * 4
            if s[S.accel_inputs] != 0.0:
                jerks = [*self.input_rate("roll_accel_cmd"), *self.input_rate("pitch_accel_cmd")]
        else:
            slopes, rate_slopes = self._command_rates()
            w2, d = s[S.omega] * s[S.omega], 2.0 * s[S.zeta] * s[S.omega]
            jerks = [
                w2 * ((commands[4 + i] if slopes[i] is None else slopes[i]) - rates[i])
                + d * (rate_slopes[i] - accels[i])
                for i in range(4)
            ]
        J = s[S.J_payload : S.J_payload + 3].tolist()
        pair = [(k, k + 2) for k in (0, 1)]  # (roll, pitch) of payloads 1 and 2
        moved = [
            payload_momentum_rate(J, *([x[i], x[j]] for x in (angles, rates, accels, jerks)))
            for i, j in pair
        ]
        hdot = self.values[Y.hdot : Y.hdot + 3]
        return np.array(
            [*rates, *accels, *hdot, *np.add(moved[0][0], moved[1][0]), *moved[0][1], *moved[1][1]]
        )


# -- kernels (components/runtime/jit.py) ----------------------------------------------
P, U, Y = PayloadGimbals.names()
DU, GIVEN = PayloadGimbals.derivative_names()
#: the commands the kernels read, from U.roll_cmd on: angles, rates and accelerations, each
#: roll 1, roll 2, pitch 1, pitch 2 (the table lays them out so, one after the other; so do
#: their derivatives a host set, from DU.roll_cmd on, and whether it did, GIVEN.roll_cmd)
_INPUT_ORDER = _COMMANDS + _ACCELERATIONS
if [getattr(U, name) for name in _INPUT_ORDER] != [U.roll_cmd + 2 * k for k in range(6)]:
    raise AssertionError(f"PayloadGimbals' inputs are not laid out as {_INPUT_ORDER}")
#: the state array: the servo's angles and rates (as the commands), the rate commands at
#: the last step and its length (ideal tracking; 1 once stepped), the payload inertia, ωn,
#: ζ, 1 for ideal tracking, 1 with accel_inputs, 1 once a rate command differing from a
#: derivative set for its angle command was reported
S = state_table(
    "PayloadGimbals state", angles=4, rates=4, last_rate_cmd=4, last_dt=1, stepped=1,
    J_payload=3, omega=1, zeta=1, ideal=1, accel_inputs=1, slope_reported=1,
)  # fmt: skip
#: gimbals_step's status: the step done, a slope conflict to report (step() warns)
SLOPE_CONFLICT = 1


@step_kernel(PayloadGimbals)
def gimbals_step(values, state, t, dt):
    """Ideal tracking: the state is the commands (and the rate commands are kept for the
    accelerations); a servo: :func:`servo_move` of each axis over ``dt``, the angle
    command at the slope set for it (else its rate command), the rate command at its
    derivative.  SLOPE_CONFLICT (the step done) the first time a non-zero rate command
    differs from a derivative set for its angle command."""
    v, s = floats(values), floats(state)
    commands = v[U.roll_cmd : U.roll_cmd + 8]
    if s[S.ideal] != 0.0:
        for i in range(8):
            state[S.angles + i] = commands[i]
        for i in range(4):
            state[S.last_rate_cmd + i] = commands[4 + i]
        state[S.last_dt], state[S.stepped] = dt, 1.0
        return 0
    conflict, omega, zeta = False, s[S.omega], s[S.zeta]
    for i in range(4):
        rate_command, given = commands[4 + i], v[GIVEN.roll_cmd + i] != 0.0
        a = v[DU.roll_cmd + i] if given else rate_command
        conflict = conflict or given and rate_command != 0.0 and rate_command != a
        state[S.angles + i], state[S.rates + i] = servo_move(
            s[S.angles + i], s[S.rates + i], commands[i], rate_command, dt, omega, zeta, a,
            v[DU.roll_rate_cmd + i],
        )  # fmt: skip
    if conflict and s[S.slope_reported] == 0.0:
        state[S.slope_reported] = 1.0
        return SLOPE_CONFLICT
    return 0


@jitable
def _motion(commands, s) -> tuple:
    """(angles, rates, accelerations), each roll 1, roll 2, pitch 1, pitch 2, now."""
    if s[S.ideal] != 0.0:
        angles, rates = commands[:4], commands[4:8]
        if s[S.accel_inputs] != 0.0:
            accels = [commands[8 + i] for i in range(4)]
        elif s[S.stepped] == 0.0:
            accels = [0.0, 0.0, 0.0, 0.0]
        else:
            k = 1.0 / s[S.last_dt]
            accels = [(rates[i] - s[S.last_rate_cmd + i]) * k for i in range(4)]
    else:
        angles, rates = s[S.angles : S.angles + 4], s[S.rates : S.rates + 4]
        w2, d = s[S.omega] * s[S.omega], 2.0 * s[S.zeta] * s[S.omega]
        accels = [
            w2 * (commands[i] - angles[i]) + d * (commands[4 + i] - rates[i]) for i in range(4)
        ]
    return angles, rates, accels


@output_kernel(PayloadGimbals)
def gimbals_output(values, state, t):
    """Angles and rates, h, ḣ (eq. 3: the sums over the two payloads) and the boresights."""
    commands, s = floats(values[U.roll_cmd : U.roll_cmd + 12]), floats(state)
    angles, rates, accels = _motion(commands, s)
    J = (s[S.J_payload], s[S.J_payload + 1], s[S.J_payload + 2])
    h1, d1, l1 = payload_momentum(J, angles[0], angles[2], rates[0], rates[2], accels[0], accels[2])
    h2, d2, l2 = payload_momentum(J, angles[1], angles[3], rates[1], rates[3], accels[1], accels[3])
    for i in range(2):
        values[Y.roll + i], values[Y.pitch + i] = angles[i], angles[2 + i]
        values[Y.roll_rate + i], values[Y.pitch_rate + i] = rates[i], rates[2 + i]
    for k in range(3):
        values[Y.h + k] = h1[k] + h2[k]
        values[Y.hdot + k] = d1[k] + d2[k]
        values[Y.los_B + k], values[Y.los_B + 3 + k] = l1[k], l2[k]
    return 0
