"""Reaction-wheel assembly of one to four wheels (the 0.2 N·m flywheel of [Chang 2015]).

Wheel i has the unit spin axis a_i (in B), the spin inertia J_w and the speed Ω_i relative
to the body; its motor applies the torque m_i to the wheel (and −m_i a_i to the body).
With viscous and Coulomb bearing friction c_v, c_c::

    h    = Σ J_w Ω_i a_i                                   (relative to the body, in B)
    J_w Ω̇_i = m_i − c_v Ω_i − c_c sign(Ω_i)
    hdot = Σ J_w Ω̇_i a_i                                   (as seen in B)

and the assembly exerts −hdot − w_BI_B × h on the body (DESIGN.md §2).  A wheel at rest
stays at rest while |m_i| ≤ c_c (static friction taken equal to the Coulomb level) and
breaks away with J_w Ω̇_i = m_i − c_c sign(m_i) otherwise.

Drive (what a wheel drive electronics with closed-loop torque control does, sampled and
held at the communication points).  The body torque τ_cmd needs
``hdot_req = −τ_cmd − w_BI_B × h``; it is shared among the active wheels by least squares
(minimum-norm pseudo-inverse of A = [a_1 … a_n]), J_w Ω̇_i,req = (A⁺ hdot_req)_i, and the
drive adds the friction it knows about, so the motor torque is::

    m_i = clip(J_w Ω̇_i,req + c_v Ω_i + c_c sign(Ω_i), ±torque_limit)

(at Ω_i = 0: + c_c sign(Ω̇_i,req), the break-away torque).  Within the limits the wheels
deliver τ_cmd exactly at the communication point; the compensation is ideal (the friction
parameters are the drive's model too).  A wheel at or beyond ±momentum_limit is not driven
further out: its requested acceleration away from zero is set to zero, i.e. the drive
holds its speed.  ``saturated`` is true while a motor torque is clipped or a wheel is held
at the momentum limit; torque the axes cannot reach (fewer than three independent axes)
is not delivered and is reported once as a warning.

Integration: over a step the motor torque is held, and between zero crossings of Ω the
wheel ODE is linear, J_w Ω̇ = b − c_v Ω with b = m − c_c sign(Ω), whose exact solution is::

    Ω(t) = Ω + Ω̇(0) (1 − e^{−k t}) / k,    k = c_v / J_w      (→ Ω + Ω̇(0) t as k → 0)

A wheel decelerating toward zero stops there at t* = −ln(1 − k φ*) / k, φ* = −Ω / Ω̇(0),
and then either sticks (|m| ≤ c_c, for the rest of the step, without chattering) or
restarts the other way.  A speed limiter in the drive clamps Ω at the momentum limit
(J_w |Ω| ≤ max(momentum_limit, J_w |Ω| at the step's start)) if it is reached within
the step.

Faults (DESIGN.md §3.2), per wheel place i, from the first communication point at or
after the time (the drive samples and holds): from ``fail_time[i]`` the motor gives no
torque (the wheel coasts down on its friction; the drive does not share its torque out
among the others: that is the FDIR's reconfiguration); from ``friction_change_time[i]``
the bearing friction is ``friction_factor[i]`` times c_v and c_c, while the drive keeps
compensating the nominal friction it knows (the increase is a torque it does not deliver).

Output derivatives at the current time, along the step's motion with the motor torque
held: Ω̇_i = (J Ω̇_i) / J_w as the drive delivers it, ḣ, ḧ = −(c_v / J_w) ḣ (J_w Ω̈_i = −c_v Ω̇_i
between zero crossings; zero for a wheel at rest or held), and zero for the motor torques
(held over the step).  The inputs are sampled by the drive at communication points, not
integrated: the model does not interpolate them (no canInterpolateInputs).

Rotor microvibration (DESIGN.md §3.2, components/imbalance.py): wheel i with static and
dynamic imbalance U_s,i, U_d,i, centred at ``rotor_position_B`` r_i, turns its imbalance
through φ_i = ``imbalance_phase0``_i + ∫ Ω_i dt (the trapezoidal rule over each step: exact
at constant acceleration; a wheel stopping within a step is off by less than Ω̇ dt² / 8)
from its reference direction u_i (:func:`.imbalance.reference_direction`: y for a wheel on
x, x for one on y or z), e_i = u_i cos φ_i + (a_i × u_i) sin φ_i.  The assembly outputs the
sums ``f_jitter_B`` = Σ U_s Ω_i² e_i and ``tau_jitter_B`` = Σ (U_d Ω_i² e_i + r_i × F_i),
and each wheel's imbalance momentum as a row of ``h_jitter_B`` with its rate (at Ω_i: the
``speed`` output) for a hub row each (SatelliteDynamics ``h_extra``, ``h_extra_frequency``).
All zero without imbalance.

Default wheel: Honeywell HR12 (Constellation series, 12 N·m·s option), the 0.2 N·m class
of [Chang 2015]: 0.2 N·m, 12 N·m·s at 6000 rpm, so J_w = 12 / (200π) = 0.0191 kg·m²; Coulomb
friction 0.5 mN·m (the figure Basilisk's ``simIncludeRW.Honeywell_HR12`` uses); viscous
friction 1e-5 N·m·s/rad, an estimate (6.3 mN·m drag at 6000 rpm, 3 % of the torque).
Three wheels along x, y, z; the 4th row of ``axis`` zero (no 4th wheel).
"""

