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

``step`` and ``output`` are each one kernel (components/jit.py) on the value array and the
state array: the filter's history is a table of records there (``RECORD``), its matrices
3×3 blocks of tuples (P = [[A, B], [Bᵀ, C]], attitude and bias), S inverted by its
cofactors.

Defaults: the sensors' own defaults (components/gyro.py, components/star_tracker.py):
σ_v = the gyro's ARW; σ_u = √(rrw² + 2 σ_β²/T_c), the random walk that covers the
gyro's bias instability (its Gauss–Markov drive); σ_c, σ_b and q_SB of the star tracker;
σ_b0 = 10 °/h (twice the gyro's default initial bias).  The star tracker's low-frequency
error is not modelled by the filter (it appears as a slowly varying bias).
"""

from __future__ import annotations

import math

import numpy as np

from .flat import StateTable
from .gyro import DEFAULT_RATE, DEG_PER_HOUR, FILTER_BIAS_WALK, STIM300_ARW
from .jit import floats, jitable, output_kernel, step_kernel
from .model import Model, ModelError
from .rotations import IDENTITY_Q, dcm, qmul, rotate
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
from .variables import Layout, input_, output, parameter

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
        section = RECORDS + capacity * N_RECORD
        self.state = np.zeros(SECTIONS + 2 * section)
        self.state[:SECTIONS] = (t0, capacity, section, *R.reshape(-1))
        self.t = t0

    def step(self, t, dt):
        # at the model's clock, as output() (components/gyro.py, step)
        status = estimator_step(self.values, self.state, self.t, dt)
        if status == FULL:
            raise ModelError(_FULL)
        if status == LATE:
            t_j, t_m = self.state[SECTIONS + NOTE : SECTIONS + NOTE + 2]
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
        for at in (SECTIONS, SECTIONS + int(constants[SECTION])):
            n = float(state[at + N_RECORDS])
            if not (n == int(n) and 0 <= n <= constants[CAPACITY] - 2):
                return f"count of records {n!r} is not a whole number in [0, capacity - 2]"
        return ""

    @property
    def records(self) -> list:
        """The committed records (t, gyro reading of the interval ending at t, q̂, b̂, P;
        None for the three before initialisation), for analysis."""
        s = self.state
        decoded = []
        for i in range(int(s[SECTIONS + N_RECORDS])):
            r = s[_record(SECTIONS, i) : _record(SECTIONS, i + 1)]
            known = r[INITIALISED] != 0.0
            decoded.append(
                (
                    float(r[T]),
                    tuple(r[W : W + 3].tolist()),
                    tuple(r[Q : Q + 4].tolist()) if known else None,
                    tuple(r[B : B + 3].tolist()) if known else None,
                    r[P : P + 36].reshape(6, 6).copy() if known else None,
                )
            )
        return decoded


# -- kernels (components/jit.py) ------------------------------------------------------
_AT = Layout(AttitudeEstimator.VARIABLES).offset  # offsets in AttitudeEstimator.values
P_RATE, P_ARW, P_RRW, P_SIGMA_BIAS0, P_HISTORY = (
    _AT["rate"], _AT["arw"], _AT["rrw"], _AT["sigma_bias0"], _AT["history"]
)  # fmt: skip
U_W, U_Q_M, U_VALID, U_T_MEAS = (_AT[name] for name in _INPUTS)
U_Q_OI, U_W_OI, Y_Q_BO, Y_W_BO = (_AT[n] for n in ("q_OI", "w_OI_O", "q_BO_est", "w_BO_B_est"))
Y_Q, Y_W, Y_BIAS, Y_SIGMA_ATT, Y_SIGMA_BIAS = (
    _AT["q_BI_est"], _AT["w_BI_B_est"], _AT["bias_est_B"], _AT["sigma_att"], _AT["sigma_bias"]
)  # fmt: skip
Y_INNOVATION, Y_NIS, Y_VALID, Y_N_UPDATES = (
    _AT["innovation"], _AT["nis"], _AT["valid"], _AT["n_updates"]
)  # fmt: skip
#: the state array: t0, the records a section holds, the length of a section, R
#: (row-major); then two sections (FILTER and the records): the committed one, and the one
#: advanced to the output's time
CONSTANTS = StateTable(t0=1, capacity=1, section=1, R=9)
T0, CAPACITY, SECTION, R_ = CONSTANTS.offsets
SECTIONS = CONSTANTS.size  # where the committed section starts
#: a section: the last cycle's index (1 when there is one), the inputs of the last call
#: (1 when there were: w_meas_B, q_BI_meas, meas_valid, t_meas), the measurement seen at
#: the last cycle (1 when one was: t_meas, q_BI_meas), the time of the last measurement
#: processed (1 when one was), the latest innovation, its NIS, the updates, 1 once the late
#: warning was given, the (cycle, measurement) times of a late warning to give, the count of
#: records, then the records (RECORD each), oldest first
FILTER = StateTable(
    cycled=1, j=1, called=1, last_inputs=9, seen=1, seen_measurement=5, anchored=1, anchor=1,
    innovation=3, nis=1, n_updates=1, late_warned=1, note=2, n_records=1,
)  # fmt: skip
CYCLED, J, CALLED, LAST_INPUTS, SEEN, SEEN_MEASUREMENT, ANCHORED, ANCHOR = FILTER.offsets[:8]
INNOVATION, NIS, N_UPDATES, LATE_WARNED, NOTE, N_RECORDS = FILTER.offsets[8:]
#: a record: the cycle's (or measurement's) time, the gyro reading of the interval ending
#: at it, 1 once initialised, q̂, b̂ and P (row-major)
RECORD = StateTable(t=1, w=3, initialised=1, q=4, b=3, P=36)
T, W, INITIALISED, Q, B, P = RECORD.offsets
N_RECORD = RECORD.size
RECORDS = FILTER.size  # where the records of a section start
#: the kernels' statuses: a late measurement was ignored (step() warns, once); no room for
#: a cycle's records (a state the model was never in: nothing committed, step() raises);
#: q_OI not a unit quaternion (output() raises)
LATE, FULL, NOT_UNIT = 1, 2, 3
_FULL = "internal error: more records than the history holds"
#: the most cycles the filter's history holds (each record 48 values, twice: ~8 MB)
MAX_RECORDS = 10_000


@step_kernel(AttitudeEstimator)
def estimator_step(values, state, t, dt):
    """Every cycle up to the model's time t run and committed; LATE when a measurement
    older than ``history`` was ignored for the first time."""
    status = advance(values, state, t)
    if status == FULL:
        return FULL
    size = int(state[SECTION])
    for i in range(size):
        state[SECTIONS + i] = state[SECTIONS + size + i]
    return status


@output_kernel(AttitudeEstimator)
def estimator_output(values, state, t):
    """The latest cycle's estimate at t (the committed state advanced to t, not committed)."""
    if advance(values, state, t) == FULL:
        return FULL
    a = SECTIONS + int(state[SECTION])
    last = _record(a, int(state[a + N_RECORDS]) - 1)
    s = floats(state)
    w = (s[last + W], s[last + W + 1], s[last + W + 2])
    known = s[last + INITIALISED] != 0.0
    for i in range(3):
        if known:
            b = s[last + B + i]
            values[Y_BIAS + i], values[Y_W + i] = b, w[i] - b
            values[Y_SIGMA_ATT + i] = math.sqrt(s[last + P + 7 * i])
            values[Y_SIGMA_BIAS + i] = math.sqrt(s[last + P + 7 * (i + 3)])
        else:
            values[Y_BIAS + i], values[Y_W + i] = 0.0, w[i]
            values[Y_SIGMA_ATT + i], values[Y_SIGMA_BIAS + i] = math.pi, values[P_SIGMA_BIAS0]
        values[Y_INNOVATION + i] = s[a + INNOVATION + i]
    for i in range(4):
        values[Y_Q + i] = s[last + Q + i] if known else (1.0 if i == 0 else 0.0)
    values[Y_NIS], values[Y_N_UPDATES] = s[a + NIS], s[a + N_UPDATES]
    values[Y_VALID] = 1.0 if known else 0.0
    return orbit_frame(values)


@jitable
def orbit_frame(values) -> int:
    """q_BO_est = q_OI* ⊗ q_BI_est, w_BO_B_est = w_BI_B_est − C_BO w_OI_O (the relations
    SatelliteDynamics' q_BO and w_BO_B follow, on the estimate); NOT_UNIT when q_OI is
    not a unit quaternion (to 1e-6)."""
    v = floats(values)
    q_OI = (v[U_Q_OI], v[U_Q_OI + 1], v[U_Q_OI + 2], v[U_Q_OI + 3])
    n = math.sqrt(q_OI[0] ** 2 + q_OI[1] ** 2 + q_OI[2] ** 2 + q_OI[3] ** 2)
    if not abs(n - 1.0) <= 1e-6:
        return NOT_UNIT
    q_IO = (q_OI[0] / n, -q_OI[1] / n, -q_OI[2] / n, -q_OI[3] / n)
    q_BO = qmul(q_IO, (v[Y_Q], v[Y_Q + 1], v[Y_Q + 2], v[Y_Q + 3]))
    w_OI_B = rotate(dcm(q_BO), (v[U_W_OI], v[U_W_OI + 1], v[U_W_OI + 2]))
    for i in range(4):
        values[Y_Q_BO + i] = q_BO[i]
    for i in range(3):
        values[Y_W_BO + i] = v[Y_W + i] - w_OI_B[i]
    return 0


@jitable
def advance(values, state, now: float) -> int:
    """The committed section with every cycle up to ``now`` run (the last call's inputs
    held for cycles before ``now``, the current ones at ``now``), into the advanced one;
    LATE when a late measurement was ignored for the first time (its times in ``note``),
    FULL when a cycle's records would not fit (a state the model was never in), else 0."""
    v = floats(values)
    c, a = SECTIONS, SECTIONS + int(state[SECTION])
    size = int(state[SECTION])
    for i in range(size):
        state[a + i] = state[c + i]
    t0, rate = state[T0], v[P_RATE]
    inputs = (
        v[U_W], v[U_W + 1], v[U_W + 2], *normalized(v[U_Q_M : U_Q_M + 4]), v[U_VALID],
        v[U_T_MEAS],
    )  # fmt: skip
    s = floats(state)
    held = c + LAST_INPUTS
    last = (
        s[held], s[held + 1], s[held + 2], s[held + 3], s[held + 4], s[held + 5], s[held + 6],
        s[held + 7], s[held + 8],
    )  # fmt: skip
    newest = tick(now, t0, rate)
    first = newest if state[c + CYCLED] == 0.0 else int(state[c + J]) + 1
    late, capacity = False, int(state[CAPACITY])
    for j in range(first, newest + 1):
        if int(state[a + N_RECORDS]) + 2 > capacity:  # a cycle's record and a measurement's
            return FULL
        t_j = tick_time(j, t0, rate)
        at_now = abs(t_j - now) <= TICK_TOLERANCE / rate or state[c + CALLED] == 0.0
        late = _cycle(values, state, a, t_j, inputs if at_now else last) or late
    if first <= newest:
        state[a + CYCLED], state[a + J] = 1.0, newest
    state[a + CALLED] = 1.0
    for i in range(9):
        state[a + LAST_INPUTS + i] = inputs[i]
    return LATE if late else 0


@jitable
def _cycle(values, state, a: int, t_j: float, inputs) -> bool:
    """One cycle at t_j on the section at ``a``: propagate to t_j, then take a new
    measurement if any; whether a late one was ignored for the first time."""
    v = floats(values)
    w = (inputs[0], inputs[1], inputs[2])
    q_m = (inputs[3], inputs[4], inputs[5], inputs[6])
    valid, t_meas = inputs[7], inputs[8]
    n = int(state[a + N_RECORDS])
    new, latest = _record(a, n), _record(a, n - 1)
    state[new + T], state[new + INITIALISED] = t_j, 0.0
    for i in range(3):
        state[new + W + i] = w[i]
    if n > 0 and state[latest + INITIALISED] != 0.0:
        _propagated(state, latest, new, v, w, t_j - state[latest + T])
    state[a + N_RECORDS] = n + 1
    seen = state[a + SEEN] != 0.0
    at = a + SEEN_MEASUREMENT
    before = (state[at], state[at + 1], state[at + 2], state[at + 3], state[at + 4])
    state[a + SEEN] = 1.0
    state[a + SEEN_MEASUREMENT] = t_meas
    for i in range(4):
        state[a + SEEN_MEASUREMENT + 1 + i] = q_m[i]
    horizon = t_j - v[P_HISTORY]
    same = (
        seen and t_meas == before[0] and q_m[0] == before[1] and q_m[1] == before[2]
        and q_m[2] == before[3] and q_m[3] == before[4]
    )  # fmt: skip
    late = False
    if valid != 0.0 and not same:
        stamped = t_meas >= horizon if not seen else t_meas != before[0]
        t_m = min(t_meas, t_j) if stamped else t_j
        if t_m >= horizon and (state[a + ANCHORED] == 0.0 or t_m > state[a + ANCHOR]):
            _measure(state, a, v, t_m, q_m)
            state[a + ANCHORED], state[a + ANCHOR] = 1.0, t_m
        elif t_m < horizon and state[a + LATE_WARNED] == 0.0:
            state[a + LATE_WARNED] = 1.0
            state[a + NOTE], state[a + NOTE + 1] = t_j, t_m
            late = True
    dropped = 0  # keep the last record at or before the horizon
    while dropped + 1 < int(state[a + N_RECORDS]) and state[_record(a, dropped + 1) + T] <= horizon:
        dropped += 1
    _drop(state, a, dropped)
    return late


@jitable
def _record(a: int, i: int) -> int:
    """Where record i of the section at ``a`` starts."""
    return a + RECORDS + N_RECORD * i


@jitable
def _drop(state, a: int, count: int) -> None:
    """The oldest ``count`` records dropped."""
    n = int(state[a + N_RECORDS])
    for i in range(_record(a, 0), _record(a, n - count)):
        state[i] = state[i + N_RECORD * count]
    state[a + N_RECORDS] = n - count


@jitable
def _measure(state, a: int, v, t_m: float, q_m) -> None:
    """The records with the measurement (t_m, q_m) applied at t_m and the later records
    propagated again from there; those before t_m dropped."""
    n = int(state[a + N_RECORDS])
    after = 0  # the first record after t_m
    while after < n and state[_record(a, after) + T] <= t_m:
        after += 1
    if after == 0:  # before every record (not initialised): room for it first
        for i in range(_record(a, n + 1) - 1, _record(a, 1) - 1, -1):
            state[i] = state[i - N_RECORD]
        n, after = n + 1, 1
    reading = _record(a, after if after < n else after - 1)  # the reading of t_m's interval
    w = (state[reading + W], state[reading + W + 1], state[reading + W + 2])
    initialised = state[_record(a, n - 1) + INITIALISED] != 0.0
    anchor = _record(a, 0)
    if initialised:  # a record at or before t_m exists
        before = _record(a, after - 1)
        _propagated(state, before, anchor, v, w, t_m - state[before + T])
        q = (state[anchor + Q], state[anchor + Q + 1], state[anchor + Q + 2], state[anchor + Q + 3])
        z = rotation_vector(qmul(conj(q), q_m))
        _update(state, a, anchor, z)
        for i in range(3):
            state[a + INNOVATION + i] = z[i]
        state[a + N_UPDATES] += 1.0
    else:  # initialisation: q̂ = q_m, b̂ = 0, P = diag(R, σ_b0² I)
        for i in range(4):
            state[anchor + Q + i] = q_m[i]
        for i in range(3):
            state[anchor + B + i] = 0.0
        for i in range(36):
            state[anchor + P + i] = 0.0
        for i in range(3):
            for k in range(3):
                state[anchor + P + 6 * i + k] = state[R_ + 3 * i + k]
            state[anchor + P + 7 * (i + 3)] = v[P_SIGMA_BIAS0] * v[P_SIGMA_BIAS0]
        state[anchor + INITIALISED] = 1.0
    state[anchor + T] = t_m
    for i in range(3):
        state[anchor + W + i] = w[i]
    for i in range(after, n):  # each later record, propagated from the one before it
        out, into = _record(a, i), _record(a, i - after)
        reading = (state[out + W], state[out + W + 1], state[out + W + 2])
        t_r = state[out + T]
        _propagated(state, into, into + N_RECORD, v, reading, t_r - state[into + T])
        state[into + N_RECORD + T] = t_r
        for k in range(3):
            state[into + N_RECORD + W + k] = reading[k]
    state[a + N_RECORDS] = n - after + 1


@jitable
def _propagated(state, source: int, target: int, v, w, dt: float) -> None:
    """Record ``target``'s q̂, b̂, P: record ``source``'s after dt with the gyro reading w
    (module docstring); ``source`` and ``target`` may be the same."""
    s = floats(state)
    q = (s[source + Q], s[source + Q + 1], s[source + Q + 2], s[source + Q + 3])
    b = (s[source + B], s[source + B + 1], s[source + B + 2])
    A, Bc, C = _blocks(s, source + P)
    if dt > 0.0:
        wh = (w[0] - b[0], w[1] - b[1], w[2] - b[2])
        step = quat_exp((wh[0] * dt, wh[1] * dt, wh[2] * dt))
        q = normalized(qmul(q, step))
        Theta = dcm(step)
        angle = math.sqrt(wh[0] * wh[0] + wh[1] * wh[1] + wh[2] * wh[2]) * dt
        Wx = ((0.0, -wh[2], wh[1]), (wh[2], 0.0, -wh[0]), (-wh[1], wh[0], 0.0))
        if angle < 1e-4:  # series to the first neglected term, ~angle² relative
            c1, c2 = dt * dt / 2.0, dt * dt * dt / 6.0
        else:
            omega = angle / dt
            c1 = (1.0 - math.cos(angle)) / (omega * omega)
            c2 = (angle - math.sin(angle)) / (omega * omega * omega)
        Psi = _linear(1.0, _linear(-dt, _identity(), c1, Wx), -c2, _product(Wx, Wx))
        sv2, su2 = v[P_ARW] * v[P_ARW], v[P_RRW] * v[P_RRW]
        # Φ P Φᵀ + Q with Φ = [[Θ, Ψ], [0, I]]: X = Θ A + Ψ Bᵀ, Y = Θ B + Ψ C
        X = _sum(_product(Theta, A), _product(Psi, _transposed(Bc)))
        Y = _sum(_product(Theta, Bc), _product(Psi, C))
        A = _sum(_product(X, _transposed(Theta)), _product(Y, _transposed(Psi)))
        A = _plus_diagonal(A, sv2 * dt + su2 * dt * dt * dt / 3.0)
        Bc = _plus_diagonal(Y, -(su2 * dt * dt / 2.0))
        C = _plus_diagonal(C, su2 * dt)
    _store(state, target, q, b, _symmetric(A), Bc, _symmetric(C))
    state[target + INITIALISED] = 1.0


@jitable
def _update(state, a: int, at: int, z) -> None:
    """Record ``at``'s q̂, b̂, P after the measurement residual z (module docstring); its
    NIS into the section's (at ``a``) ``nis``."""
    s = floats(state)
    q = (s[at + Q], s[at + Q + 1], s[at + Q + 2], s[at + Q + 3])
    b = (s[at + B], s[at + B + 1], s[at + B + 2])
    A, Bc, C = _blocks(s, at + P)
    R = ((s[R_], s[R_ + 1], s[R_ + 2]), (s[R_ + 3], s[R_ + 4], s[R_ + 5]),
         (s[R_ + 6], s[R_ + 7], s[R_ + 8]))  # fmt: skip
    S_inv = _inverse(_sum(A, R))
    Ka, Kb = _product(A, S_inv), _product(_transposed(Bc), S_inv)  # K = P Hᵀ S⁻¹
    da, db = _times(Ka, z), _times(Kb, z)
    q = normalized(qmul(q, quat_exp(da)))
    b = (b[0] + db[0], b[1] + db[1], b[2] + db[2])
    # Joseph form with I − K H = [[M, 0], [−Kb, I]], M = I − Ka
    M, Kat, Kbt = _linear(1.0, _identity(), -1.0, Ka), _transposed(Ka), _transposed(Kb)
    MA, KaR, KbR = _product(M, A), _product(Ka, R), _product(Kb, R)
    A2 = _sum(_product(MA, _transposed(M)), _product(KaR, Kat))
    B2 = _sum(_linear(-1.0, _product(MA, Kbt), 1.0, _product(M, Bc)), _product(KaR, Kbt))
    KbA, Bt = _product(Kb, A), _transposed(Bc)
    C2 = _linear(1.0, _product(KbA, Kbt), -1.0, _sum(_product(Bt, Kbt), _product(Kb, Bc)))
    C2 = _sum(_sum(C2, C), _product(KbR, Kbt))
    _store(state, at, q, b, _symmetric(A2), B2, _symmetric(C2))
    nis_ = z[0] * (S_inv[0][0] * z[0] + S_inv[0][1] * z[1] + S_inv[0][2] * z[2])
    nis_ += z[1] * (S_inv[1][0] * z[0] + S_inv[1][1] * z[1] + S_inv[1][2] * z[2])
    nis_ += z[2] * (S_inv[2][0] * z[0] + S_inv[2][1] * z[1] + S_inv[2][2] * z[2])
    state[a + NIS] = nis_


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
        state[at + Q + i] = q[i]
    for i in range(3):
        state[at + B + i] = b[i]
        for k in range(3):
            state[at + P + 6 * i + k] = A[i][k]
            state[at + P + 6 * i + 3 + k] = Bc[i][k]
            state[at + P + 6 * (i + 3) + k] = Bc[k][i]
            state[at + P + 6 * (i + 3) + 3 + k] = C[i][k]


@jitable
def _identity() -> tuple:
    return ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@jitable
def _transposed(M) -> tuple:
    return ((M[0][0], M[1][0], M[2][0]), (M[0][1], M[1][1], M[2][1]), (M[0][2], M[1][2], M[2][2]))


@jitable
def _product(X, Y) -> tuple:
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
def _linear(a: float, X, b: float, Y) -> tuple:
    """a X + b Y."""
    return (
        (a * X[0][0] + b * Y[0][0], a * X[0][1] + b * Y[0][1], a * X[0][2] + b * Y[0][2]),
        (a * X[1][0] + b * Y[1][0], a * X[1][1] + b * Y[1][1], a * X[1][2] + b * Y[1][2]),
        (a * X[2][0] + b * Y[2][0], a * X[2][1] + b * Y[2][1], a * X[2][2] + b * Y[2][2]),
    )


@jitable
def _sum(X, Y) -> tuple:
    return (
        (X[0][0] + Y[0][0], X[0][1] + Y[0][1], X[0][2] + Y[0][2]),
        (X[1][0] + Y[1][0], X[1][1] + Y[1][1], X[1][2] + Y[1][2]),
        (X[2][0] + Y[2][0], X[2][1] + Y[2][1], X[2][2] + Y[2][2]),
    )


@jitable
def _plus_diagonal(X, d: float) -> tuple:
    return (
        (X[0][0] + d, X[0][1], X[0][2]),
        (X[1][0], X[1][1] + d, X[1][2]),
        (X[2][0], X[2][1], X[2][2] + d),
    )


@jitable
def _symmetric(X) -> tuple:
    """½ (X + Xᵀ)."""
    return _linear(0.5, X, 0.5, _transposed(X))


@jitable
def _times(X, z) -> tuple:
    return (
        X[0][0] * z[0] + X[0][1] * z[1] + X[0][2] * z[2],
        X[1][0] * z[0] + X[1][1] * z[1] + X[1][2] * z[2],
        X[2][0] * z[0] + X[2][1] * z[1] + X[2][2] * z[2],
    )


@jitable
def _inverse(X) -> tuple:
    """X⁻¹ by its cofactors (X symmetric positive definite: S = A + R)."""
    (a, b, c), (d, e, f), (g, h, i) = X
    A, B, C = e * i - f * h, f * g - d * i, d * h - e * g
    inverse_det = 1.0 / (a * A + b * B + c * C)
    return (
        (A * inverse_det, (c * h - b * i) * inverse_det, (b * f - c * e) * inverse_det),
        (B * inverse_det, (a * i - c * g) * inverse_det, (c * d - a * f) * inverse_det),
        (C * inverse_det, (b * g - a * h) * inverse_det, (a * e - b * d) * inverse_det),
    )
