"""Rigid satellite hub carrying momentum-exchange devices ([Zhao 2016] eqs 1–3).

States: the attitude q_BI and the *total* angular momentum H_I (hub + devices, inertial
axes).  With J the hub inertia, h the devices' momentum relative to the body (in B) and
τ the external torque on the body (in B: ``tau_ext``, the environment's, plus
``tau_ctrl``, that of external-torque actuators such as magnetorquers)::

    w_BI_B = J⁻¹ (C_BI H_I − h)                       (eq. 2 solved for w)
    q̇_BI  = ½ q_BI ⊗ (0, w_BI_B)
    Ḣ_I   = C_BIᵀ (τ_ext + τ_gg),   τ_gg = 3 μ/|r|⁵ · r_B × J r_B,   r_B = C_BI r_I

which is the hub equation J ẇ = −w × (J w + h) − ḣ + τ (eq. 3 with all terms kept):
H_I changes only by external torque, so total momentum is conserved exactly whatever the
co-simulation step.  Across a step the inputs the model integrates follow their
derivatives (FMI 2.0 input interpolation, components/model.py): the devices' momentum
h(t_c + s) = h + ḣ s + ½ ḧ s², with ḣ its slope (the derivative a host set for ``h_*``,
else the input ``hdot_*``: :meth:`Model.slope`) and ḧ the derivative set for ``hdot_*``;
τ + τ̇ s and r_I + ṙ s likewise (never set: zero, the input held).  q_OI and w_OI_O
enter only the outputs, at communication points.  Integration: classical RK4 with
sub-steps of at most 0.02 rad of rotation.  The gravity-gradient torque is skipped when
J ∝ 1, where it vanishes identically.

Outputs relative to the orbit frame O (inputs q_OI, w_OI_O): q_BO = q_OI* ⊗ q_BI,
w_BO_B = w_BI_B − C_BO w_OI_O and the 1-2-3 Euler angles of B relative to O on a branch
continuous in time (pitch may pass through ±90°; see rotations.euler123), with their
rates (video-SAR eq. 13).

Output derivatives (``output_derivatives``), at the current time with the inputs as
interpolated: q̇_BI and Ḣ_I from the equations above, ẇ_BI_B = J⁻¹ (−w × C_BI H_I + τ − ḣ),
q̇_BO = ½ q_BO ⊗ (0, w_BO_B), ẇ_BO_B = ẇ_BI_B + w_BO_B × C_BO w_OI_O − C_BO ẇ_OI_O (ẇ_OI_O
the derivative set for w_OI_O), the Euler angles' first and second derivatives
(rotations.euler123_ddot).

Flexible appendages (hybrid coordinates, DESIGN.md §3.2; [Likins 1971], [Hablani 1982]).
Up to N_MODES mass-normalised modes of appendages clamped to the hub, with constrained
frequencies ω_k,
damping ratios ζ_k and rotational participation factors L_k (rows of ``modal_coupling``; a
zero row is an unused mode); ``inertia`` stays the whole undeformed spacecraft's::

    J ω̇ + Σ L_kᵀ η̈_k = τ − ḣ − ω × (J ω + h + Σ L_kᵀ η̇_k)
    η̈_k + 2 ζ_k ω_k η̇_k + ω_k² η_k + L_k ω̇ = 0

The states are H_I (its body components H_B = J ω + h + Σ L_kᵀ η̇_k, still changed only by
the external torque), q_BI, η_k and the modal momenta p_k = η̇_k + L_k ω, which make every
rate explicit::

    ω = M⁻¹ (C_BI H_I − h − Σ p_k L_k),   M = J − Σ L_kᵀ L_k   (the hub alone, > 0)
    η̇_k = p_k − L_k ω,   ṗ_k = −ω_k² η_k − 2 ζ_k ω_k η̇_k

RK4 takes sub-steps of at most MAX_MODAL_PHASE of the fastest unconstrained mode too.

Further devices and torques ([Zhao 2016]'s three device slots are fixed by DESIGN.md §3):
the rows of ``h_extra``/``hdot_extra`` are momentum devices as h_cmg/hdot_cmg are (summed
after them), the rows of ``tau_extra`` torques as ``tau_ext`` is; an unconnected row is zero
and changes nothing, bit for bit.  A row with a non-zero ``h_extra_frequency`` Ω is a
rotating momentum, a rotor imbalance's (CmgCluster's and Flywheel's ``h_jitter_B``): its
mean is zero and it turns far faster than the hub and the modes, so it is not integrated
(a macro step would alias it) but enters the outputs as the body's steady response, exact
to O((ω_k/Ω)², |ω|/Ω): the appendages stay inertial, the hub alone counter-rotates::

    θ̃ = M⁻¹ Σ ḣ_r / Ω_r²,   ω̃ = −M⁻¹ Σ h_r                (the rotating rows r)
    q_BI = q̄_BI ⊗ (cos |θ̃|/2, sin(|θ̃|/2) θ̃/|θ̃|),   w_BI_B = ω̄ + ω̃,   η = η̄ − L θ̃

(q̄, ω̄, η̄ the integrated mean motion; H_B is the same with or without them, so H_I stays
exact).  A rotating row whose derivative a host set is turned to the step's end as the
sinusoid it is, not moved along a line, and its derivatives are consumed (:func:`_turned`).
The output derivatives are the mean motion's: a host extrapolating an output over a step
along the oscillation's slope would be Ω H times its amplitude off, along the mean's at most
its amplitude.  docs/jitter.md measures this against a monolithic reference that resolves the
rotors.

``step`` and ``output`` are each one kernel (components/runtime/jit.py: their Python in short
runs, compiled by numba in long ones, bit for bit the same) on the model's value array,
read and written at the offsets of the variable table, and on ``self.state``: q_BI, H_I,
η, p, the last q_BO and euler_BO, and the constants ``initialize`` derives (the state table
``S``).  A kernel returns a status code; the methods raise its ModelError.
"""

from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .orbit_environment import DEFAULT_SEMI_MAJOR_AXIS
from .rotations import (
    IDENTITY_Q,
    dcm,
    dcm_from_euler123,
    euler123,
    euler123_ddot,
    euler123_dot,
    qmul,
    quat_from_dcm,
)
from .runtime.flat import all_zero, matrix, put, quaternion, relative, state_table, vector
from .runtime.jit import floats, jitable, output_kernel, step_kernel
from .variables import input_, output, parameter
from .vectors import add, dot, norm, quat_dot, quat_norm, rotate, rotate_back, sub

