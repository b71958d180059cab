"""Attitude estimator: multiplicative extended Kalman filter (MEKF) with gyro bias.

The filter of [Lefferts 1982] as [Markley 2014] ch. 6 writes it (the MEKF: a multiplicative
attitude error, an additive bias error, the 6×6 error covariance propagated in discrete
time and updated in Joseph form), with the closed-form transition matrix and process noise
of [Crassidis 2012] ch. 7, in the body-frame error convention of DESIGN.md §2's
quaternions.  The equations, numbered as the code cites them::

    q_BI = q̂ ⊗ exp(δθ),   x = (δθ, Δb = b − b̂) in B,   P = E[x xᵀ]              (1)
    ω̃ = ω + b + η_v,   ḃ = η_u   (densities σ_v = ``arw``, σ_u = ``rrw``)          (2)

Propagation over Δt with the gyro reading ω̃ of that interval (a rate-integrating gyro's
average rate; ω = |ω̂|)::

    ω̂ = ω̃ − b̂                                                                     (3)
    q̂ ← q̂ ⊗ exp(ω̂ Δt),   b̂ unchanged                                              (4)
    Φ = [[Θ, Ψ], [0, I]],   Θ = exp(−[ω̂×] Δt) = C(exp(ω̂ Δt)),
    Ψ = −(I Δt − [ω̂×] (1 − cos ωΔt)/ω² + [ω̂×]² (ωΔt − sin ωΔt)/ω³)  (= −∫₀^Δt Θ(s) ds) (5)
    P ← Φ P Φᵀ + Q                                                                (6)
    Q = [[(σ_v² Δt + σ_u² Δt³/3) I, −(σ_u² Δt²/2) I], [−(σ_u² Δt²/2) I, σ_u² Δt I]]  (7)

(Q exact for ω̂ = 0).  Star-tracker update with the measurement q_m
(components/star_tracker.py: q_m = q ⊗ exp(e), e the error in B with covariance
R = C_SBᵀ diag(σ_c², σ_c², σ_b²) C_SB)::

    z = rotation_vector(q̂* ⊗ q_m) ≈ δθ + e,   H = [I 0]                            (8)
    S = H P Hᵀ + R                                                                (9)
    K = P Hᵀ S⁻¹,   x̂ = K z                                                        (10)
    q̂ ← q̂ ⊗ exp(x̂_θ),   b̂ ← b̂ + x̂_b                                                (11)
    P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ          (Joseph form)                       (12)
    ``innovation`` = z,   ``nis`` = zᵀ S⁻¹ z   (of the latest update)                   (13)

The kernels compute P by its 3×3 blocks P = [[A, Bc], [Bcᵀ, C]] (attitude, cross, bias),
on the small-vector algebra of components/vectors.py; each block expression is (6), (7) or
(12) multiplied out, in the order written there.

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

``step`` and ``output`` are each one kernel (components/runtime/jit.py) on the value array
and the state array: the filter's history is a table of records there (``RECORD``), each
with its q̂, b̂ and P; S is inverted by its cofactors.  The step commits the section the
output advanced when it was made at the same time from the same inputs, bit for bit
(components/sensing.py, reusing the advanced section).

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
from .runtime.flat import matrix, quaternion, state_table, vector
from .runtime.jit import floats, jitable, output_kernel, step_kernel
from .sensing import (
    TICK_TOLERANCE,
    conj,
    normalized,
    quat_exp,
    reused,
    rotation_vector,
    stamp,
    stamp_size,
    tick,
    tick_time,
    unstamp,
)
from .star_tracker import RIGEL_NEA_BORESIGHT, RIGEL_NEA_CROSS
from .variables import input_, output, parameter
from .vectors import (
    add,
    cross_matrix,
    dot,
    identity,
    inv3_reciprocal,
    mat_add,
    mat_combine,
    matmul,
    norm,
    plus_diagonal,
    rotate,
    scale,
    sub,
    symmetric,
    transpose,
)

_MEASUREMENT = ("q_BI_meas", "meas_valid", "t_meas")
_INPUTS = ("w_meas_B",) + _MEASUREMENT


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
        R = C_SB.T @ np.diag(sigma**2) @ C_SB
        # records: the one at or before the horizon, the cycles after it, a measurement's
        # own, the cycle appended before the oldest are dropped, and one for rounding
        capacity = math.floor(p.history * p.rate + TICK_TOLERANCE) + 5
        if capacity > MAX_RECORDS:
            raise ModelError(
                f"history {p.history:g} s at rate {p.rate:g} Hz is {capacity} filter records, "
                f"more than the {MAX_RECORDS} it keeps: history need only exceed the star "
                "tracker's latency"
            )
        section = FILTER.size + capacity * RECORD.size
        self.state = np.zeros(SECTIONS + 2 * section + STAMP_SIZE)
        self.state[:SECTIONS] = (t0, capacity, section, *R.reshape(-1))
        self.t = t0

    def step(self, t, dt):
        # at the model's clock, as output() (components/gyro.py, step)
        status = estimator_step(self.values, self.state, self.t, dt)
        if status == FULL:
            raise ModelError(_FULL)
        if status == LATE:
            t_j, t_m = self.state[SECTIONS + FILTER.note : SECTIONS + FILTER.note + 2]
            self.warnings.append(
                f"t={t_j:.6g} s: a measurement valid at t_meas={t_m:.6g} s is older than "
                f"history ({self.p.history} s) and is ignored (warned once): raise history "
                "above the star tracker's latency"
            )
        self.t = t + dt

    def output(self):
        status = estimator_output(self.values, self.state, self.t)
        if status == FULL:
            raise ModelError(_FULL)
        if status == NOT_UNIT:
            q_OI = self.u.q_OI.tolist()
            raise ModelError(f"t={self.t:.6g} s: q_OI must be a unit quaternion, got {q_OI}")

    @classmethod
    def state_problem(cls, attributes, reference):
        """The kernels index the state with its constants and each section's count of
        records: the constants are those the parameters make, the counts whole numbers
        leaving room for a cycle's record and a measurement's (capacity − 2 at most)."""
        state, constants = attributes["state"], reference["state"][:SECTIONS]
        if not np.array_equal(state[:SECTIONS], constants):
            return "constants (capacity, section length, R) are not its parameters'"
        for at in (SECTIONS, SECTIONS + int(constants[S.section])):
            n = float(state[at + FILTER.n_records])
            if not (n == int(n) and 0 <= n <= constants[S.capacity] - 2):
                return f"count of records {n!r} is not a whole number in [0, capacity - 2]"
        return ""

    @property
    def scratch(self) -> int:
        """Where the advanced section starts: from there on the state array is rewritten
        by advance() before it is read, or reused by the step while its stamp says it is
        what advance() would write (components/sensing.py), so an FMU's C step path need
        not save it before a step or an output (fmus/fast_paths.py)."""
        return SECTIONS + int(self.state[S.section])

    @property
    def records(self) -> list:
        """The committed records (t, gyro reading of the interval ending at t, q̂, b̂, P;
        None for the three before initialisation), for analysis."""
        s = self.state
        decoded = []
        for i in range(int(s[SECTIONS + FILTER.n_records])):
            r = s[_record(SECTIONS, i) : _record(SECTIONS, i + 1)]
            known = r[RECORD.initialised] != 0.0
            decoded.append(
                (
                    float(r[RECORD.t]),
                    tuple(r[RECORD.w : RECORD.w + 3].tolist()),
                    tuple(r[RECORD.q : RECORD.q + 4].tolist()) if known else None,
                    tuple(r[RECORD.b : RECORD.b + 3].tolist()) if known else None,
                    r[RECORD.P : RECORD.P + 36].reshape(6, 6).copy() if known else None,
                )
            )
        return decoded


# -- kernels (components/runtime/jit.py) ----------------------------------------------
P, U, Y = AttitudeEstimator.names()
#: the state array: t0, the records a section holds, the length of a section, R
#: (row-major); then two sections (FILTER and the records): the committed one, and the one
#: advanced to the output's time
S = state_table("AttitudeEstimator constants", t0=1, capacity=1, section=1, R=9)
SECTIONS = S.size  # where the committed section starts
#: a section: the last cycle's index (1 when there is one), the inputs of the last call
#: (1 when there were: w_meas_B, q_BI_meas, meas_valid, t_meas), the measurement seen at
#: the last cycle (1 when one was: t_meas, q_BI_meas), the time of the last measurement
#: processed (1 when one was), the latest innovation, its NIS, the updates, 1 once the late
#: warning was given, the (cycle, measurement) times of a late warning to give, the count of
#: records, then the records (RECORD each), oldest first
FILTER = state_table(
    "AttitudeEstimator section", cycled=1, j=1, called=1, last_inputs=9, seen=1,
    seen_measurement=5, anchored=1, anchor=1, innovation=3, nis=1, n_updates=1, late_warned=1,
    note=2, n_records=1,
)  # fmt: skip
#: a record: the cycle's (or measurement's) time, the gyro reading of the interval ending
#: at it, 1 once initialised, q̂, b̂ and P (row-major)
RECORD = state_table("AttitudeEstimator record", t=1, w=3, initialised=1, q=4, b=3, P=36)
#: the kernels' statuses: a late measurement was ignored (step() warns, once); no room for
#: a cycle's records (a state the model was never in: nothing committed, step() raises);
#: q_OI not a unit quaternion (output() raises)
LATE, FULL, NOT_UNIT = 1, 2, 3
_FULL = "internal error: more records than the history holds"
#: the most cycles the filter's history holds (each record 48 values, twice: ~8 MB)
MAX_RECORDS = 10_000
#: the inputs :func:`advance` reads (w_meas_B, q_BI_meas, meas_valid, t_meas), which the
#: stamp after the two sections keeps (components/sensing.py, reusing the advanced section)
INPUTS = ((U.w_meas_B, U.t_meas + 1),)
STAMP_SIZE = stamp_size(INPUTS)


@step_kernel(AttitudeEstimator)
def estimator_step(values, state, t, dt):
    """Every cycle up to the model's time t run and committed (the advanced section as the
    output left it if it is that, components/sensing.py); LATE when a measurement older
    than ``history`` was ignored for the first time."""
    size = int(state[S.section])
    status = reused(values, state, SECTIONS + 2 * size, INPUTS, t)
    if status < 0:
        status = advance(values, state, t)
    if status == FULL:
        return FULL
    for i in range(size):
        state[SECTIONS + i] = state[SECTIONS + size + i]
    unstamp(state, SECTIONS + 2 * size)
    return status


@output_kernel(AttitudeEstimator)
def estimator_output(values, state, t):
    """The latest cycle's estimate at t (the committed state advanced to t, not committed)."""
    if advance(values, state, t) == FULL:
        return FULL
    a = SECTIONS + int(state[S.section])
    last = _record(a, int(state[a + FILTER.n_records]) - 1)
    s = floats(state)
    w = vector(s, last + RECORD.w)
    known = s[last + RECORD.initialised] != 0.0
    for i in range(3):
        if known:
            b = s[last + RECORD.b + i]
            values[Y.bias_est_B + i], values[Y.w_BI_B_est + i] = b, w[i] - b
            values[Y.sigma_att + i] = math.sqrt(s[last + RECORD.P + 7 * i])
            values[Y.sigma_bias + i] = math.sqrt(s[last + RECORD.P + 7 * (i + 3)])
        else:
            values[Y.bias_est_B + i], values[Y.w_BI_B_est + i] = 0.0, w[i]
            values[Y.sigma_att + i], values[Y.sigma_bias + i] = math.pi, values[P.sigma_bias0]
        values[Y.innovation + i] = s[a + FILTER.innovation + i]
    for i in range(4):
        values[Y.q_BI_est + i] = s[last + RECORD.q + i] if known else (1.0 if i == 0 else 0.0)
    values[Y.nis], values[Y.n_updates] = s[a + FILTER.nis], s[a + FILTER.n_updates]
    values[Y.valid] = 1.0 if known else 0.0
    return orbit_frame(values)


