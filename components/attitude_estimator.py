"""Attitude estimator: multiplicative extended Kalman filter (MEKF) with gyro bias.

The filter of [Lefferts 1982] in the form of [Markley 2014] ch. 6, with the
body-frame error of DESIGN.md §2's quaternions: the true attitude is
q_BI = q̂ ⊗ exp(δθ) (components/sensing.py), the state error x = (δθ, Δb = b − b̂) in B.

Gyro model (components/gyro.py): ω̃ = ω + b + η_v, ḃ = η_u with densities σ_v (``arw``)
and σ_u (``rrw``).  Propagation over Δt with the gyro reading ω̃ of that interval (a
rate-integrating gyro's average rate) and ω̂ = ω̃ − b̂::

    q̂ ← q̂ ⊗ exp(ω̂ Δt),   b̂ unchanged,   P ← Φ P Φᵀ + Q
    Φ = [[Θ, Ψ], [0, I]],   Θ = exp(−[ω̂×] Δt) = C(exp(ω̂ Δt))
    Ψ = −(I Δt − [ω̂×] (1 − cos ωΔt)/ω² + [ω̂×]² (ωΔt − sin ωΔt)/ω³)   (= −∫₀^Δt Θ(s) ds)
    Q = [[(σ_v² Δt + σ_u² Δt³/3) I, −(σ_u² Δt²/2) I], [−(σ_u² Δt²/2) I, σ_u² Δt I]]

(Q exact for ω̂ = 0, the form of [Crassidis 2012] ch. 7; ω = |ω̂|).  Star-tracker update
with the measurement q_m (components/star_tracker.py: q_m = q ⊗ exp(e), e the error in B
with covariance R = C_SBᵀ diag(σ_c², σ_c², σ_b²) C_SB)::

    z = rotation_vector(q̂* ⊗ q_m) ≈ δθ + e,   H = [I 0],   S = H P Hᵀ + R
    K = P Hᵀ S⁻¹,   x̂ = K z,   q̂ ← q̂ ⊗ exp(x̂_θ),   b̂ ← b̂ + x̂_b
    P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ          (Joseph form)

``innovation`` = z and ``nis`` = zᵀ S⁻¹ z of the latest update.

Timing.  The filter runs cycles at t_j = t0 + j / rate (components/sensing.py), each with
the gyro reading and star-tracker inputs of that time (between communication points: the
last values, held).  A measurement is new when ``meas_valid`` and (t_meas, q_BI_meas)
differ from those seen at the previous cycle; it is valid at t_meas, or, if t_meas did not
change (the input left open), at the cycle.  A measurement valid before the cycle (the
star tracker's latency) is processed at its own time: the filter goes back to the state
it had then (a history of its cycles over the last ``history`` seconds is kept), updates,
and propagates again with the same gyro readings — exactly what a filter without latency
would have done.  Ignored: measurements not newer than the last one processed, older
than ``history`` (with a warning, once), or invalid; a time of validity after the cycle is
taken as the cycle.  At the first cycle t_meas counts as changed if it lies within the
history (a connected star tracker's first sample), else the measurement is taken as of the
cycle.

Initialisation: at the first valid measurement, q̂ = q_m, b̂ = 0, P = diag(R, σ_b0² I).
Before it, ``valid`` is false, q_BI_est the identity, sigma_att π (no knowledge) and
bias_est zero with sigma_bias0.  Outputs are those of the latest cycle, held between
cycles: w_BI_B_est = ω̃ − b̂.

Relative to the orbit frame (an extension: for a controller that reads q_BO and w_BO_B, as
the pitch-maneuver law does), with O given by the optional inputs q_OI and w_OI_O, the
relations of SatelliteDynamics' q_BO and w_BO_B applied to the estimate::

    q_BO_est = q_OI* ⊗ q_BI_est,   w_BO_B_est = w_BI_B_est − C(q_BO_est) w_OI_O

(at the communication point, with the orbit frame of that time; unconnected, O = I).

Defaults: the sensors' own defaults (components/gyro.py, components/star_tracker.py):
σ_v = the gyro's ARW; σ_u = √(rrw² + 2 σ_β²/T_c), the random walk that covers the
gyro's bias instability (its Gauss–Markov drive); σ_c, σ_b and q_SB of the star tracker;
σ_b0 = 10 °/h (twice the gyro's default initial bias).  The star tracker's low-frequency
error is not modelled by the filter (it appears as a slowly varying bias).
"""