MAX_ROTATION_PER_SUBSTEP = 0.02  # rad
#: rad of the fastest unconstrained mode per RK4 sub-step (its frequency then errs by
#: (ω h)⁴/120 ≈ 1e-6 relative)
MAX_MODAL_PHASE = 0.1
MAX_SUBSTEPS = 10000
N_MODES = 6  # two wings' out-of-plane, in-plane and torsion modes
N_EXTRA = 6  # further momentum devices: a CMG cluster's jitter, four wheels', one more
N_TORQUES = 4  # further torques: a magnetorquer, a second disturbance model, ...
#: rad/s, above the orbit-frame rate of any Earth orbit: h/r² is largest at the perigee of an
#: orbit grazing the surface, √2 · √(μ/R³) ≈ 1.75e-3 rad/s for e → 1
MAX_ORBIT_FRAME_RATE = 2e-3
DEVICES = ("cmg", "wheel", "payload")
MOMENTUM_INPUTS = tuple(f"h_{d}" for d in DEVICES) + ("h_extra", "h_extra_frequency")
#: the inputs the rotating rows' steady response θ̃ is made of
JITTER_INPUTS = ("hdot_extra", "h_extra_frequency")
#: r_I when unconnected: the default orbit's radius (OrbitEnvironment) on the nadir
#: (+z_O) of the identity orbit frame that q_OI defaults to, so that the FMU at its
#: defaults is a satellite at 681 km with the gravity gradient on
DEFAULT_R_I = (0.0, 0.0, -DEFAULT_SEMI_MAJOR_AXIS)


def _device_inputs():
    for device in DEVICES:
        yield input_(
            f"h_{device}",
            "N.m.s",
            f"{device} angular momentum relative to the body, in B",
            shape=(3,),
            optional=f"zero: no {device} momentum",
        )
        yield input_(
            f"hdot_{device}",
            "N.m",
            f"time derivative of h_{device} as seen in B",
            shape=(3,),
            optional=f"zero: constant {device} momentum",
            derivative_of=f"h_{device}",
        )