@jitable
def orbit_frame(values) -> int:
    """q_BO_est = q_OI* ⊗ q_BI_est, w_BO_B_est = w_BI_B_est − C_BO w_OI_O (the relations
    SatelliteDynamics' q_BO and w_BO_B follow, on the estimate); NOT_UNIT when q_OI is
    not a unit quaternion (to 1e-6)."""
    v = floats(values)
    q_OI = (v[U.q_OI], v[U.q_OI + 1], v[U.q_OI + 2], v[U.q_OI + 3])
    n = math.sqrt(q_OI[0] ** 2 + q_OI[1] ** 2 + q_OI[2] ** 2 + q_OI[3] ** 2)
    if not abs(n - 1.0) <= 1e-6:
        return NOT_UNIT
    q_IO = (q_OI[0] / n, -q_OI[1] / n, -q_OI[2] / n, -q_OI[3] / n)
    q_BO = qmul(q_IO, (v[Y.q_BI_est], v[Y.q_BI_est + 1], v[Y.q_BI_est + 2], v[Y.q_BI_est + 3]))
    w_OI_B = rotate(dcm(q_BO), (v[U.w_OI_O], v[U.w_OI_O + 1], v[U.w_OI_O + 2]))
    for i in range(4):
        values[Y.q_BO_est + i] = q_BO[i]
    for i in range(3):
        values[Y.w_BO_B_est + i] = v[Y.w_BI_B_est + i] - w_OI_B[i]
    return 0