from __future__ import annotations

import math

import numpy as np

from .imbalance import reference_direction, rotor_imbalance
from .model import Model, ModelError
from .runtime.flat import put, relative, state_table
from .runtime.jit import floats, jitable, output_kernel, step_kernel
from .variables import input_, output, parameter
from .vectors import total

N_WHEELS = 4
RPM = 2.0 * math.pi / 60.0
HR12_TORQUE = 0.2  # N·m
HR12_MOMENTUM = 12.0  # N·m·s (smallest of the 12 / 25 / 50 options)
HR12_SPEED = 6000.0 * RPM  # rad/s at 12 N·m·s
HR12_INERTIA = HR12_MOMENTUM / HR12_SPEED
HR12_COULOMB = 5e-4  # N·m
VISCOUS = 1e-5  # N·m·s/rad (estimate)
DEFAULT_AXES = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0))
_AXIS_TOLERANCE = 1e-9
_INPUTS = ("tau_cmd", "w_BI_B")


@jitable
def wheel_step(
    speed: float,
    torque: float,
    dt: float,
    inertia: float,
    viscous: float,
    coulomb: float,
    limit: float = math.inf,
) -> float:
    """Wheel speed after ``dt`` with the motor torque held (exact, see the module notes).

    ``limit`` is the speed the drive's limiter clamps |Ω| to (it is never below the start
    speed: a wheel already beyond it is not pulled back).
    """
    omega, remaining = speed, dt
    k = viscous / inertia
    for _ in range(2):  # at most: run down to rest, then one regime from rest
        if omega == 0.0:
            if abs(torque) <= coulomb:
                return 0.0  # stiction
            sign = 1.0 if torque > 0.0 else -1.0
        else:
            sign = 1.0 if omega > 0.0 else -1.0
        accel = (torque - sign * coulomb - viscous * omega) / inertia
        phi = remaining if k == 0.0 else -math.expm1(-k * remaining) / k
        if omega != 0.0 and accel * sign < 0.0:
            phi_zero = -omega / accel  # reaches rest if φ* ≤ φ (so k φ* < 1)
            if phi_zero <= phi:
                remaining -= phi_zero if k == 0.0 else -math.log1p(-k * phi_zero) / k
                omega = 0.0
                continue
        omega += accel * phi
        bound = max(limit, abs(speed))
        if sign * omega > bound:
            omega = sign * bound
        return omega
    return omega