class SatelliteDynamics(Model):
    """Rigid-body attitude dynamics with internal momentum and gravity-gradient torque."""

    INTERPOLATES_INPUTS = True
    OUTPUT_DERIVATIVES = True

    _BO_DEPENDS = ("q_OI",) + JITTER_INPUTS
    _RATE_DEPENDS = MOMENTUM_INPUTS + _BO_DEPENDS + ("w_OI_O",)
    VARIABLES = (
        parameter(
            "inertia",
            956.0 * np.eye(3),
            "kg.m2",
            "hub inertia about the centre of mass, in B",
            shape=(3, 3),
        ),
        parameter(
            "attitude0",
            0.0,
            "rad",
            "initial 1-2-3 Euler angles (roll, pitch, yaw) of B relative to O",
            shape=(3,),
            display_unit="deg",
        ),
        parameter(
            "rate0",
            0.0,
            "rad/s",
            "initial angular velocity of B relative to O, in B",
            shape=(3,),
            display_unit="deg/s",
        ),
        parameter(
            "gravity_gradient", True, "1", "apply the gravity-gradient torque", type="Boolean"
        ),
        parameter("mu", 3.986004418e14, "m3/s2", "gravitational parameter of the Earth"),
        parameter(
            "modal_frequency",
            0.0,
            "rad/s",
            "constrained frequency of each appendage mode (appendage clamped to a fixed hub)",
            shape=(N_MODES,),
        ),
        parameter("modal_damping", 0.0, "1", "damping ratio of each mode", shape=(N_MODES,)),
        parameter(
            "modal_coupling",
            0.0,
            "kg0.5.m",
            "rotational participation factors L_k of each mass-normalised mode, in B (rows; "
            "a zero row is an unused mode)",
            shape=(N_MODES, 3),
        ),
        parameter("eta0", 0.0, "kg0.5.m", "initial modal coordinates", shape=(N_MODES,)),
        parameter("eta_dot0", 0.0, "kg0.5.m/s", "initial modal rates", shape=(N_MODES,)),
        *_device_inputs(),
        input_(
            "tau_ext",
            "N.m",
            "other external torque on the body, in B",
            shape=(3,),
            optional="zero: no other external torque",
        ),
        input_(
            "tau_ctrl",
            "N.m",
            "torque of external-torque actuators (magnetorquers, thrusters) on the body, in "
            "B; added to tau_ext",
            shape=(3,),
            optional="zero: no such actuator",
        ),
        input_(
            "r_I",
            "m",
            "satellite position in I (for the gravity gradient); the start "
            "value is the default orbit's radius at nadir of the identity orbit frame",
            DEFAULT_R_I,
            shape=(3,),
            optional="a fixed position, the default orbit's radius at nadir of the "
            "identity orbit frame: connect it for the gravity gradient of a real "
            "orbit",
        ),
        input_(
            "q_OI",
            "1",
            "attitude of the orbit frame O relative to I",
            IDENTITY_Q,
            shape=(4,),
            optional="identity: O is the inertial frame (q_BO = q_BI)",
        ),
        input_(
            "w_OI_O",
            "rad/s",
            "angular velocity of O relative to I, in O",
            shape=(3,),
            optional="zero: O does not rotate",
        ),
        input_(
            "h_extra",
            "N.m.s",
            "angular momentum of further devices relative to the body, in B, one a row",
            shape=(N_EXTRA, 3),
            optional="zero: no further device",
        ),
        input_(
            "hdot_extra",
            "N.m",
            "time derivative of h_extra as seen in B",
            shape=(N_EXTRA, 3),
            optional="zero: constant momentum",
            derivative_of="h_extra",
        ),
        input_(
            "h_extra_frequency",
            "rad/s",
            "angular frequency at which a row of h_extra rotates (a rotor imbalance's spin "
            "rate): the row is taken as the body's steady response to it, not integrated",
            shape=(N_EXTRA, 1),
            optional="zero: a device integrated as h_cmg is",
        ),
        input_(
            "tau_extra",
            "N.m",
            "further external torques on the body, in B, one source a row",
            shape=(N_TORQUES, 3),
            optional="zero: no further torque",
        ),
        output("q_BI", "1", "attitude of B relative to I", shape=(4,), depends=JITTER_INPUTS),
        output(
            "w_BI_B",
            "rad/s",
            "angular velocity of B relative to I, in B",
            shape=(3,),
            depends=MOMENTUM_INPUTS,
            display_unit="deg/s",
        ),
        output("q_BO", "1", "attitude of B relative to O", shape=(4,), depends=_BO_DEPENDS),
        output(
            "euler_BO",
            "rad",
            "1-2-3 Euler angles of B relative to O (continuous branch)",
            shape=(3,),
            depends=_BO_DEPENDS,
            display_unit="deg",
        ),
        output(
            "euler_rate_BO",
            "rad/s",
            "rates of euler_BO",
            shape=(3,),
            depends=_RATE_DEPENDS,
            display_unit="deg/s",
        ),
        output(
            "w_BO_B",
            "rad/s",
            "angular velocity of B relative to O, in B",
            shape=(3,),
            depends=_RATE_DEPENDS,
            display_unit="deg/s",
        ),
        output(
            "H_I",
            "N.m.s",
            "total angular momentum (hub + appendages + devices), in I",
            shape=(3,),
        ),
        output(
            "eta",
            "kg0.5.m",
            "modal coordinates",
            shape=(N_MODES,),
            depends=JITTER_INPUTS,
        ),
        output(
            "eta_dot",
            "kg0.5.m/s",
            "modal rates",
            shape=(N_MODES,),
            depends=MOMENTUM_INPUTS,
        ),
    )
    INITIAL_STATE_DEPENDS = MOMENTUM_INPUTS + ("q_OI", "w_OI_O")

    def initialize(self, t0):
        p, u = self.p, self.u
        J = np.array(p.inertia)
        if not np.allclose(J, J.T, rtol=1e-12, atol=1e-12 * np.abs(J).max()):
            raise ModelError(f"inertia must be symmetric, got {J.tolist()}")
        moments = np.linalg.eigvalsh(J)  # ascending
        if np.any(moments <= 0):
            raise ModelError(f"inertia must be positive definite, got {J.tolist()}")
        if moments[2] > (moments[0] + moments[1]) * (1 + 1e-12):
            raise ModelError(
                f"inertia {J.tolist()}: no rigid body has it: its largest principal moment "
                f"{moments[2]:.6g} exceeds the sum of the other two ({moments[0]:.6g} + "
                f"{moments[1]:.6g}; the triangle inequality of principal moments)"
            )
        # the gravity-gradient torque r × J r vanishes identically for J ∝ 1
        isotropic = np.allclose(J, J[0, 0] * np.eye(3), rtol=1e-15, atol=0.0)
        modes, L, M = self._modes(J)
        q_OI = _unit(u.q_OI, "q_OI")
        C_BO = dcm_from_euler123(p.attitude0)
        q_BO = quat_from_dcm(C_BO)
        q_BI = qmul(q_OI, q_BO)
        w_BI_B = p.rate0 + C_BO @ u.w_OI_O
        H_B = rotate(J.tolist(), w_BI_B)
        h = (u.h_cmg + u.h_wheel + u.h_payload).tolist()
        extra = _extras(*_inputs(self.values, ALL))
        if extra[0]:
            h = [h[i] + extra[1][i] for i in range(3)]
        #: the state and the constants of the step and output kernels (STATE)
        self.state = state = S.zeros()
        if modes:  # H_B = J ω + h + Σ L_kᵀ η̇_k, p_k = η̇_k + L_k ω
            rates = p.eta_dot0[modes]
            H_B = (np.array(H_B) + L.T @ rates).tolist()
            put(state, S.mode, modes)
            put(state, S.eta, p.eta0[modes])
            put(state, S.p, rates + L @ w_BI_B)
            put(state, S.L, L.reshape(-1))
            put(state, S.w2, p.modal_frequency[modes] ** 2)
            put(state, S.c, 2.0 * p.modal_damping[modes] * p.modal_frequency[modes])
            state[S.modal_rate] = _fastest_mode(J, L, p.modal_frequency[modes])
        state[S.modes] = len(modes)
        state[S.q_BI : S.q_BI + 4] = q_BI
        state[S.H_I : S.H_I + 3] = rotate_back(dcm(q_BI), [H_B[i] + h[i] for i in range(3)])
        state[S.q_BO : S.q_BO + 4] = q_BO
        state[S.euler : S.euler + 3] = p.attitude0
        state[S.J : S.J + 9] = J.reshape(-1)
        state[S.J_inv : S.J_inv + 9] = np.linalg.inv(J).reshape(-1)
        state[S.M_inv : S.M_inv + 9] = np.linalg.inv(M).reshape(-1)
        state[S.mu] = p.mu
        state[S.gravity_gradient] = p.gravity_gradient and not isotropic
        state[S.needs_position] = p.gravity_gradient
        self.t = t0
        self.remember_initial_inputs()

    def _modes(self, J) -> tuple[list, np.ndarray, np.ndarray]:
        """(the used modes, their rows of modal_coupling, M = J − Σ L_kᵀ L_k), checked."""
        p = self.p
        coupling, frequency, damping = p.modal_coupling, p.modal_frequency, p.modal_damping
        if not (np.all(np.isfinite(frequency)) and np.all(frequency >= 0)):
            raise ModelError(f"modal_frequency must be finite and >= 0, got {frequency.tolist()}")
        if not (np.all(np.isfinite(damping)) and np.all(damping >= 0)):
            raise ModelError(f"modal_damping must be finite and >= 0, got {damping.tolist()}")
        modes = [k for k in range(N_MODES) if np.any(coupling[k] != 0.0)]
        for k in range(N_MODES):
            if k in modes and not frequency[k] > 0:
                raise ModelError(
                    f"mode {k + 1} is coupled (modal_coupling[{k + 1},:] = "
                    f"{coupling[k].tolist()}) but modal_frequency[{k + 1}] is "
                    f"{frequency[k]}: a mode needs a positive frequency"
                )
            if k not in modes and (p.eta0[k] != 0.0 or p.eta_dot0[k] != 0.0):
                raise ModelError(
                    f"mode {k + 1} is unused (modal_coupling[{k + 1},:] is zero) but eta0 or "
                    f"eta_dot0 is not zero ({p.eta0[k]}, {p.eta_dot0[k]})"
                )
        L = coupling[modes]
        M = J - L.T @ L
        if np.any(np.linalg.eigvalsh(M) <= 0):
            raise ModelError(
                "modal_coupling is too large for inertia: J − Σ L_kᵀ L_k (the hub alone "
                f"without its appendages) must be positive definite, got {M.tolist()}"
            )
        return modes, L, M

    def step(self, t, dt):
        self.check_initial_inputs(dt)
        status = _step(self.values, self.state, self.t, dt)
        if status == SLOPE_CONFLICT:
            conflicts = [
                text
                for h in (*(f"h_{d}" for d in DEVICES), "h_extra")
                for text in self.slope_conflicts(h, "hdot" + h[1:])
            ]
            self.warnings.append(
                f"t={t:.6g} s: {'; '.join(conflicts)}: the derivative a host sets for h_* "
                "(fmi2SetRealInputDerivatives) is its slope over the step, hdot_* only "
                "where none was set (reported once)"
            )
            status = OK
        if status == NO_POSITION:
            raise ModelError(
                "gravity_gradient is on but r_I is zero: connect r_I or set "
                "gravity_gradient = false"
            )
        if status == TOO_MANY_SUBSTEPS:
            s, (u, d, g) = floats(self.state), _inputs(self.values, ALL)
            h0 = add(_device_sum(u, UI.h_cmg, UI.h_wheel, UI.h_payload), _extras(u, d, g)[1])
            rate, needed = _substeps(_body_rate(s, h0), s, dt)
            n = math.ceil(needed) if math.isfinite(needed) else needed
            raise ModelError(
                f"t={t:.6g} s: body rate {rate:.3g} rad/s would need "
                f"{n} sub-steps of {dt:g} s: the state is unphysical"
            )
        if status == NON_FINITE:
            raise ModelError(f"non-finite state at t={t + dt:.6g} s")
        self.t = t + dt

    def output(self):
        if _output(self.values, self.state, self.t) == NOT_UNIT:
            _unit(self.u.q_OI, "q_OI")  # raises its ModelError

    def output_derivatives(self):
        """See the module docstring: d/dt of the outputs at ``self.t``."""
        s, y = floats(self.state), self.y
        u, d, g = _inputs(self.values, ALL)
        q_BI, H_I = quaternion(s, S.q_BI), vector(s, S.H_I)
        J, M_inv = matrix(s, S.J), matrix(s, S.M_inv)
        slope, _, _, r_rate, tau_rate = _rates(u, d, g)
        h, tau = _device_sum(u, UI.h_cmg, UI.h_wheel, UI.h_payload), external(u)
        extra = _extras(u, d, g)
        if extra[0]:
            h, slope = add(h, extra[1]), add(slope, extra[2])
            tau, tau_rate = add(tau, extra[4]), add(tau_rate, extra[5])
        n = int(s[S.modes])
        eta, momenta = s[S.eta : S.eta + n], s[S.p : S.p + n]
        L, w2, c = s[S.L : S.L + 3 * n], s[S.w2 : S.w2 + n], s[S.c : S.c + n]
        torque = (tau, vector(u, UI.r_I), tau_rate, r_rate)
        q_dot_H_dot = _derivative(
            q_BI + H_I, 0.0, add(h, _modal_momentum(momenta, L, n)), slope, (0.0,) * 3,
            torque, J, M_inv, s[S.mu], s[S.gravity_gradient] != 0.0, (False, False, False),
        )  # fmt: skip
        C_BI = dcm(q_BI)
        w_mean = _rate(q_BI, H_I, add(h, _modal_momentum(momenta, L, n)), M_inv)
        H_B = rotate(C_BI, H_I)
        tau_B = rotate(C_BI, q_dot_H_dot[4:])
        eta_dot = [momenta[k] - (L[3 * k] * w_mean[0] + L[3 * k + 1] * w_mean[1]
                                 + L[3 * k + 2] * w_mean[2]) for k in range(n)]  # fmt: skip
        p_dot = [-w2[k] * eta[k] - c[k] * eta_dot[k] for k in range(n)]
        modal = _modal_momentum(p_dot, L, n)
        w_dot = rotate(M_inv, np.subtract(np.subtract(tau_B, slope), modal) - np.cross(w_mean, H_B))
        w, w_BO, eta_rate = y.w_BI_B.tolist(), y.w_BO_B.tolist(), y.eta_dot
        euler, euler_dot = y.euler_BO.tolist(), y.euler_rate_BO.tolist()
        if extra[0] and (_nonzero(extra[8]) or _nonzero(extra[9])):
            # rotating rows: the mean motion's rates (module docstring), ω̄ = ω − ω̃
            mean = rotate(M_inv, extra[8])
            w, w_BO = add(w, mean), add(w_BO, mean)
            euler_dot = list(euler123_dot(euler, w_BO))
            eta_rate = np.zeros(N_MODES)
            eta_rate[[int(k) for k in s[S.mode : S.mode + n]]] = eta_dot
        q_dot = [0.5 * x for x in qmul(y.q_BI, (0.0, *w))]
        eta_ddot = [p_dot[k] - float(np.dot(L[3 * k : 3 * k + 3], w_dot)) for k in range(n)]
        q_BO = y.q_BO.tolist()
        C_BO = dcm(q_BO)
        w_OI_B = rotate(C_BO, self.u.w_OI_O.tolist())
        w_BO_dot = (
            np.add(w_dot, np.cross(w_BO, w_OI_B)) - rotate(C_BO, self.input_rate("w_OI_O"))
        ).tolist()
        by_mode = np.zeros((2, N_MODES))
        modes = [int(k) for k in s[S.mode : S.mode + n]]
        by_mode[0, modes], by_mode[1, modes] = eta_rate[modes], eta_ddot
        return np.array(
            [
                *q_dot,
                *w_dot,
                *(0.5 * x for x in qmul(q_BO, (0.0, *w_BO))),
                *euler_dot,
                *euler123_ddot(euler, euler_dot, w_BO, w_BO_dot),
                *w_BO_dot,
                *q_dot_H_dot[4:],
                *by_mode.reshape(-1),
            ]
        )

    @classmethod
    def state_problem(cls, attributes, reference):
        """The kernels index the value array with the modes' places and count."""
        rows = slice(S.modes, S.mode + N_MODES)
        if not np.array_equal(attributes["state"][rows], reference["state"][rows]):
            return "modes (count, places) are not its parameters'"
        return ""

    def initial_input_jumps(self, used, dt):
        """Bounds of one step of dt (margin 4): the orbit frame turns by at most
        |w_OI_O| dt, its rate changes by a small fraction, each device's momentum by
        |hdot| dt (the rows of h_extra one by one; a rotating row's frequency not at all).
        A host that passed nothing in initialisation jumps by the whole orbit attitude or
        stored momentum (radians, tens of N·m·s).  The frame's rate is taken as at least
        that of any Earth orbit (``MAX_ORBIT_FRAME_RATE``), so that a system leaving the
        optional w_OI_O open still passes its moving q_OI."""
        u, jumps = self.u, {}
        w = max(np.linalg.norm(used["w_OI_O"]), np.linalg.norm(u.w_OI_O), MAX_ORBIT_FRAME_RATE)
        cos_half = abs(float(np.dot(_unit(u.q_OI, "q_OI"), _unit(used["q_OI"], "q_OI"))))
        angle = 2.0 * math.acos(min(1.0, cos_half))
        if angle > 4.0 * w * dt + 1e-9:
            jumps["q_OI"] = f"turned {math.degrees(angle):.4g} deg"
        change = np.linalg.norm(u.w_OI_O - used["w_OI_O"])
        if change > 0.01 * w + 1e-12:
            jumps["w_OI_O"] = f"changed by {change:.3g} rad/s"
        frequency = u.h_extra_frequency.reshape(-1)
        if not np.array_equal(frequency, used["h_extra_frequency"]):
            jumps["h_extra_frequency"] = (
                f"{used['h_extra_frequency'].tolist()} -> {frequency.tolist()}"
            )
        for h in MOMENTUM_INPUTS[:-1]:
            now, then = np.reshape(getattr(u, h), (-1, 3)), np.reshape(used[h], (-1, 3))
            hdot = np.reshape(self.slope(h, "hdot" + h[1:]), (-1, 3))
            change = np.linalg.norm(now - then, axis=1)
            bound = 4.0 * np.linalg.norm(hdot, axis=1) * dt + 1e-9 * (
                1.0 + np.linalg.norm(then, axis=1)
            )
            if np.any(change > bound):
                jumps[h] = f"changed by {change.max():.4g} N.m.s"
        return jumps