@jitable
def advance(values, state, now: float) -> int:
    """The committed section with every cycle up to ``now`` run (the last call's inputs
    held for cycles before ``now``, the current ones at ``now``), into the advanced one;
    LATE when a late measurement was ignored for the first time (its times in ``note``),
    FULL when a cycle's records would not fit (a state the model was never in), else 0;
    stamped (components/sensing.py)."""
    v = floats(values)
    c, a = SECTIONS, SECTIONS + int(state[S.section])
    size = int(state[S.section])
    unstamp(state, a + size)
    for i in range(size):
        state[a + i] = state[c + i]
    t0, rate = state[S.t0], v[P.rate]
    inputs = (
        *vector(v, U.w_meas_B), *normalized(v[U.q_BI_meas : U.q_BI_meas + 4]),
        v[U.meas_valid], v[U.t_meas],
    )  # fmt: skip
    s = floats(state)
    held = c + FILTER.last_inputs
    last = (
        s[held], s[held + 1], s[held + 2], s[held + 3], s[held + 4], s[held + 5], s[held + 6],
        s[held + 7], s[held + 8],
    )  # fmt: skip
    newest = tick(now, t0, rate)
    first = newest if state[c + FILTER.cycled] == 0.0 else int(state[c + FILTER.j]) + 1
    late, capacity = False, int(state[S.capacity])
    for j in range(first, newest + 1):
        if int(state[a + FILTER.n_records]) + 2 > capacity:  # a cycle's record and a measurement's
            return FULL
        t_j = tick_time(j, t0, rate)
        at_now = abs(t_j - now) <= TICK_TOLERANCE / rate or state[c + FILTER.called] == 0.0
        late = _cycle(values, state, a, t_j, inputs if at_now else last) or late
    if first <= newest:
        state[a + FILTER.cycled], state[a + FILTER.j] = 1.0, newest
    state[a + FILTER.called] = 1.0
    for i in range(9):
        state[a + FILTER.last_inputs + i] = inputs[i]
    status = LATE if late else 0
    stamp(values, state, a + size, INPUTS, now, status)
    return status


