"""CMG steering law: gimbal-rate commands that deliver a wanted body torque ([Zhao 2016] §3.2).

The cluster exerts −ḣ − w × h on the body (DESIGN.md §2), so the torque τ_cmd needs
ḣ = −τ_cmd − w × h = h_rotor A(δ) δ̇  (eq. 14 with the gyroscopic term kept), solved as

``law`` names the solution: a named choice (an Integer parameter whose values 0, 1 the
variable table names, :data:`LAW_CHOICES`; ``--set CmgSteering.law=SR_INVERSE`` on the
command line, ``CmgSteering(law="SR_INVERSE")`` in Python).  FMI 2.0 would call it an
Enumeration, but pythonfmu 0.7 has no Enumeration variables (NTNU-IHB/PythonFMU PR #255,
open) and libcosim does not read them (open-simulation-platform/libcosim#246):

``law = 0`` (PSEUDO_INVERSE) — pseudo-inverse with null motion (the paper)::

    δ̇ = Aᵀ(AAᵀ)⁻¹ ḣ / h_rotor + ε (1 − Aᵀ(AAᵀ)⁻¹A) ∂Q/∂δ,   Q = det(AAᵀ)
    ∂Q/∂δ_i = −2 Q a_iᵀ (AAᵀ)⁻¹ σ_i          (σ_i: spin of gyro i, ∂a_i/∂δ_i = −σ_i)

  The null motion moves the gimbals toward larger Q without changing the torque.  At an
  exact singularity (Q below 1e-12) the inverse is replaced by the SVD pseudo-inverse,
  which leaves the torque along the singular direction undelivered.

``law = 1`` (SR_INVERSE) — singularity-robust inverse (Nakamura & Hanafusa 1986; Bedrossian 1990)::

    δ̇ = Aᵀ(AAᵀ + λ1)⁻¹ ḣ / h_rotor,   λ = λ0 exp(−μ Q)

  which trades a small torque error near singularities for bounded gimbal rates.

Healthy gimbals (DESIGN.md §3.2): a gimbal whose input ``healthy`` is false (locked:
CmgCluster.healthy) has its column taken out of A — zero rate commanded, Q the measure of
the healthy gyros, the null motion among them — so the law steers the five (or fewer)
that move.  Its rotor's momentum stays in h, hence in the −w × h the law accounts for.
With one of the default pyramid's six locked, the envelope of the five shrinks to about
45 N·m·s in its worst direction (74 N·m·s with six) and internal singular surfaces come
within 1.6–3.7 N·m·s of where the lock leaves the momentum (10.8 N·m·s with six): see
orchestration/studies/cmg_envelope.py and docs/missions.md.
"""

from __future__ import annotations

import math

import numpy as np

from .cmg_cluster import (
    DEFAULT_SPINS,
    GIMBAL_AXES,
    N_GYROS,
    ClusterGeometry,
    CmgCluster,
    axes,
    healthy_columns,
)
from .model import Model, ModelError
from .runtime.flat import relative, state_table
from .runtime.jit import floats, jitable, output_kernel
from .variables import choice, input_, output, parameter
from .vectors import det3, dot, gram, inv3, rotate

#: values of the ``law`` parameter, named in the variable table by LAW_CHOICES
PSEUDO_INVERSE, SR_INVERSE = 0, 1
LAW_CHOICES = (
    ("PSEUDO_INVERSE", "pseudo-inverse with null motion"),
    ("SR_INVERSE", "singularity-robust inverse"),
)

SINGULAR_Q = 1e-12
_INPUTS = ("tau_cmd", "delta", "w_BI_B", "h", "healthy")
H_ROTOR = 16.65
#: start values of the delta and h inputs: the cluster's default (CmgCluster.delta0, the
#: paper's δ0, Q = 1.10) and its momentum there, so that the FMU at its defaults is the
#: steering of a default cluster at t = 0, away from any singularity
DELTA_START: tuple[float, ...] = tuple(
    np.asarray(
        next(v.start for v in CmgCluster.VARIABLES if v.name == "delta0"), dtype=float
    ).tolist()
)
H_START = tuple(ClusterGeometry(H_ROTOR, GIMBAL_AXES, DEFAULT_SPINS).momentum(DELTA_START).tolist())