def _fastest_mode(J, L, frequency) -> float:
    """The highest unconstrained frequency (rad/s) of the linearised hub and modes: √λ of
    det(K − λ [[J, Lᵀ], [L, 1]]) = 0, K = diag(0, 0, 0, ω_k²)."""
    n = len(frequency)
    mass = np.block([[J, L.T], [L, np.eye(n)]])
    stiffness = np.zeros((3 + n, 3 + n))
    stiffness[3:, 3:] = np.diag(frequency**2)
    return float(np.sqrt(np.max(np.linalg.eigvals(np.linalg.solve(mass, stiffness)).real)))


# -- step and output: kernels on the value array (components/runtime/jit.py) -------------
P, U, Y = SatelliteDynamics.names()
#: the derivatives a host set for the inputs, and 1 where it set one (of h_*)
DU, GIVEN = SatelliteDynamics.derivative_names()
#: SatelliteDynamics.state: the state (q_BI, H_I), the last output's q_BO and euler_BO
#: (their sign and branch are kept continuous), and constants set by initialize: the hub
#: inertia and its inverse (row-major), μ, whether to apply the gravity-gradient torque
#: (gravity_gradient on and J not ∝ 1) and whether r_I must not be zero (gravity_gradient
#: on); 1 once a conflict of hdot_* with a derivative set for h_* was reported; the fastest
#: unconstrained mode's frequency, the number of used modes, their places (rows of
#: modal_coupling), their η and momenta p, and their constants: L rows, ω_k², 2 ζ_k ω_k,
#: and (J − Σ L_kᵀ L_k)⁻¹ (J⁻¹ without modes)
S = state_table(
    "SatelliteDynamics state", q_BI=4, H_I=3, q_BO=4, euler=3, J=9, J_inv=9, mu=1,
    gravity_gradient=1, needs_position=1, slope_conflict=1, modal_rate=1, modes=1,
    mode=N_MODES, eta=N_MODES, p=N_MODES, L=3 * N_MODES, w2=N_MODES, c=N_MODES, M_inv=9,
)  # fmt: skip
#: the rows a rigid hub with its three fixed devices reads (the modes' rows come after)
RIGID = S.modes + 1
#: the kernels' status codes (the Python wrapper raises the message, or warns: a step
#: returning SLOPE_CONFLICT is done)
OK, NO_POSITION, TOO_MANY_SUBSTEPS, NON_FINITE, NOT_UNIT, SLOPE_CONFLICT = range(6)
#: The kernels read the inputs, the derivatives a host set for them and the flags of those
#: set as three slices of the value array (:func:`_inputs`), by these offsets from each
#: slice's start; the fixed inputs come first (FIXED scalars), the rows of further devices
#: and torques after them (ALL with them)
UI, DI, GI = relative(U, U.h_cmg), relative(DU, DU.h_cmg), relative(GIVEN, GIVEN.h_cmg)
FIXED, ALL = U.w_OI_O + 3 - U.h_cmg, U.tau_extra + 3 * N_TORQUES - U.h_cmg