@jitable
def _cycle(values, state, a: int, t_j: float, inputs) -> bool:
    """One cycle at t_j on the section at ``a``: propagate to t_j, then take a new
    measurement if any; whether a late one was ignored for the first time."""
    v = floats(values)
    w = (inputs[0], inputs[1], inputs[2])
    q_m = (inputs[3], inputs[4], inputs[5], inputs[6])
    valid, t_meas = inputs[7], inputs[8]
    n = int(state[a + FILTER.n_records])
    new, latest = _record(a, n), _record(a, n - 1)
    state[new + RECORD.t], state[new + RECORD.initialised] = t_j, 0.0
    for i in range(3):
        state[new + RECORD.w + i] = w[i]
    if n > 0 and state[latest + RECORD.initialised] != 0.0:
        _propagated(state, latest, new, v, w, t_j - state[latest + RECORD.t])
    state[a + FILTER.n_records] = n + 1
    seen = state[a + FILTER.seen] != 0.0
    at = a + FILTER.seen_measurement
    before = (state[at], state[at + 1], state[at + 2], state[at + 3], state[at + 4])
    state[a + FILTER.seen] = 1.0
    state[a + FILTER.seen_measurement] = t_meas
    for i in range(4):
        state[a + FILTER.seen_measurement + 1 + i] = q_m[i]
    horizon = t_j - v[P.history]
    same = (
        seen and t_meas == before[0] and q_m[0] == before[1] and q_m[1] == before[2]
        and q_m[2] == before[3] and q_m[3] == before[4]
    )  # fmt: skip
    late = False
    if valid != 0.0 and not same:
        stamped = t_meas >= horizon if not seen else t_meas != before[0]
        t_m = min(t_meas, t_j) if stamped else t_j
        if t_m >= horizon and (state[a + FILTER.anchored] == 0.0 or t_m > state[a + FILTER.anchor]):
            _measure(state, a, v, t_m, q_m)
            state[a + FILTER.anchored], state[a + FILTER.anchor] = 1.0, t_m
        elif t_m < horizon and state[a + FILTER.late_warned] == 0.0:
            state[a + FILTER.late_warned] = 1.0
            state[a + FILTER.note], state[a + FILTER.note + 1] = t_j, t_m
            late = True
    dropped = 0  # keep the last record at or before the horizon
    while (
        dropped + 1 < int(state[a + FILTER.n_records])
        and state[_record(a, dropped + 1) + RECORD.t] <= horizon
    ):
        dropped += 1
    _drop(state, a, dropped)
    return late