class Flywheel(Model):
    """Reaction-wheel assembly: torque command to wheel motor torques, exact wheel dynamics."""

    OUTPUT_DERIVATIVES = True

    VARIABLES = (
        parameter(
            "axis",
            DEFAULT_AXES,
            "1",
            "spin axis of each wheel in B (rows, normalised; a zero row = no wheel)",
            shape=(N_WHEELS, 3),
        ),
        parameter("J_wheel", HR12_INERTIA, "kg.m2", "spin-axis inertia of each wheel"),
        parameter(
            "torque_limit",
            HR12_TORQUE,
            "N.m",
            "motor torque limit of each wheel (0: motors off, wheels coast)",
        ),
        parameter(
            "momentum_limit",
            HR12_MOMENTUM,
            "N.m.s",
            "momentum limit J_wheel |speed| of each wheel (not driven beyond)",
        ),
        parameter(
            "viscous_friction", VISCOUS, "N.m.s/rad", "viscous bearing friction coefficient c_v"
        ),
        parameter(
            "coulomb_friction",
            HR12_COULOMB,
            "N.m",
            "Coulomb (and static) bearing friction torque c_c",
        ),
        parameter(
            "speed0",
            0.0,
            "rad/s",
            "initial wheel speeds relative to the body",
            shape=(N_WHEELS,),
            display_unit="rpm",
        ),
        parameter(
            "fail_time",
            math.inf,
            "s",
            "time each wheel's motor stops giving torque (inf: never)",
            shape=(N_WHEELS,),
        ),
        parameter(
            "friction_factor",
            1.0,
            "1",
            "each wheel's bearing friction from friction_change_time on, times the nominal",
            shape=(N_WHEELS,),
        ),
        parameter(
            "friction_change_time",
            math.inf,
            "s",
            "time each wheel's friction becomes friction_factor times the nominal (inf: never)",
            shape=(N_WHEELS,),
        ),
        parameter(
            "static_imbalance",
            0.0,
            "kg.m",
            "static imbalance U_s of each wheel",
            shape=(N_WHEELS,),
        ),
        parameter(
            "dynamic_imbalance",
            0.0,
            "kg.m2",
            "dynamic imbalance U_d of each wheel",
            shape=(N_WHEELS,),
        ),
        parameter(
            "rotor_position_B",
            0.0,
            "m",
            "centre of each wheel from the centre of mass, in B (rows)",
            shape=(N_WHEELS, 3),
        ),
        parameter(
            "imbalance_phase0",
            0.0,
            "rad",
            "angle of each wheel's imbalance from its reference direction at t = 0",
            shape=(N_WHEELS,),
            display_unit="deg",
        ),
        input_("tau_cmd", "N.m", "torque wanted on the body, in B", shape=(3,)),
        input_(
            "w_BI_B",
            "rad/s",
            "body angular velocity relative to I, in B",
            shape=(3,),
            display_unit="deg/s",
        ),
        output("h", "N.m.s", "wheel angular momentum relative to the body, in B", shape=(3,)),
        output(
            "hdot",
            "N.m",
            "time derivative of h as seen in B",
            shape=(3,),
            depends=_INPUTS,
            derivative_of="h",
        ),
        output(
            "speed",
            "rad/s",
            "wheel speeds relative to the body (0 for no wheel)",
            shape=(N_WHEELS,),
            display_unit="rpm",
        ),
        output(
            "motor_torque",
            "N.m",
            "motor torque on each wheel (held over the step)",
            shape=(N_WHEELS,),
            depends=_INPUTS,
        ),
        output(
            "saturated",
            "1",
            "a motor torque is clipped or a wheel is held at the momentum limit",
            type="Boolean",
            depends=_INPUTS,
        ),
        output("f_jitter_B", "N", "force of the wheels' imbalances on the body, in B", shape=(3,)),
        output(
            "tau_jitter_B",
            "N.m",
            "torque of the wheels' imbalances on the body about the centre of mass, in B",
            shape=(3,),
        ),
        output(
            "h_jitter_B",
            "N.m.s",
            "angular momentum of each wheel's imbalance relative to the body, in B (rows)",
            shape=(N_WHEELS, 3),
        ),
        output(
            "hdot_jitter_B",
            "N.m",
            "time derivative of h_jitter_B as seen in B",
            shape=(N_WHEELS, 3),
            depends=_INPUTS,
            derivative_of="h_jitter_B",
        ),
    )

    def initialize(self, t0):
        p = self.p
        if not p.J_wheel > 0:
            raise ModelError(f"J_wheel must be positive, got {p.J_wheel}")
        if not p.momentum_limit > 0:
            raise ModelError(f"momentum_limit must be positive, got {p.momentum_limit}")
        if not (p.torque_limit >= 0 and p.viscous_friction >= 0 and p.coulomb_friction >= 0):
            raise ModelError(
                "torque_limit, viscous_friction and coulomb_friction must not be "
                f"negative, got {p.torque_limit}, {p.viscous_friction}, "
                f"{p.coulomb_friction}"
            )
        axes = np.array(p.axis, dtype=float)
        norms = np.linalg.norm(axes, axis=1)
        self.wheels = [i for i in range(N_WHEELS) if norms[i] > _AXIS_TOLERANCE]
        if not self.wheels:
            raise ModelError("no wheel: every row of axis is zero")
        A = (axes[self.wheels] / norms[self.wheels, None]).T  # 3 × n
        distribution = np.linalg.pinv(A, rcond=1e-9)
        rank = np.linalg.matrix_rank(A, tol=1e-9)
        if rank < 3:
            self.warnings.append(
                f"the wheel axes span only {rank} dimension(s): torque "
                "outside their span is not delivered"
            )
        for i in range(N_WHEELS):
            if i not in self.wheels and p.speed0[i] != 0.0:
                self.warnings.append(f"speed0[{i + 1}] ignored: wheel {i + 1} has no axis")
        self.state = state = S.zeros()
        n = len(self.wheels)
        state[S.n], state[S.wheel : S.wheel + n] = n, self.wheels
        state[S.axes : S.axes + 3 * n] = A.T.reshape(-1)
        state[S.distribution : S.distribution + 3 * n] = distribution.reshape(-1)
        state[S.inertia : S.speed_limit + 1] = (
            p.J_wheel, p.viscous_friction, p.coulomb_friction, p.torque_limit,
            p.momentum_limit / p.J_wheel,
        )  # fmt: skip
        state[S.omega : S.omega + n] = [p.speed0[i] for i in self.wheels]
        for name in ("fail_time", "friction_change_time"):
            if np.any(np.isnan(getattr(p, name))):
                raise ModelError(f"{name} must be times or inf, got {getattr(p, name).tolist()}")
        if not np.all(p.friction_factor >= 0.0) or not np.all(np.isfinite(p.friction_factor)):
            raise ModelError(f"friction_factor must be >= 0, got {p.friction_factor.tolist()}")
        state[S.fail : S.fail + n] = [p.fail_time[i] for i in self.wheels]
        state[S.factor : S.factor + n] = [p.friction_factor[i] for i in self.wheels]
        state[S.change : S.change + n] = [p.friction_change_time[i] for i in self.wheels]
        if np.any(p.static_imbalance != 0.0) or np.any(p.dynamic_imbalance != 0.0):
            state[S.jitter] = 1.0
            for k, i in enumerate(self.wheels):
                state[S.us + k], state[S.ud + k] = p.static_imbalance[i], p.dynamic_imbalance[i]
                state[S.angle + k] = p.imbalance_phase0[i]
                put(state, S.r + 3 * k, p.rotor_position_B[i])
                put(state, S.u + 3 * k, reference_direction(A[:, k].tolist()))
        self.t = t0

    def step(self, t, dt):
        before = self.state[S.limited : S.limited + 2 * N_WHEELS].copy()
        if flywheel_step(self.values, self.state, self.t, dt) == NEW_LIMIT:
            new = (self.state[S.limited : S.limited + 2 * N_WHEELS] != 0) & (before == 0)
            self.warnings.append(
                f"t={t:.3f} s: "
                + "; ".join(
                    f"wheel {self.wheels[k // 2] + 1} {_LIMITS[k % 2]}" for k in np.flatnonzero(new)
                )
                + " (the commanded torque is not delivered)"
            )
        self.t = t + dt

    def output(self):
        flywheel_output(self.values, self.state, self.t)

    @classmethod
    def state_problem(cls, attributes, reference):
        """The kernels index the value array with the wheels' places: the rows before the
        speeds (places, axes, constants, imbalances) are those the parameters make."""
        rows = np.r_[0 : S.omega, S.us : S.size]
        if not np.array_equal(attributes["state"][rows], reference["state"][rows]):
            return (
                "wheel constants (places, axes, distribution, imbalances) are not its parameters'"
            )
        return ""

    def output_derivatives(self):
        """See the module docstring: d/dt of h, ḣ, the speeds and motor torques now."""
        s = self.state
        inputs = self.values[U.tau_cmd : U.w_BI_B + 3].tolist()
        _, accel_torques, _, _, _ = _drive(inputs, s.tolist(), self.t)
        speed_rate = [0.0] * N_WHEELS
        for k in range(int(s[S.n])):
            speed_rate[int(s[S.wheel + k])] = accel_torques[k] / s[S.inertia]
        hdot = self.y.hdot.tolist()
        k = s[S.viscous] / s[S.inertia]  # nominal friction: ḧ's viscous decay
        jitter = np.zeros((2, N_WHEELS, 3))
        forces = np.zeros((2, 3))
        if s[S.jitter] != 0.0:
            rows = _jitter(s.tolist(), accel_torques)
            for k_, row in enumerate(rows):
                jitter[:, int(s[S.wheel + k_])] = row[1], row[2]
            forces[:] = (
                np.sum([row[4] for row in rows], axis=0),
                np.sum([row[6] for row in rows], axis=0),
            )
        return np.array(
            [*hdot, *(-k * x for x in hdot), *speed_rate, *[0.0] * N_WHEELS, 0.0,
             *forces.reshape(-1), *jitter.reshape(-1)]
        )  # fmt: skip