@step_kernel(SatelliteDynamics)
def _step(values, state, t, dt):
    """Advance (q_BI, H_I) in ``state`` by ``dt`` with the inputs in ``values``, as
    interpolated (module docstring): RK4 in n = ⌈max|w_BI_B| dt / MAX_ROTATION_PER_SUBSTEP⌉
    sub-steps, q_BI normalised after; with modes or further devices, :func:`_step_extended`.
    Returns the status; on an error nothing changes; SLOPE_CONFLICT (the step done) the
    first time an hdot_* input differs from a derivative set for its h_*."""
    if _extended(values, state):
        return _step_extended(values, state, dt)
    u, d, g = _inputs(values, FIXED)
    s = floats(state[:RIGID])
    h0 = _device_sum(u, UI.h_cmg, UI.h_wheel, UI.h_payload)
    hdot, conflict, curvature, r_rate, tau_rate = _rates(u, d, g)
    tau, r_I = external(u), vector(u, UI.r_I)
    if s[S.needs_position] != 0.0 and r_I[0] == 0.0 and r_I[1] == 0.0 and r_I[2] == 0.0:
        return NO_POSITION
    q_BI, H_I = quaternion(s, S.q_BI), vector(s, S.H_I)
    J, J_inv = matrix(s, S.J), matrix(s, S.J_inv)
    needed = _substeps(_rate(q_BI, H_I, h0, J_inv), s, dt)[1]
    if not needed <= MAX_SUBSTEPS:
        return TOO_MANY_SUBSTEPS
    n = max(1, int(math.ceil(needed)))
    moving = (_nonzero(curvature), _nonzero(tau_rate), _nonzero(r_rate))
    x = _integrate(
        q_BI + H_I, n, dt / n, h0, hdot, curvature, (tau, r_I, tau_rate, r_rate),
        J, J_inv, s[S.mu], s[S.gravity_gradient] != 0.0, moving,
    )  # fmt: skip
    return _stored(state, s, x, 0, conflict)


@jitable
def _inputs(values, n):
    """(u, d, g): the first n inputs (by UI), the derivatives a host set for them (by DI)
    and 1.0 where it set one (by GI)."""
    return (
        floats(values[U.h_cmg : U.h_cmg + n]),
        floats(values[DU.h_cmg : DU.h_cmg + n]),
        floats(values[GIVEN.h_cmg : GIVEN.h_cmg + n]),
    )


@jitable
def _extended(values, state) -> bool:
    """Whether the hub has modes, or a row of h_extra or tau_extra is fed (a value or a
    derivative set): then the step and the outputs are :func:`_step_extended` and
    :func:`_attitude_extended`, else the rigid hub's, unchanged."""
    rows = U.h_cmg + FIXED, U.h_cmg + ALL
    return state[S.modes] != 0.0 or not (
        all_zero(values, *rows) and all_zero(values, GIVEN.h_cmg + FIXED, GIVEN.h_cmg + ALL)
    )


@jitable
def _step_extended(values, state, dt):
    """:func:`_step` with the rows of further devices and torques (:func:`_extras`: the
    ordinary rows added to h_cmg's, the rotating ones left to the outputs) and the modes
    (:func:`_integrate_modes`; without them the rigid hub's RK4 on M⁻¹ = J⁻¹)."""
    s = floats(state)
    u, d, g = _inputs(values, ALL)
    extra = _extras(u, d, g)
    hdot, conflict, curvature, r_rate, tau_rate = _rates(u, d, g)
    h0 = add(_device_sum(u, UI.h_cmg, UI.h_wheel, UI.h_payload), extra[1])
    hdot, curvature, conflict = add(hdot, extra[2]), add(curvature, extra[3]), conflict or extra[7]
    tau, tau_rate = add(external(u), extra[4]), add(tau_rate, extra[5])
    r_I = vector(u, UI.r_I)
    if s[S.needs_position] != 0.0 and r_I[0] == 0.0 and r_I[1] == 0.0 and r_I[2] == 0.0:
        return NO_POSITION
    q_BI, H_I = quaternion(s, S.q_BI), vector(s, S.H_I)
    J, M_inv = matrix(s, S.J), matrix(s, S.M_inv)
    needed = _substeps(_body_rate(s, h0), s, dt)[1]
    if not needed <= MAX_SUBSTEPS:
        return TOO_MANY_SUBSTEPS
    n = max(1, int(math.ceil(needed)))
    moving = (_nonzero(curvature), _nonzero(tau_rate), _nonzero(r_rate))
    torque = (tau, r_I, tau_rate, r_rate)
    modes = int(s[S.modes])
    if modes == 0:
        x = _integrate(
            q_BI + H_I, n, dt / n, h0, hdot, curvature, torque, J, M_inv, s[S.mu],
            s[S.gravity_gradient] != 0.0, moving,
        )  # fmt: skip
        return _turned(values, dt, _stored(state, s, x, 0, conflict))
    modal = (s[S.L : S.L + 3 * modes], s[S.w2 : S.w2 + modes], s[S.c : S.c + modes])
    start = [*q_BI, *H_I, *s[S.eta : S.eta + modes], *s[S.p : S.p + modes]]
    y = _integrate_modes(
        start, modes, modal, n, dt / n, h0, hdot, curvature, torque, J, M_inv, s[S.mu],
        s[S.gravity_gradient] != 0.0, moving,
    )  # fmt: skip
    return _turned(values, dt, _stored(state, s, y, modes, conflict))