class CmgSteering(Model):
    """Steering law of a six-gyro SGCMG cluster: torque command to gimbal rates."""

    VARIABLES = (
        parameter("h_rotor", H_ROTOR, "N.m.s", "rotor angular momentum of each gyro"),
        parameter(
            "gimbal_axis", GIMBAL_AXES, "1", "gimbal axis of each gyro in B (rows)", shape=(6, 3)
        ),
        parameter(
            "spin_ref",
            DEFAULT_SPINS,
            "1",
            "rotor spin direction of each gyro at zero gimbal angle, in B (rows)",
            shape=(6, 3),
        ),
        choice("law", PSEUDO_INVERSE, "steering law", LAW_CHOICES),
        parameter("null_gain", 0.0, "1", "null-motion gain epsilon (law 0)"),
        parameter("sr_lambda0", 0.01, "1", "singularity-robust weight lambda0 (law 1)"),
        parameter("sr_mu", 10.0, "1", "singularity-robust decay mu in lambda0 exp(-mu Q)"),
        input_("tau_cmd", "N.m", "torque wanted on the body, in B", shape=(3,)),
        input_(
            "delta",
            "rad",
            "gimbal angles (start: CmgCluster's default delta0)",
            DELTA_START,
            shape=(6,),
            display_unit="deg",
        ),
        input_("w_BI_B", "rad/s", "body angular velocity relative to I, in B", shape=(3,)),
        input_(
            "h",
            "N.m.s",
            "cluster angular momentum relative to the body, in B (start: "
            "the default cluster's at delta0)",
            H_START,
            shape=(3,),
        ),
        input_(
            "healthy",
            "1",
            "each gimbal is free (CmgCluster.healthy): only those are steered",
            True,
            shape=(N_GYROS,),
            type="Boolean",
            optional="true: every gimbal steers",
        ),
        output(
            "delta_dot_cmd",
            "rad/s",
            "gimbal rate commands",
            shape=(6,),
            depends=_INPUTS,
            display_unit="deg/s",
        ),
        output(
            "singularity",
            "1",
            "singularity measure Q = det(A A^T) of the healthy gyros",
            depends=("delta", "healthy"),
        ),
    )
    #: step() only advances t (stateless between communication points)
    STATELESS = True

    def initialize(self, t0):
        p = self.p
        if p.law not in range(len(LAW_CHOICES)):
            raise ModelError(self.layout.by_name["law"].choice_error(p.law))
        if p.h_rotor == 0:
            raise ModelError("h_rotor must be non-zero")
        self.geometry = ClusterGeometry(p.h_rotor, p.gimbal_axis, p.spin_ref)
        self.state = S.zeros()
        self.state[S.st : S.h_rotor] = self.geometry.st
        self.state[S.h_rotor : S.sr_mu + 1] = p.h_rotor, p.law, p.null_gain, p.sr_lambda0, p.sr_mu
        self.t = t0

    def step(self, t, dt):
        self.t = t + dt

    def output(self):
        status = steering_output(self.values, self.state, self.t)
        if status & PSEUDO_INVERSE_SINGULAR:
            _, columns = self.geometry.axes(self.u.delta.tolist())
            columns = healthy_columns(columns, self.u.healthy.tolist())
            h_dot = wanted_hdot(self.values[U.tau_cmd : U.healthy + N_GYROS].tolist())
            rates = np.linalg.pinv(np.array(columns).T, rcond=1e-6) @ h_dot / self.geometry.h_rotor
            self.y.delta_dot_cmd[:] = rates
        if status & BECAME_SINGULAR:
            self.warnings.append(
                f"t={self.t:.3f} s: singular gimbal configuration "
                f"(Q = {self.y.singularity:.2e}); torque along the singular direction is "
                "not delivered"
            )


# -- kernel (components/runtime/jit.py) -----------------------------------------------
P, U, Y = CmgSteering.names()
#: the inputs' places in the slice of them the kernel reads, values[U.tau_cmd : U.healthy + 6]
UI = relative(U, U.tau_cmd)
#: the state array: s_i, t_i of each gyro (ClusterGeometry.st), the law's constants, and 1
#: while the configuration is singular (Q ≤ SINGULAR_Q)
S = state_table(
    "CmgSteering state", st=6 * N_GYROS, h_rotor=1, law=1, null_gain=1, sr_lambda0=1, sr_mu=1,
    singular=1,
)  # fmt: skip
#: steering_output's status, bits: the pseudo-inverse at a singularity, left to the SVD;
#: the configuration became singular (output() warns)
PSEUDO_INVERSE_SINGULAR, BECAME_SINGULAR = 1, 2