# -- kernels (components/runtime/jit.py) ----------------------------------------------
#: the value array's offsets by the table's names: parameters, inputs, outputs
P, U, Y = Flywheel.names()
#: the state array: the number n of wheels, their places (rows of ``axis``), their unit axes
#: and the rows of the pseudo-inverse distributing ḣ among them (the first n of each), the
#: wheels' constants, each wheel's fail time, friction factor and its time,
#: their speeds Ω and, per wheel, 1 while it is held at the momentum limit and 1 while its
#: motor torque is at the limit (_LIMITS)
#: and, for the wheels' imbalance: 1 if any, the angle φ of each wheel and (read only then)
#: its U_s, U_d, r and u (rows)
S = state_table(
    "Flywheel state", n=1, wheel=N_WHEELS, axes=3 * N_WHEELS, distribution=3 * N_WHEELS,
    inertia=1, viscous=1, coulomb=1, torque_limit=1, speed_limit=1, fail=N_WHEELS,
    factor=N_WHEELS, change=N_WHEELS, jitter=1, omega=N_WHEELS, limited=2 * N_WHEELS,
    angle=N_WHEELS, us=N_WHEELS, ud=N_WHEELS, r=3 * N_WHEELS, u=3 * N_WHEELS,
)  # fmt: skip
#: the inputs' places in the slice of them the kernels read (tau_cmd, w_BI_B)
UI = relative(U, U.tau_cmd)
_LIMITS = ("held at the momentum limit", "motor torque at the limit")
#: flywheel_step's status: a wheel reached a limit (step() warns)
NEW_LIMIT = 1