@jitable
def _turned(values, dt, status):
    """``status``, and if the step was done (OK, SLOPE_CONFLICT) every rotating row's
    scalar whose derivative a host set (its h_extra's or hdot_extra's) turned to the step's
    end as the sinusoid it is: h cos ΩH + (ḣ/Ω) sin ΩH, its hdot_extra ḣ cos ΩH − Ω h sin ΩH
    (ḣ the derivative set for h_extra, else hdot_extra), and those derivatives consumed
    (cleared: the row held until a host sets them again), so Model.inputs_to_step_end, which
    would move it along a straight line (h + ḣ H), leaves it."""
    if status != OK and status != SLOPE_CONFLICT:
        return status
    for row in range(N_EXTRA):
        w = values[U.h_extra_frequency + row]
        if w == 0.0:
            continue
        c, s = math.cos(w * dt), math.sin(w * dt)
        for i in range(3):
            at = 3 * row + i
            given, rate_given = values[GIVEN.h_extra + at], values[GIVEN.hdot_extra + at]
            if given == 0.0 and rate_given == 0.0:
                continue
            x = values[U.h_extra + at]
            rate = values[DU.h_extra + at] if given != 0.0 else values[U.hdot_extra + at]
            values[U.h_extra + at] = x * c + rate / w * s
            values[U.hdot_extra + at] = rate * c - w * x * s
            values[DU.h_extra + at] = values[DU.hdot_extra + at] = 0.0
            values[GIVEN.h_extra + at] = values[GIVEN.hdot_extra + at] = 0.0
    return status


@jitable
def _stored(state, s, x, modes, conflict):
    """Put x = (q_BI, H_I, η, p) into ``state``, q_BI normalised, and return OK, or
    SLOPE_CONFLICT the first time ``conflict``; NON_FINITE (nothing put) if x is not
    finite."""
    for xi in x:
        if not math.isfinite(xi):
            return NON_FINITE
    norm = quat_norm(x)
    put(state, S.q_BI, (x[0] / norm, x[1] / norm, x[2] / norm, x[3] / norm))
    put(state, S.H_I, (x[4], x[5], x[6]))
    for k in range(modes):
        state[S.eta + k], state[S.p + k] = x[7 + k], x[7 + modes + k]
    if conflict and s[S.slope_conflict] == 0.0:
        state[S.slope_conflict] = 1.0
        return SLOPE_CONFLICT
    return OK


@jitable
def _rates(u, d, g):
    """The inputs' rates over the step (module docstring; ``u, d, g`` of :func:`_inputs`):
    (ḣ summed over the devices as _device_sum adds h, whether a non-zero hdot_* differs
    from a derivative set for its h_*, ḧ summed, ṙ_I, τ̇_ext)."""
    slope = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    conflict = False
    for k, (h, stated) in enumerate(
        ((UI.h_cmg, UI.hdot_cmg), (UI.h_wheel, UI.hdot_wheel), (UI.h_payload, UI.hdot_payload))
    ):
        for i in range(3):
            given, rate, wired = g[h + i] != 0.0, d[h + i], u[stated + i]
            slope[3 * k + i] = rate if given else wired
            if given and wired != 0.0 and wired != rate:
                conflict = True
    hdot = (
        (slope[0] + slope[3]) + slope[6],
        (slope[1] + slope[4]) + slope[7],
        (slope[2] + slope[5]) + slope[8],
    )
    curvature = _device_sum(d, DI.hdot_cmg, DI.hdot_wheel, DI.hdot_payload)
    tau_rate = add(vector(d, DI.tau_ext), vector(d, DI.tau_ctrl))
    return hdot, conflict, curvature, vector(d, DI.r_I), tau_rate


@jitable
def external(u) -> tuple:
    """τ = tau_ext + tau_ctrl, the fixed inputs' external torque on the body (in B; ``u``
    the inputs' slice, :func:`_inputs`)."""
    return add(vector(u, UI.tau_ext), vector(u, UI.tau_ctrl))


@jitable
def _extras(u, d, g):
    """The rows of h_extra, hdot_extra and tau_extra, summed in row order: (whether any is
    not zero or has a derivative set; the ordinary rows' h, slope (the derivative set for
    h_extra, else hdot_extra) and ḧ; τ and τ̇ of tau_extra; the rotating rows' (non-zero
    h_extra_frequency Ω) ḣ; whether a non-zero hdot_extra differs from a derivative set
    for its h_extra; the rotating rows' h and Σ ḣ / Ω²)."""
    present, conflict = False, False
    h, slope, curvature = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    h_r, h_r_dot, theta = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    tau, tau_rate = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    for row in range(N_EXTRA):
        frequency = u[UI.h_extra_frequency + row]
        for i in range(3):
            at = 3 * row + i
            x, stated = u[UI.h_extra + at], u[UI.hdot_extra + at]
            given = g[GI.h_extra + at] != 0.0
            rate = d[DI.h_extra + at] if given else stated
            if x != 0.0 or stated != 0.0 or given or g[GI.hdot_extra + at] != 0.0:
                present = True
            if frequency != 0.0:
                h_r[i] += x
                h_r_dot[i] += rate
                theta[i] += rate / (frequency * frequency)
                continue
            h[i] += x
            slope[i] += rate
            curvature[i] += d[DI.hdot_extra + at]
            if given and stated != 0.0 and stated != d[DI.h_extra + at]:
                conflict = True
    for row in range(N_TORQUES):
        for i in range(3):
            at = 3 * row + i
            x, rate = u[UI.tau_extra + at], d[DI.tau_extra + at]
            if x != 0.0 or rate != 0.0:
                present = True
            tau[i] += x
            tau_rate[i] += rate
    return (
        present, (h[0], h[1], h[2]), (slope[0], slope[1], slope[2]),
        (curvature[0], curvature[1], curvature[2]), (tau[0], tau[1], tau[2]),
        (tau_rate[0], tau_rate[1], tau_rate[2]), (h_r_dot[0], h_r_dot[1], h_r_dot[2]),
        conflict, (h_r[0], h_r[1], h_r[2]), (theta[0], theta[1], theta[2]),
    )  # fmt: skip


@jitable
def _nonzero(x):
    return x[0] != 0.0 or x[1] != 0.0 or x[2] != 0.0