@jitable
def _record(a: int, i: int) -> int:
    """Where record i of the section at ``a`` starts."""
    return a + FILTER.size + RECORD.size * i


@jitable
def _drop(state, a: int, count: int) -> None:
    """The oldest ``count`` records dropped."""
    n = int(state[a + FILTER.n_records])
    for i in range(_record(a, 0), _record(a, n - count)):
        state[i] = state[i + RECORD.size * count]
    state[a + FILTER.n_records] = n - count


@jitable
def _measure(state, a: int, v, t_m: float, q_m) -> None:
    """The records with the measurement (t_m, q_m) applied at t_m and the later records
    propagated again from there; those before t_m dropped."""
    n = int(state[a + FILTER.n_records])
    after = 0  # the first record after t_m
    while after < n and state[_record(a, after) + RECORD.t] <= t_m:
        after += 1
    if after == 0:  # before every record (not initialised): room for it first
        for i in range(_record(a, n + 1) - 1, _record(a, 1) - 1, -1):
            state[i] = state[i - RECORD.size]
        n, after = n + 1, 1
    reading = _record(a, after if after < n else after - 1)  # the reading of t_m's interval
    w = vector(state, reading + RECORD.w)
    initialised = state[_record(a, n - 1) + RECORD.initialised] != 0.0
    anchor = _record(a, 0)
    if initialised:  # a record at or before t_m exists
        before = _record(a, after - 1)
        _propagated(state, before, anchor, v, w, t_m - state[before + RECORD.t])
        q = quaternion(state, anchor + RECORD.q)
        z = rotation_vector(qmul(conj(q), q_m))  # (8)
        _update(state, a, anchor, z)
        for i in range(3):
            state[a + FILTER.innovation + i] = z[i]
        state[a + FILTER.n_updates] += 1.0
    else:  # initialisation: q̂ = q_m, b̂ = 0, P = diag(R, σ_b0² I)
        for i in range(4):
            state[anchor + RECORD.q + i] = q_m[i]
        for i in range(3):
            state[anchor + RECORD.b + i] = 0.0
        for i in range(36):
            state[anchor + RECORD.P + i] = 0.0
        for i in range(3):
            for k in range(3):
                state[anchor + RECORD.P + 6 * i + k] = state[S.R + 3 * i + k]
            state[anchor + RECORD.P + 7 * (i + 3)] = v[P.sigma_bias0] * v[P.sigma_bias0]
        state[anchor + RECORD.initialised] = 1.0
    state[anchor + RECORD.t] = t_m
    for i in range(3):
        state[anchor + RECORD.w + i] = w[i]
    for i in range(after, n):  # each later record, propagated from the one before it
        out, into = _record(a, i), _record(a, i - after)
        reading = vector(state, out + RECORD.w)
        t_r = state[out + RECORD.t]
        _propagated(state, into, into + RECORD.size, v, reading, t_r - state[into + RECORD.t])
        state[into + RECORD.size + RECORD.t] = t_r
        for k in range(3):
            state[into + RECORD.size + RECORD.w + k] = reading[k]
    state[a + FILTER.n_records] = n - after + 1