@jitable
def _along_axes(s, values) -> tuple:
    """Σ a_i v_i over the wheels, in B (v_i: speeds for h, J Ω̇_i for ḣ)."""
    x = y = z = 0.0
    for i in range(int(s[S.n])):
        at = S.axes + 3 * i
        ax, ay, az = s[at], s[at + 1], s[at + 2]
        x += ax * values[i]
        y += ay * values[i]
        z += az * values[i]
    return x, y, z


@jitable
def _momentum(s) -> tuple:
    """h = J Σ a_i Ω_i: the assembly's momentum relative to the body, in B."""
    hx, hy, hz = _along_axes(s, s[S.omega : S.omega + N_WHEELS])
    J = s[S.inertia]
    return J * hx, J * hy, J * hz


@jitable
def _drive(u, s, t: float):
    """(motor torques m_i, J Ω̇_i at the communication point, held, at the momentum limit,
    at the torque limit), per wheel, at time t.

    Each wheel is asked for its share (least squares over the axes) of
    ḣ_req = −τ_cmd − w × h; :func:`_wheel` applies its friction and limits (and its
    faults at t).
    """
    tx, ty, tz = u[UI.tau_cmd], u[UI.tau_cmd + 1], u[UI.tau_cmd + 2]
    wx, wy, wz = u[UI.w_BI_B], u[UI.w_BI_B + 1], u[UI.w_BI_B + 2]
    hx, hy, hz = _momentum(s)
    rx = -tx - (wy * hz - wz * hy)  # hdot_req = −τ_cmd − w × h
    ry = -ty - (wz * hx - wx * hz)
    rz = -tz - (wx * hy - wy * hx)
    torques, net = [0.0] * N_WHEELS, [0.0] * N_WHEELS
    held, momentum, torque = [False] * N_WHEELS, [False] * N_WHEELS, [False] * N_WHEELS
    cv, cc, tau_max, speed_max = s[S.viscous], s[S.coulomb], s[S.torque_limit], s[S.speed_limit]
    for k in range(int(s[S.n])):
        at = S.distribution + 3 * k
        px, py, pz = s[at], s[at + 1], s[at + 2]
        torques[k], net[k], held[k], momentum[k], torque[k] = _wheel(
            s[S.omega + k], px * rx + py * ry + pz * rz, cv, cc, tau_max, speed_max,
            t >= s[S.fail + k], friction(s, k, t),
        )  # fmt: skip
    return torques, net, held, momentum, torque