@jitable
def _modal_momentum(momenta, L, n):
    """Σ p_k L_k over the first n modes (L: their rows, flat), summed in mode order."""
    x = y = z = 0.0
    for k in range(n):
        x += momenta[k] * L[3 * k]
        y += momenta[k] * L[3 * k + 1]
        z += momenta[k] * L[3 * k + 2]
    return x, y, z


@jitable
def _body_rate(s, h0):
    """The mean body rate ω = M⁻¹ (C_BI H_I − h − Σ p_k L_k) now, the devices' momentum
    ``h0`` (the rigid hub's J⁻¹ (C_BI H_I − h) without modes: M⁻¹ = J⁻¹)."""
    n = int(s[S.modes])
    q_BI, H_I, M_inv = quaternion(s, S.q_BI), vector(s, S.H_I), matrix(s, S.M_inv)
    if n == 0:
        return _rate(q_BI, H_I, h0, M_inv)
    return _rate(
        q_BI, H_I, add(h0, _modal_momentum(s[S.p : S.p + n], s[S.L : S.L + 3 * n], n)), M_inv
    )


@jitable
def _substeps(w, s, dt):
    """(max|ω| at the step's start, the RK4 sub-steps of ``dt`` it and the fastest mode
    need, unrounded)."""
    rate = abs(w[0])
    if abs(w[1]) > rate:
        rate = abs(w[1])
    if abs(w[2]) > rate:
        rate = abs(w[2])
    needed = rate * dt / MAX_ROTATION_PER_SUBSTEP
    modal = s[S.modal_rate] * dt / MAX_MODAL_PHASE
    return rate, modal if modal > needed else needed


@output_kernel(SatelliteDynamics)
def _output(values, state, t):
    """Write the outputs into ``values`` from ``state`` and the inputs (with modes or
    further devices: :func:`_attitude_extended`); keep q_BO's sign and euler_BO's branch
    in ``state``.  Returns the status: NOT_UNIT (nothing written) if q_OI is not a unit
    quaternion."""
    extended = _extended(values, state)
    u, d, g = _inputs(values, ALL if extended else FIXED)
    s = floats(state) if extended else floats(state[:RIGID])
    q0, q1, q2, q3 = q = quaternion(u, UI.q_OI)
    norm = quat_norm(q)
    if not _is_unit(norm):
        return NOT_UNIT
    q_OI = (q0 / norm, q1 / norm, q2 / norm, q3 / norm)
    if extended:
        q_BI, w_BI_B = _attitude_extended(values, u, d, g, s)
    else:
        q_BI = quaternion(s, S.q_BI)
        h = _device_sum(u, UI.h_cmg, UI.h_wheel, UI.h_payload)
        w_BI_B = _rate(q_BI, vector(s, S.H_I), h, matrix(s, S.J_inv))
    q_BO = qmul((q_OI[0], -q_OI[1], -q_OI[2], -q_OI[3]), q_BI)
    last = quaternion(s, S.q_BO)
    if quat_dot(q_BO, last) < 0:
        q_BO = (-q_BO[0], -q_BO[1], -q_BO[2], -q_BO[3])  # keep the sign continuous
    C_BO = dcm(q_BO)
    euler = euler123(q_BO, C_BO, vector(s, S.euler), True)
    w_OI_B = rotate(C_BO, vector(u, UI.w_OI_O))
    w_BO_B = (w_BI_B[0] - w_OI_B[0], w_BI_B[1] - w_OI_B[1], w_BI_B[2] - w_OI_B[2])
    put(state, S.q_BO, q_BO)
    put(state, S.euler, euler)
    put(values, Y.q_BI, q_BI)
    put(values, Y.w_BI_B, w_BI_B)
    put(values, Y.q_BO, q_BO)
    put(values, Y.euler_BO, euler)
    put(values, Y.euler_rate_BO, euler123_dot(euler, w_BO_B))
    put(values, Y.w_BO_B, w_BO_B)
    put(values, Y.H_I, vector(s, S.H_I))
    return OK


@jitable
def _attitude_extended(values, u, d, g, s):
    """(q_BI, w_BI_B) of the outputs with the modes and the further devices (module
    docstring: the rotating rows' steady response added to the mean motion), and η, η̇
    written."""
    extra = _extras(u, d, g)
    q_BI = quaternion(s, S.q_BI)
    w_BI_B = _body_rate(s, add(_device_sum(u, UI.h_cmg, UI.h_wheel, UI.h_payload), extra[1]))
    theta = (0.0, 0.0, 0.0)
    if _nonzero(extra[8]) or _nonzero(extra[9]):
        M_inv = matrix(s, S.M_inv)
        theta = rotate(M_inv, extra[9])
        w_BI_B = sub(w_BI_B, rotate(M_inv, extra[8]))
        q_BI = qmul(q_BI, _small_rotation(theta))
    for k in range(int(s[S.modes])):
        at, lk = int(s[S.mode + k]), (s[S.L + 3 * k], s[S.L + 3 * k + 1], s[S.L + 3 * k + 2])
        values[Y.eta + at] = s[S.eta + k] - dot(lk, theta)
        values[Y.eta_dot + at] = s[S.p + k] - dot(lk, w_BI_B)
    return q_BI, w_BI_B


@jitable
def _small_rotation(theta):
    """The unit quaternion of the rotation vector θ: (cos |θ|/2, sin(|θ|/2) θ/|θ|)."""
    angle = norm(theta)
    if angle == 0.0:
        return (1.0, 0.0, 0.0, 0.0)
    k = math.sin(0.5 * angle) / angle
    return (math.cos(0.5 * angle), k * theta[0], k * theta[1], k * theta[2])


@jitable
def _rate(q, H_I, h, J_inv):
    """w_BI_B = J⁻¹ (C_BI H_I − h)."""
    H_B = rotate(dcm(q), H_I)
    return rotate(J_inv, (H_B[0] - h[0], H_B[1] - h[1], H_B[2] - h[2]))


@jitable
def _integrate(x, n, sub, h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving):
    """x = (q_BI, H_I) after n RK4 sub-steps of ``sub``."""
    for k in range(n):
        x = _rk4(
            x, k * sub, sub, h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving
        )
    return x


@jitable
def _rk4(x, s, ds, h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving):
    """One classical Runge-Kutta step of ``ds`` from ``s`` into the macro step."""
    f, half = _derivative, ds / 2
    inputs = h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving
    k1 = f(x, s, *inputs)
    k2 = f(_shift(x, half, k1), s + half, *inputs)
    k3 = f(_shift(x, half, k2), s + half, *inputs)
    k4 = f(_shift(x, ds, k3), s + ds, *inputs)
    return _shift(x, ds / 6, _weighted(k1, k2, k3, k4))


@jitable
def _shift(x, a, k):
    """x + a k (7-tuples)."""
    return (
        x[0] + a * k[0], x[1] + a * k[1], x[2] + a * k[2], x[3] + a * k[3],
        x[4] + a * k[4], x[5] + a * k[5], x[6] + a * k[6],
    )  # fmt: skip