from __future__ import annotations

import math

import numpy as np

from .gyro import DEFAULT_RATE, DEG_PER_HOUR, FILTER_BIAS_WALK, STIM300_ARW
from .model import Model, ModelError
from .rotations import IDENTITY_Q, dcm, qmul
from .sensing import (
    TICK_TOLERANCE,
    conj,
    normalized,
    quat_exp,
    rotation_vector,
    tick,
    tick_time,
)
from .star_tracker import RIGEL_NEA_BORESIGHT, RIGEL_NEA_CROSS
from .variables import input_, output, parameter

_MEASUREMENT = ("q_BI_meas", "meas_valid", "t_meas")
_INPUTS = ("w_meas_B",) + _MEASUREMENT
_I3 = np.eye(3)


class AttitudeEstimator(Model):
    """Multiplicative extended Kalman filter of attitude and gyro bias (gyro, star tracker)."""

    VARIABLES = (
        parameter("rate", DEFAULT_RATE, "Hz", "cycle rate of the filter"),
        parameter(
            "arw",
            STIM300_ARW,
            "rad/s0.5",
            "gyro angle random walk sigma_v assumed",
            display_unit="deg/h0.5",
        ),
        parameter(
            "rrw",
            FILTER_BIAS_WALK,
            "rad/s1.5",
            "gyro bias random walk sigma_u assumed",
            display_unit="deg/h1.5",
        ),
        parameter(
            "nea_cross",
            RIGEL_NEA_CROSS,
            "rad",
            "star-tracker noise (1 sigma) about each cross-boresight axis, assumed",
        ),
        parameter(
            "nea_boresight",
            RIGEL_NEA_BORESIGHT,
            "rad",
            "star-tracker noise (1 sigma) about the boresight, assumed",
        ),
        parameter(
            "q_SB",
            IDENTITY_Q,
            "1",
            "star-tracker mounting (attitude of S relative to B)",
            shape=(4,),
        ),
        parameter(
            "sigma_bias0",
            10.0 * DEG_PER_HOUR,
            "rad/s",
            "initial 1-sigma uncertainty of the gyro bias, per axis",
        ),
        parameter(
            "history", 1.0, "s", "how late a measurement may come (its time of validity before now)"
        ),
        input_(
            "w_meas_B",
            "rad/s",
            "gyro reading: average rate over its last sample interval, in B",
            shape=(3,),
            display_unit="deg/s",
        ),
        input_(
            "q_BI_meas", "1", "star-tracker attitude of B relative to I", IDENTITY_Q, shape=(4,)
        ),
        input_("meas_valid", "1", "q_BI_meas is valid", True, type="Boolean"),
        input_(
            "t_meas",
            "s",
            "time of validity of q_BI_meas (StarTracker.t_meas)",
            optional="unconnected: a new q_BI_meas is valid at the cycle that first sees it",
        ),
        input_(
            "q_OI",
            "1",
            "attitude of the orbit frame O relative to I (for q_BO_est)",
            IDENTITY_Q,
            shape=(4,),
            optional="identity: O is the inertial frame (q_BO_est = q_BI_est)",
        ),
        input_(
            "w_OI_O",
            "rad/s",
            "angular velocity of O relative to I, in O (for w_BO_B_est)",
            shape=(3,),
            optional="zero: O does not rotate",
        ),
        output(
            "q_BI_est", "1", "estimated attitude of B relative to I", shape=(4,), depends=_INPUTS
        ),
        output(
            "w_BI_B_est",
            "rad/s",
            "estimated angular velocity of B relative to I, in B (gyro minus bias)",
            shape=(3,),
            depends=_INPUTS,
            display_unit="deg/s",
        ),
        output("bias_est_B", "rad/s", "estimated gyro bias, in B", shape=(3,), depends=_INPUTS),
        output(
            "sigma_att",
            "rad",
            "1-sigma attitude uncertainty about x_B, y_B, z_B",
            shape=(3,),
            depends=_INPUTS,
            display_unit="deg",
        ),
        output(
            "sigma_bias", "rad/s", "1-sigma bias uncertainty per axis", shape=(3,), depends=_INPUTS
        ),
        output(
            "innovation",
            "rad",
            "innovation z of the latest update (rotation vector, in B)",
            shape=(3,),
            depends=_INPUTS,
        ),
        output("nis", "1", "normalised innovation squared of the latest update", depends=_INPUTS),
        output(
            "valid", "1", "initialised by a valid measurement", type="Boolean", depends=_MEASUREMENT
        ),
        output("n_updates", "1", "measurements processed", type="Integer", depends=_MEASUREMENT),
        output(
            "q_BO_est",
            "1",
            "estimated attitude of B relative to O: q_OI* ⊗ q_BI_est",
            shape=(4,),
            depends=_INPUTS + ("q_OI",),
        ),
        output(
            "w_BO_B_est",
            "rad/s",
            "estimated angular velocity of B relative to O, in B: w_BI_B_est − C_BO w_OI_O",
            shape=(3,),
            depends=_INPUTS + ("q_OI", "w_OI_O"),
            display_unit="deg/s",
        ),
    )

    def initialize(self, t0):
        p = self.p
        for name in ("rate", "nea_cross", "nea_boresight", "sigma_bias0", "history"):
            if not getattr(p, name) > 0.0:
                raise ModelError(f"{name} must be > 0, got {getattr(p, name)}")
        for name in ("arw", "rrw"):
            if not getattr(p, name) >= 0.0:
                raise ModelError(f"{name} must be >= 0, got {getattr(p, name)}")
        q_SB = np.asarray(p.q_SB, dtype=float)
        if abs(math.sqrt(q_SB @ q_SB) - 1.0) > 1e-6:
            raise ModelError(f"q_SB must be a unit quaternion, got {q_SB.tolist()}")
        C_SB = np.array(dcm(q_SB / math.sqrt(q_SB @ q_SB)))
        sigma = np.array([p.nea_cross, p.nea_cross, p.nea_boresight])
        self.R = C_SB.T @ np.diag(sigma**2) @ C_SB
        self.t0 = t0
        # committed state: the last cycle's index and inputs, the records (t, gyro reading
        # of the interval ending at t, q̂, b̂, P or None before initialisation), the time
        # of the last measurement processed, the latest innovation, its NIS, the count
        self.j = None
        self.last_inputs = None
        self.seen = None
        self.records = ()
        self.anchor = None
        self.innovation = (0.0, 0.0, 0.0)
        self.nis = 0.0
        self.n_updates = 0
        self.late_warned = False
        self.t = t0

    def step(self, t, dt):
        # at the model's clock, as output() (components/gyro.py, step)
        state = self._advance(self.t, self._inputs())
        self.warnings.extend(state.pop("notes"))
        vars(self).update(state)
        self.t = t + dt

    def output(self):
        state = self._advance(self.t, self._inputs())
        t, w, q, b, P = state["records"][-1]
        y = self.y
        if q is None:
            y.q_BI_est[:] = IDENTITY_Q
            y.bias_est_B[:] = 0.0
            y.sigma_att[:] = math.pi
            y.sigma_bias[:] = self.p.sigma_bias0
            y.w_BI_B_est[:] = w
        else:
            y.q_BI_est[:] = q
            y.bias_est_B[:] = b
            sd = np.sqrt(np.diag(P))
            y.sigma_att[:] = sd[:3]
            y.sigma_bias[:] = sd[3:]
            y.w_BI_B_est[:] = (w[0] - b[0], w[1] - b[1], w[2] - b[2])
        y.innovation[:] = state["innovation"]
        y.nis = state["nis"]
        y.valid = q is not None
        y.n_updates = state["n_updates"]
        self._orbit_frame()

    def _orbit_frame(self) -> None:
        """q_BO_est = q_OI* ⊗ q_BI_est, w_BO_B_est = w_BI_B_est − C_BO w_OI_O (the
        relations SatelliteDynamics' q_BO and w_BO_B follow, on the estimate)."""
        u, y = self.u, self.y
        q_OI = u.q_OI.tolist()
        n = math.sqrt(sum(x * x for x in q_OI))
        if abs(n - 1.0) > 1e-6:
            raise ModelError(f"t={self.t:.6g} s: q_OI must be a unit quaternion, got {q_OI}")
        q_BO = qmul((q_OI[0] / n, -q_OI[1] / n, -q_OI[2] / n, -q_OI[3] / n), y.q_BI_est.tolist())
        w_OI_B = np.array(dcm(q_BO)) @ u.w_OI_O
        y.q_BO_est[:] = q_BO
        y.w_BO_B_est[:] = y.w_BI_B_est - w_OI_B

    # -- internals -------------------------------------------------------------------
    def _inputs(self) -> tuple:
        u = self.u
        return (
            tuple(u.w_meas_B.tolist()),
            normalized(u.q_BI_meas.tolist()),
            u.meas_valid,
            u.t_meas,
        )

    def _advance(self, now: float, inputs: tuple) -> dict:
        """The committed state with every cycle up to ``now`` run (the last cycle's inputs
        held for cycles before ``now``, the current ones at ``now``).  Pure."""
        p = self.p
        state = {
            "records": self.records,
            "seen": self.seen,
            "anchor": self.anchor,
            "innovation": self.innovation,
            "nis": self.nis,
            "n_updates": self.n_updates,
            "late_warned": self.late_warned,
            "notes": [],
        }
        newest = tick(now, self.t0, p.rate)
        first = newest if self.j is None else self.j + 1
        for j in range(first, newest + 1):
            t_j = tick_time(j, self.t0, p.rate)
            at_now = abs(t_j - now) <= TICK_TOLERANCE / p.rate or self.last_inputs is None
            self._cycle(t_j, inputs if at_now else self.last_inputs, state)
        if first <= newest:
            state["j"] = newest
        state["last_inputs"] = inputs
        return state

    def _cycle(self, t_j: float, inputs: tuple, state: dict) -> None:
        """One cycle at t_j: propagate to t_j, then take a new measurement if any."""
        w, q_m, valid, t_meas = inputs
        records = list(state["records"])
        if records and records[-1][2] is not None:
            t, _, q, b, P = records[-1]
            q, P = self._propagate(q, b, P, w, t_j - t)
            records.append((t_j, w, q, b, P))
        else:
            records.append((t_j, w, None, None, None))
        seen, state["seen"] = state["seen"], (t_meas, q_m)
        horizon = t_j - self.p.history
        if valid and (t_meas, q_m) != seen:
            stamped = t_meas >= horizon if seen is None else t_meas != seen[0]
            t_m = min(t_meas, t_j) if stamped else t_j
            anchor = state["anchor"]
            if t_m >= horizon and (anchor is None or t_m > anchor):
                records = self._measure(records, t_m, q_m, state)
                state["anchor"] = t_m
            elif t_m < horizon and not state["late_warned"]:
                state["late_warned"] = True
                state["notes"].append(
                    f"t={t_j:.6g} s: a measurement valid at t_meas={t_m:.6g} s is older than "
                    f"history ({self.p.history} s) and is ignored (warned once): raise history "
                    "above the star tracker's latency"
                )
        while len(records) > 1 and records[1][0] <= horizon:
            records.pop(0)  # keep the last record at or before the horizon
        state["records"] = tuple(records)

    def _measure(self, records: list, t_m: float, q_m: tuple, state: dict) -> list:
        """Records with the measurement (t_m, q_m) applied at t_m and the later records
        propagated again from there."""
        before = [r for r in records if r[0] <= t_m]
        after = [r for r in records if r[0] > t_m]
        w = after[0][1] if after else before[-1][1]  # the reading of t_m's interval
        if records[-1][2] is not None:  # initialised: a record at or before t_m exists
            t, _, q, b, P = before[-1]
            q, P = self._propagate(q, b, P, w, t_m - t)
            z = rotation_vector(qmul(conj(q), q_m))
            q, b, P, nis = self._update(q, b, P, z)
            state.update(innovation=z, nis=nis, n_updates=state["n_updates"] + 1)
        else:  # initialisation
            q, b = q_m, (0.0, 0.0, 0.0)
            P = np.zeros((6, 6))
            P[:3, :3] = self.R
            P[3:, 3:] = self.p.sigma_bias0**2 * _I3
        anchor = (t_m, w, q, b, P)
        out = [anchor]
        for t_r, w_r, _, _, _ in after:
            q, P = self._propagate(q, b, P, w_r, t_r - out[-1][0])
            out.append((t_r, w_r, q, b, P))
        return out

    def _propagate(self, q, b, P, w, dt: float):
        """q̂ and P after dt with the gyro reading w (module docstring)."""
        if dt <= 0.0:
            return q, P
        p = self.p
        wh = np.array([w[0] - b[0], w[1] - b[1], w[2] - b[2]])
        step = quat_exp(tuple((wh * dt).tolist()))
        q = normalized(qmul(q, step))
        Theta = np.array(dcm(step))
        angle = math.sqrt(float(wh @ wh)) * dt
        W = np.array([[0.0, -wh[2], wh[1]], [wh[2], 0.0, -wh[0]], [-wh[1], wh[0], 0.0]])
        if angle < 1e-4:  # series to the first neglected term, ~angle² relative
            c1, c2 = dt * dt / 2.0, dt**3 / 6.0
        else:
            omega = angle / dt
            c1 = (1.0 - math.cos(angle)) / omega**2
            c2 = (angle - math.sin(angle)) / omega**3
        Psi = -(dt * _I3 - c1 * W + c2 * (W @ W))
        Phi = np.eye(6)
        Phi[:3, :3], Phi[:3, 3:] = Theta, Psi
        sv2, su2 = p.arw**2, p.rrw**2
        Q = np.zeros((6, 6))
        Q[:3, :3] = (sv2 * dt + su2 * dt**3 / 3.0) * _I3
        Q[:3, 3:] = Q[3:, :3] = -(su2 * dt * dt / 2.0) * _I3
        Q[3:, 3:] = su2 * dt * _I3
        P = Phi @ P @ Phi.T + Q
        return q, 0.5 * (P + P.T)

    def _update(self, q, b, P, z):
        """(q̂, b̂, P, NIS) after the measurement residual z (module docstring)."""
        z = np.asarray(z)
        S = P[:3, :3] + self.R
        K = np.linalg.solve(S, P[:3, :]).T  # P Hᵀ S⁻¹ (S symmetric)
        dx = K @ z
        q = normalized(qmul(q, quat_exp(tuple(dx[:3].tolist()))))
        b = tuple((np.asarray(b) + dx[3:]).tolist())
        A = np.eye(6)
        A[:, :3] -= K
        P = A @ P @ A.T + K @ self.R @ K.T
        return q, b, 0.5 * (P + P.T), float(z @ np.linalg.solve(S, z))