@jitable
def friction(s, k: int, t: float) -> float:
    """Wheel k's friction factor at t (1 before its change)."""
    return s[S.factor + k] if t >= s[S.change + k] else 1.0


@jitable
def _wheel(
    w: float,
    n: float,
    cv: float,
    cc: float,
    tau_max: float,
    speed_max: float,
    failed: bool,
    factor: float,
) -> tuple:
    """One wheel at speed Ω = ``w`` asked for J Ω̇ = ``n``: (motor torque m, delivered
    J Ω̇, held, at the momentum limit, at the torque limit).

    m = n plus the friction cv Ω + cc sign(Ω) (at rest: the breakaway cc in the sense
    of n), clipped to ±torque_limit; J Ω̇ = m − friction (at rest: 0 while |m| ≤ cc).
    A held wheel (at the momentum limit, friction compensated within the torque limit)
    keeps its speed exactly: J Ω̇ = 0 by construction, not up to rounding, so that the
    limit does not toggle from one step to the next.  A ``failed`` wheel's m is 0; the
    friction acting is ``factor`` times the nominal cv, cc the drive compensates.
    """
    if failed:
        return 0.0, _net(0.0, w, factor * cv, factor * cc), False, False, False
    at_momentum = at_torque = held = False
    if (w >= speed_max and n > 0.0) or (w <= -speed_max and n < 0.0):
        n = 0.0
        at_momentum = held = True
    if w > 0.0:
        m = n + cv * w + cc
    elif w < 0.0:
        m = n + cv * w - cc
    else:
        m = n + cc if n > 0.0 else n - cc if n < 0.0 else 0.0
    if m > tau_max or m < -tau_max:
        m = tau_max if m > tau_max else -tau_max
        at_torque, held = True, False
    if held and factor == 1.0:
        return m, 0.0, True, at_momentum, at_torque
    return m, _net(m, w, factor * cv, factor * cc), False, at_momentum, at_torque