@jitable
def _weighted(k1, k2, k3, k4):
    """RK4's k1 + 2 (k2 + k3) + k4 (7-tuples)."""
    a, b, c, d = k1, k2, k3, k4
    return (
        a[0] + 2 * (b[0] + c[0]) + d[0], a[1] + 2 * (b[1] + c[1]) + d[1],
        a[2] + 2 * (b[2] + c[2]) + d[2], a[3] + 2 * (b[3] + c[3]) + d[3],
        a[4] + 2 * (b[4] + c[4]) + d[4], a[5] + 2 * (b[5] + c[5]) + d[5],
        a[6] + 2 * (b[6] + c[6]) + d[6],
    )  # fmt: skip


@jitable
def _integrate_modes(
    x, n, modal, steps, sub, h0, hdot, curvature, torque, J, M_inv, mu, gravity_gradient, moving
):
    """x = [q_BI, H_I, η, p] (a list, n modes) after ``steps`` RK4 sub-steps of ``sub``."""
    inputs = n, modal, h0, hdot, curvature, torque, J, M_inv, mu, gravity_gradient, moving
    half = sub / 2
    for step in range(steps):
        s = step * sub
        k1 = _modes_derivative(x, s, *inputs)
        k2 = _modes_derivative(_shift_list(x, half, k1), s + half, *inputs)
        k3 = _modes_derivative(_shift_list(x, half, k2), s + half, *inputs)
        k4 = _modes_derivative(_shift_list(x, sub, k3), s + sub, *inputs)
        x = [x[i] + sub / 6 * (k1[i] + 2 * (k2[i] + k3[i]) + k4[i]) for i in range(len(x))]
    return x


@jitable
def _shift_list(x, a, k):
    """x + a k (lists)."""
    return [x[i] + a * k[i] for i in range(len(x))]


@jitable
def _modes_derivative(
    x, s, n, modal, h0, hdot, curvature, torque, J, M_inv, mu, gravity_gradient, moving
):
    """d/dt [q_BI, H_I, η, p] (module docstring): the hub's (q̇, Ḣ) of :func:`_derivative`
    with the modes' momentum Σ p_k L_k among the devices' and M⁻¹ for J⁻¹, its ω from q̇
    (ω = 2 q* ⊗ q̇ / |q|²); η̇_k = p_k − L_k ω, ṗ_k = −ω_k² η_k − 2 ζ_k ω_k η̇_k."""
    L, w2, c = modal
    momenta = x[7 + n : 7 + 2 * n]
    q = (x[0], x[1], x[2], x[3])
    h = add(h0, _modal_momentum(momenta, L, n))
    rates = list(
        _derivative((*q, x[4], x[5], x[6]), s, h, hdot, curvature, torque, J, M_inv, mu,
                    gravity_gradient, moving)
    )  # fmt: skip
    k = 2.0 / quat_norm(q) ** 2
    w = qmul((q[0], -q[1], -q[2], -q[3]), (rates[0], rates[1], rates[2], rates[3]))
    wx, wy, wz = k * w[1], k * w[2], k * w[3]
    eta_dot = [momenta[i] - (L[3 * i] * wx + L[3 * i + 1] * wy + L[3 * i + 2] * wz)
               for i in range(n)]  # fmt: skip
    for i in range(n):
        rates.append(eta_dot[i])
    for i in range(n):
        rates.append(-w2[i] * x[7 + i] - c[i] * eta_dot[i])
    return rates


@jitable
def _derivative(x, s, h0, hdot, curvature, torque, J, J_inv, mu, gravity_gradient, moving):
    """(q̇_BI, Ḣ_I) at time s into the step (the hot loop: plain floats).  ``torque`` is
    (τ_ext, r_I, τ̇_ext, ṙ_I); ``moving`` says which of ḧ, τ̇_ext, ṙ_I are not zero (a
    rate of zero leaves the arithmetic of a held input untouched, bit for bit)."""
    tau, r_I, tau_rate, r_rate = torque
    q0, q1, q2, q3 = q = x[:4]
    k = 1.0 / (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)  # C(q)/|q|² is a rotation for any q
    (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = dcm(q)
    C = (k * c00, k * c01, k * c02), (k * c10, k * c11, k * c12), (k * c20, k * c21, k * c22)
    H_B = rotate(C, x[4:])
    if moving[0]:  # h + ḣ s + ½ ḧ s²
        a = (hdot[0] + 0.5 * curvature[0] * s, hdot[1] + 0.5 * curvature[1] * s,
             hdot[2] + 0.5 * curvature[2] * s)  # fmt: skip
        relative = (H_B[0] - h0[0] - a[0] * s, H_B[1] - h0[1] - a[1] * s, H_B[2] - h0[2] - a[2] * s)
    else:
        relative = (
            H_B[0] - h0[0] - hdot[0] * s,
            H_B[1] - h0[1] - hdot[1] * s,
            H_B[2] - h0[2] - hdot[2] * s,
        )
    if moving[1]:
        tau = (tau[0] + tau_rate[0] * s, tau[1] + tau_rate[1] * s, tau[2] + tau_rate[2] * s)
    if moving[2]:
        r_I = (r_I[0] + r_rate[0] * s, r_I[1] + r_rate[1] * s, r_I[2] + r_rate[2] * s)
    wx, wy, wz = rotate(J_inv, relative)
    q_dot = (
        0.5 * (-q1 * wx - q2 * wy - q3 * wz),
        0.5 * (q0 * wx + q2 * wz - q3 * wy),
        0.5 * (q0 * wy - q1 * wz + q3 * wx),
        0.5 * (q0 * wz + q1 * wy - q2 * wx),
    )
    if not gravity_gradient:
        return q_dot + rotate_back(C, tau)
    rx, ry, rz = r_B = rotate(C, r_I)
    r2 = rx * rx + ry * ry + rz * rz
    g = 3.0 * mu / (r2 * r2 * math.sqrt(r2))
    jx, jy, jz = rotate(J, r_B)
    torque = (
        tau[0] + g * (ry * jz - rz * jy),
        tau[1] + g * (rz * jx - rx * jz),
        tau[2] + g * (rx * jy - ry * jx),
    )
    return q_dot + rotate_back(C, torque)


@jitable
def _device_sum(a, cmg, wheel, payload):
    """(cmg + wheel) + payload of three 3-vectors at these offsets."""
    c, w, p = vector(a, cmg), vector(a, wheel), vector(a, payload)
    return (c[0] + w[0]) + p[0], (c[1] + w[1]) + p[1], (c[2] + w[2]) + p[2]


@jitable
def _is_unit(norm):
    """|q| near enough to 1 for a quaternion meant to be a unit one."""
    return 0.5 < norm < 2.0


def _unit(q, name) -> tuple:
    q0, q1, q2, q3 = q = q.tolist()
    norm = quat_norm(q)
    if not _is_unit(norm):
        raise ModelError(f"{name} must be a unit quaternion, got {q} (norm {norm})")
    return q0 / norm, q1 / norm, q2 / norm, q3 / norm