@jitable
def _propagated(state, source: int, target: int, v, w, dt: float) -> None:
    """Record ``target``'s q̂, b̂, P: record ``source``'s after dt with the gyro reading w,
    eqs (3)–(7) of the module docstring; ``source`` and ``target`` may be the same."""
    s = floats(state)
    q, b = quaternion(s, source + RECORD.q), vector(s, source + RECORD.b)
    A, Bc, C = _blocks(s, source + RECORD.P)  # P = [[A, Bc], [Bcᵀ, C]]
    if dt > 0.0:
        wh = sub(w, b)  # ω̂ = ω̃ − b̂                                                  (3)
        step = quat_exp(scale(dt, wh))
        q = normalized(qmul(q, step))  # q̂ ← q̂ ⊗ exp(ω̂ Δt)                            (4)
        Theta = dcm(step)  # Θ = C(exp(ω̂ Δt))                                           (5)
        angle = norm(wh) * dt
        Wx = cross_matrix(wh)
        if angle < 1e-4:  # series to the first neglected term, ~angle² relative
            c1, c2 = dt * dt / 2.0, dt * dt * dt / 6.0
        else:
            omega = angle / dt
            c1 = (1.0 - math.cos(angle)) / (omega * omega)
            c2 = (angle - math.sin(angle)) / (omega * omega * omega)
        # Ψ = −(I Δt − [ω̂×] c1 + [ω̂×]² c2)                                             (5)
        Psi = mat_combine(1.0, mat_combine(-dt, identity(), c1, Wx), -c2, matmul(Wx, Wx))
        sv2, su2 = v[P.arw] * v[P.arw], v[P.rrw] * v[P.rrw]
        # Φ P Φᵀ + Q, Φ = [[Θ, Ψ], [0, I]], by blocks: Φ P's first row (FA, FB)          (6)
        FA = mat_add(matmul(Theta, A), matmul(Psi, transpose(Bc)))  # Θ A + Ψ Bcᵀ
        FB = mat_add(matmul(Theta, Bc), matmul(Psi, C))  # Θ Bc + Ψ C
        A = mat_add(matmul(FA, transpose(Theta)), matmul(FB, transpose(Psi)))
        A = plus_diagonal(A, sv2 * dt + su2 * dt * dt * dt / 3.0)  # + Q_θθ              (7)
        Bc = plus_diagonal(FB, -(su2 * dt * dt / 2.0))  # + Q_θb                          (7)
        C = plus_diagonal(C, su2 * dt)  # + Q_bb                                         (7)
    _store(state, target, q, b, symmetric(A), Bc, symmetric(C))
    state[target + RECORD.initialised] = 1.0