@jitable
def _net(m: float, w: float, cv: float, cc: float) -> float:
    """J Ω̇ of a wheel at speed Ω = ``w`` under the motor torque m and the friction cv, cc
    (at rest: 0 while |m| ≤ cc)."""
    if w > 0.0:
        return m - cv * w - cc
    if w < 0.0:
        return m - cv * w + cc
    if abs(m) <= cc:
        return 0.0
    return m - cc if m > 0.0 else m + cc


@step_kernel(Flywheel)
def flywheel_step(values, state, t, dt):
    """Each wheel over ``dt`` with its motor torque held (:func:`wheel_step`; a held wheel
    keeps its speed); returns NEW_LIMIT when a wheel reaches a limit it was not at."""
    u, s = floats(values[U.tau_cmd : U.w_BI_B + 3]), floats(state[: S.us])
    torques, _, held, momentum, torque = _drive(u, s, t)
    status = 0
    J, cv, cc, speed_max = s[S.inertia], s[S.viscous], s[S.coulomb], s[S.speed_limit]
    for k in range(int(s[S.n])):
        for j, limited in ((0, momentum[k]), (1, torque[k])):
            at = S.limited + 2 * k + j
            if limited and s[at] == 0.0:
                status = NEW_LIMIT
            state[at] = 1.0 if limited else 0.0
        at = S.omega + k
        before = s[at]  # (compiled, s is state itself)
        if not held[k]:
            f = friction(s, k, t)
            state[at] = wheel_step(before, torques[k], dt, J, f * cv, f * cc, speed_max)
        if s[S.jitter] != 0.0:  # the trapezoidal rule (module docstring)
            state[S.angle + k] = s[S.angle + k] + 0.5 * (before + state[at]) * dt
    return status


@output_kernel(Flywheel)
def flywheel_output(values, state, t):
    """h, ḣ, the speeds and motor torques (at the wheels' places) and whether saturated."""
    u, s = floats(values[U.tau_cmd : U.w_BI_B + 3]), floats(state[: S.us])
    torques, net, _, momentum, torque = _drive(u, s, t)
    h = _momentum(s)
    hdot = _along_axes(s, net)
    saturated = False
    for k in range(N_WHEELS):
        values[Y.speed + k] = 0.0
        values[Y.motor_torque + k] = 0.0
    for k in range(int(s[S.n])):
        wheel = int(s[S.wheel + k])
        values[Y.speed + wheel], values[Y.motor_torque + wheel] = s[S.omega + k], torques[k]
        saturated = saturated or momentum[k] or torque[k]
    for k in range(3):
        values[Y.h + k], values[Y.hdot + k] = h[k], hdot[k]
    values[Y.saturated] = 1.0 if saturated else 0.0
    if s[S.jitter] != 0.0:
        rows = _jitter(floats(state), net)
        force, torque = total([r[3] for r in rows]), total([r[5] for r in rows])
        for k in range(int(s[S.n])):
            at = 3 * int(s[S.wheel + k])
            put(values, Y.h_jitter_B + at, rows[k][0])
            put(values, Y.hdot_jitter_B + at, rows[k][1])
        put(values, Y.f_jitter_B, force)
        put(values, Y.tau_jitter_B, torque)
    return 0


@jitable
def _jitter(s, net) -> list:
    """Each wheel's :func:`.imbalance.rotor_imbalance` (h_u, ḣ_u, ḧ_u, F, Ḟ, τ, τ̇) now,
    its speed changing at the delivered J Ω̇ = ``net``."""
    rows = []
    J = s[S.inertia]
    for k in range(int(s[S.n])):
        axis = (s[S.axes + 3 * k], s[S.axes + 3 * k + 1], s[S.axes + 3 * k + 2])
        u = (s[S.u + 3 * k], s[S.u + 3 * k + 1], s[S.u + 3 * k + 2])
        r = (s[S.r + 3 * k], s[S.r + 3 * k + 1], s[S.r + 3 * k + 2])
        rows.append(
            rotor_imbalance(
                s[S.us + k], s[S.ud + k], r, axis, u, s[S.omega + k], net[k] / J,
                s[S.angle + k], (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
            )
        )  # fmt: skip
    return rows