@output_kernel(CmgSteering)
def steering_output(values, state, t):
    """Gimbal-rate commands δ̇ and Q for the wanted torque (module docstring): writes both,
    or only Q and returns PSEUDO_INVERSE_SINGULAR where the law is the pseudo-inverse and
    Q ≤ SINGULAR_Q (the SVD pseudo-inverse is then the caller's); keeps whether the
    configuration is singular (Q ≤ SINGULAR_Q) and adds BECAME_SINGULAR when it becomes so."""
    u, s = floats(values[U.tau_cmd : U.healthy + N_GYROS]), floats(state)  # the inputs alone
    spins, columns = axes(u[UI.delta : UI.delta + N_GYROS], s[S.st : S.h_rotor])
    columns = healthy_columns(columns, u[UI.healthy : UI.healthy + N_GYROS])
    M = gram(columns)
    Q = det3(M)
    values[Y.singularity] = Q
    singular = Q <= SINGULAR_Q
    became = BECAME_SINGULAR if singular and state[S.singular] == 0.0 else 0
    state[S.singular] = 1.0 if singular else 0.0
    law = s[S.law]
    if law == SR_INVERSE:
        lam = s[S.sr_lambda0] * math.exp(-s[S.sr_mu] * Q)
        M = (
            (M[0][0] + lam, M[0][1], M[0][2]),
            (M[1][0], M[1][1] + lam, M[1][2]),
            (M[2][0], M[2][1], M[2][2] + lam),
        )
    elif not Q > SINGULAR_Q:
        return PSEUDO_INVERSE_SINGULAR | became
    M_inv = inv3(M)
    x = rotate(M_inv, wanted_hdot(u))
    h_rotor = s[S.h_rotor]
    rates = [(a[0] * x[0] + a[1] * x[1] + a[2] * x[2]) / h_rotor for a in columns]
    null_gain = s[S.null_gain]
    if law == PSEUDO_INVERSE and null_gain != 0.0:
        moves = _null_motion(columns, M_inv, Q, spins)
        rates = [r + null_gain * n for r, n in zip(rates, moves)]
    values[Y.delta_dot_cmd : Y.delta_dot_cmd + N_GYROS] = rates
    return became


@jitable
def wanted_hdot(u) -> tuple:
    """ḣ = −τ_cmd − w × h from the inputs ``u`` (values[U.tau_cmd : U.healthy + 6])."""
    wx, wy, wz = u[UI.w_BI_B], u[UI.w_BI_B + 1], u[UI.w_BI_B + 2]
    hx, hy, hz = u[UI.h], u[UI.h + 1], u[UI.h + 2]
    tx, ty, tz = u[UI.tau_cmd], u[UI.tau_cmd + 1], u[UI.tau_cmd + 2]
    return (-tx - (wy * hz - wz * hy), -ty - (wz * hx - wx * hz), -tz - (wx * hy - wy * hx))


@jitable
def _null_motion(columns, M_inv, Q, spins) -> list:
    """(1 − Aᵀ M⁻¹ A) ∂Q/∂δ with ∂Q/∂δ_i = −2 Q a_iᵀ M⁻¹ σ_i."""
    # 0.0 + a · b: a zero of the sign Python's ``sum`` gives, as (0.0 + a₀b₀) + ... does
    gradient = [-2.0 * Q * (0.0 + dot(a, rotate(M_inv, s))) for a, s in zip(columns, spins)]
    v = rotate(M_inv, _sum_weighted(columns, gradient))
    return [d - (a[0] * v[0] + a[1] * v[1] + a[2] * v[2]) for a, d in zip(columns, gradient)]


@jitable
def _sum_weighted(columns, weights) -> tuple:
    """A w = Σ a_i w_i."""
    x = y = z = 0.0
    for a, w in zip(columns, weights):
        x += a[0] * w
        y += a[1] * w
        z += a[2] * w
    return x, y, z