@jitable
def _update(state, a: int, at: int, z) -> None:
    """Record ``at``'s q̂, b̂, P after the measurement residual z, eqs (9)–(12) of the
    module docstring; its NIS (13) into the section's (at ``a``) ``nis``."""
    s = floats(state)
    q, b = quaternion(s, at + RECORD.q), vector(s, at + RECORD.b)
    A, Bc, C = _blocks(s, at + RECORD.P)
    R = matrix(s, S.R)
    S_inv = inv3_reciprocal(mat_add(A, R))  # S⁻¹, S = H P Hᵀ + R = A + R             (9)
    Ka, Kb = matmul(A, S_inv), matmul(transpose(Bc), S_inv)  # K = P Hᵀ S⁻¹          (10)
    da, db = rotate(Ka, z), rotate(Kb, z)  # x̂ = K z                                   (10)
    q = normalized(qmul(q, quat_exp(da)))  # q̂ ← q̂ ⊗ exp(x̂_θ)                         (11)
    b = add(b, db)  # b̂ ← b̂ + x̂_b                                                     (11)
    # Joseph form (12) by blocks, with I − K H = [[M, 0], [−Kb, I]], M = I − Ka
    M, Kat, Kbt = mat_combine(1.0, identity(), -1.0, Ka), transpose(Ka), transpose(Kb)
    MA, KaR, KbR = matmul(M, A), matmul(Ka, R), matmul(Kb, R)
    A2 = mat_add(matmul(MA, transpose(M)), matmul(KaR, Kat))
    B2 = mat_add(
        mat_combine(-1.0, matmul(MA, Kbt), 1.0, matmul(M, Bc)), matmul(KaR, Kbt)
    )  # fmt: skip
    KbA, Bt = matmul(Kb, A), transpose(Bc)
    C2 = mat_combine(1.0, matmul(KbA, Kbt), -1.0, mat_add(matmul(Bt, Kbt), matmul(Kb, Bc)))
    C2 = mat_add(mat_add(C2, C), matmul(KbR, Kbt))
    _store(state, at, q, b, symmetric(A2), B2, symmetric(C2))
    state[a + FILTER.nis] = dot(z, rotate(S_inv, z))  # zᵀ S⁻¹ z                      (13)


# -- 3×3 blocks (tuples of rows) -----------------------------------------------------------
@jitable
def _blocks(s, at: int) -> tuple:
    """(A, B, C) of the 6×6 P at ``at`` (row-major): [[A, B], [Bᵀ, C]]."""
    return (
        _block(s, at, 0, 0),
        _block(s, at, 0, 3),
        _block(s, at, 3, 3),
    )


@jitable
def _block(s, at: int, row: int, column: int) -> tuple:
    k = at + 6 * row + column
    return (
        (s[k], s[k + 1], s[k + 2]), (s[k + 6], s[k + 7], s[k + 8]),
        (s[k + 12], s[k + 13], s[k + 14]),
    )  # fmt: skip


@jitable
def _store(state, at: int, q, b, A, Bc, C) -> None:
    for i in range(4):
        state[at + RECORD.q + i] = q[i]
    for i in range(3):
        state[at + RECORD.b + i] = b[i]
        for k in range(3):
            state[at + RECORD.P + 6 * i + k] = A[i][k]
            state[at + RECORD.P + 6 * i + 3 + k] = Bc[i][k]
            state[at + RECORD.P + 6 * (i + 3) + k] = Bc[k][i]
            state[at + RECORD.P + 6 * (i + 3) + 3 + k] = C[i][k]
