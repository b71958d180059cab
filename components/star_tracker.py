"""Star tracker: the body attitude measured through the sensor's mounting, sampled and late.

Frames: sensor S, boresight +z_S, mounted by q_SB (attitude of S relative to B), so
q_SI = q_BI ⊗ q_SB (DESIGN.md §2).  Sample k is taken at t_k = t0 + k / rate
(components/sensing.py) and released ``latency`` later: the output at t is the latest
sample with t_k + latency ≤ t, held until the next, and ``t_meas`` = t_k is its time of
validity (what an estimator needs to use it).  The true attitude at t_k is the input's:
between communication points the rotation from one to the next at a constant rate
(slerp), before t0 the attitude turning at the rate w_BI_B of t0.  The step commits the
samples the output took when it took them at the same time from the same inputs, bit for
bit (components/sensing.py, reusing the advanced section).

Error of sample k, a small rotation of S given in S axes ([Markley 2014] ch. 4: the
star-tracker attitude error as three independent small angles; terms of ECSS-E-ST-60-20C)::

    δθ_S = (σ_c N₁, σ_c N₂, σ_b N₃) + e_lf(t_k)
    e_lf,i(t) = bias_lf_i sin(2π t / lf_period + φ_i),   φ_i ~ U(0, 2π) from the seed
    error_B = C_SBᵀ δθ_S                                 (the same rotation in B axes)
    q_BI_meas = q_BI(t_k) ⊗ exp(error_B)

with σ_c = nea_cross, σ_b = nea_boresight (1σ noise-equivalent angles) and N standard
normals of sample k (components/noise.py).  e_lf is the low-frequency error (thermo-
elastic, field-of-view): slow against the sample rate, periodic at ``lf_period``.
``error_B`` is measured-minus-true: q_BI(t_k)* ⊗ q_BI_meas = exp(error_B).

Validity at t_k (``valid`` false otherwise; the sample is output all the same):

- Sun: the angle between the boresight b_I = C_BIᵀ C_SBᵀ ẑ and sun_I is ≥ sun_exclusion;
- Earth: the angle between b_I and the nadir −r_I is ≥ ρ + earth_exclusion, where
  ρ = asin(R / |r_I|) is the Earth's apparent radius (a sphere of the WGS-84 equatorial
  radius R): ``earth_exclusion`` is counted from the limb;
- rate: |w_BI_B| ≤ max_rate;
- no outage: t_k is not in [``outage_start``, ``outage_stop``) (a fault on the timeline,
  DESIGN.md §3.2: blinding, a reset; inf: none).

A zero sun_I or r_I (the inputs unconnected) skips that test.  Angles are atan2(|a×b|, a·b),
exact at the boundaries.

Defaults: SSTL Rigel-L (APS star tracker; SSTL's star-tracker FAQ): 3″ across and 28″
about the boresight (68 %) at a 4 Hz update.  Estimates, not from a datasheet: latency
0.2 s, Sun exclusion 30°, Earth exclusion 20° from the limb, maximum rate 3 °/s,
low-frequency error 1″, 1″, 5″ (S axes) over 5900 s (about the default orbit's period,
the thermal cycle that drives it).  Mounting: S = B (boresight along +z_B).
"""

from __future__ import annotations

import math

import numpy as np

from .model import Model, ModelError
from .noise import joined_key, key_halves, normal, stream_key, uniform
from .rotations import IDENTITY_Q, dcm, qmul
from .runtime.flat import matrix, state_table
from .runtime.jit import floats, jitable, output_kernel, step_kernel
from .sensing import (
    EARTH_RADIUS,
    TICK_TOLERANCE,
    angle_between,
    lerp,
    normalized,
    quat_exp,
    reused,
    slerp,
    stamp,
    stamp_size,
    tick,
    tick_time,
    unstamp,
)
from .variables import input_, output, parameter
from .vectors import norm, quat_norm, rotate_back

ARCSEC = math.pi / 180.0 / 3600.0
RIGEL_NEA_CROSS = 3.0 * ARCSEC
RIGEL_NEA_BORESIGHT = 28.0 * ARCSEC
RIGEL_RATE = 4.0  # Hz
DEFAULT_LATENCY = 0.2  # s
DEFAULT_BIAS_LF = (1.0 * ARCSEC, 1.0 * ARCSEC, 5.0 * ARCSEC)
DEFAULT_LF_PERIOD = 5900.0  # s
#: the most samples waiting for their release a star tracker holds (latency × rate)
MAX_WAITING = 10_000
#: noise streams: N₁, N₂, N₃ and the phases of the low-frequency error
NOISE, PHASE = 0, 3
_INPUTS = ("q_BI", "w_BI_B", "sun_I", "r_I")


class StarTracker(Model):
    """Star tracker with noise, low-frequency error, latency and Sun/Earth/rate exclusions."""

    DEFAULT_STEP = 1.0 / RIGEL_RATE  #: its update period

    VARIABLES = (
        parameter(
            "q_SB",
            IDENTITY_Q,
            "1",
            "mounting: attitude of the sensor frame S relative to B (boresight +z_S)",
            shape=(4,),
        ),
        parameter(
            "nea_cross",
            RIGEL_NEA_CROSS,
            "rad",
            "noise-equivalent angle (1 sigma) about each cross-boresight axis x_S, y_S",
        ),
        parameter(
            "nea_boresight",
            RIGEL_NEA_BORESIGHT,
            "rad",
            "noise-equivalent angle (1 sigma) about the boresight z_S",
        ),
        parameter(
            "bias_lf",
            DEFAULT_BIAS_LF,
            "rad",
            "amplitude of the low-frequency error about x_S, y_S, z_S",
            shape=(3,),
        ),
        parameter("lf_period", DEFAULT_LF_PERIOD, "s", "period of the low-frequency error"),
        parameter("rate", RIGEL_RATE, "Hz", "update rate"),
        parameter("latency", DEFAULT_LATENCY, "s", "time from a sample's validity to its output"),
        parameter(
            "sun_exclusion",
            math.radians(30.0),
            "rad",
            "Sun exclusion half-angle about the boresight",
            display_unit="deg",
        ),
        parameter(
            "earth_exclusion",
            math.radians(20.0),
            "rad",
            "Earth exclusion: least angle between the boresight and the Earth's limb",
            display_unit="deg",
        ),
        parameter(
            "max_rate",
            math.radians(3.0),
            "rad/s",
            "largest body rate |w_BI_B| with a valid solution",
            display_unit="deg/s",
        ),
        parameter("outage_start", math.inf, "s", "start of an outage: no valid sample (inf: none)"),
        parameter("outage_stop", math.inf, "s", "end of the outage (samples valid again)"),
        parameter("seed", 2, "1", "seed of the noise (components/noise.py)", type="Integer"),
        input_("q_BI", "1", "true attitude of B relative to I", IDENTITY_Q, shape=(4,)),
        input_(
            "w_BI_B",
            "rad/s",
            "true angular velocity of B relative to I, in B",
            shape=(3,),
            optional="zero: the body is at rest (no rate limit reached)",
            display_unit="deg/s",
        ),
        input_(
            "sun_I",
            "1",
            "unit Sun direction in I (OrbitEnvironment.sun_I)",
            shape=(3,),
            optional="zero: no Sun exclusion test",
        ),
        input_(
            "r_I",
            "m",
            "satellite position in I (OrbitEnvironment.r_I)",
            shape=(3,),
            optional="zero: no Earth exclusion test",
        ),
        output(
            "q_BI_meas",
            "1",
            "measured attitude of B relative to I (the latest released sample)",
            shape=(4,),
            depends=("q_BI", "w_BI_B"),  # w_BI_B: the samples before t0 only
        ),
        output(
            "valid",
            "1",
            "the sample is outside the Sun and Earth exclusions and below max_rate",
            type="Boolean",
            depends=_INPUTS,
        ),
        output(
            "error_B",
            "rad",
            "measured-minus-true rotation vector of the sample, in B (for analysis)",
            shape=(3,),
            display_unit="deg",
        ),
        output("t_meas", "s", "time of validity t_k of the sample"),
    )

    def initialize(self, t0):
        p = self.p
        for name in ("nea_cross", "nea_boresight", "latency", "sun_exclusion", "earth_exclusion"):
            if not getattr(p, name) >= 0.0:
                raise ModelError(f"{name} must be >= 0, got {getattr(p, name)}")
        for name in ("rate", "lf_period", "max_rate"):
            if not getattr(p, name) > 0.0:
                raise ModelError(f"{name} must be > 0, got {getattr(p, name)}")
        if not p.outage_start <= p.outage_stop:
            raise ModelError(
                f"outage_start must not be after outage_stop, got {p.outage_start} and "
                f"{p.outage_stop}"
            )
        if abs(quat_norm(p.q_SB) - 1.0) > 1e-6:
            raise ModelError(f"q_SB must be a unit quaternion, got {p.q_SB.tolist()}")
        keys = [half for i in range(3) for half in key_halves(stream_key(p.seed, NOISE + i))]
        phase = [2.0 * math.pi * uniform(stream_key(p.seed, PHASE + i), 0) for i in range(3)]
        # at most floor(latency rate) + 2 samples wait for their release (ticks in
        # [t − latency, t]); one more for the rounding of the ticks
        capacity = math.floor(p.latency * p.rate + TICK_TOLERANCE) + 3
        if capacity > MAX_WAITING:
            raise ModelError(
                f"latency {p.latency:g} s at rate {p.rate:g} Hz is {capacity} samples waiting "
                f"for their release, more than the {MAX_WAITING} a star tracker holds"
            )
        rows = dcm(normalized(p.q_SB.tolist()))
        section = WAITING.size + capacity * SAMPLE.size
        self.state = state = np.zeros(SECTIONS + 2 * section + STAMP_SIZE)
        state[S.t0], state[S.capacity], state[S.section] = t0, capacity, section
        state[S.C_SB : S.C_SB + 9] = (*rows[0], *rows[1], *rows[2])
        state[S.keys : S.keys + 6], state[S.phase : S.phase + 3] = keys, phase
        self.t = t0

    def step(self, t, dt):
        # at the model's clock, as output() (components/gyro.py, step)
        if tracker_step(self.values, self.state, self.t, dt) == FULL:
            raise ModelError(_FULL)
        self.t = t + dt

    def output(self):
        if tracker_output(self.values, self.state, self.t) == FULL:
            raise ModelError(_FULL)

    @classmethod
    def state_problem(cls, attributes, reference):
        """The kernels index the state with its constants and each section's count of
        samples waiting: the constants are those the parameters make, the counts whole
        numbers up to the capacity."""
        state, constants = attributes["state"], reference["state"][:SECTIONS]
        if not np.array_equal(state[:SECTIONS], constants):
            return "constants (capacity, section length, mounting, keys) are not its parameters'"
        for at in (SECTIONS, SECTIONS + int(constants[S.section])):
            n = float(state[at + WAITING.n])
            if not (n == int(n) and 0 <= n <= constants[S.capacity]):
                return f"count of samples waiting {n!r} is not a whole number in [0, capacity]"
        return ""


_FULL = "internal error: more samples wait for their release than the state holds"

# -- kernels (components/runtime/jit.py) ----------------------------------------------
P, U, Y = StarTracker.names()
#: the state array: t0, the capacity of the pipeline, the length of a section, C_SB
#: (row-major), the noise keys (key_halves) and the low-frequency phases; then two sections
#: (WAITING and the pipeline): the committed one, and the one advanced to the output's time
S = state_table("StarTracker constants", t0=1, capacity=1, section=1, C_SB=9, keys=6, phase=3)
SECTIONS = S.size  # where the committed section starts
#: a section: whether a communication point was seen, its time and inputs (q_BI, w_BI_B,
#: sun_I, r_I), the last sample taken and the number of samples waiting, then those
#: (SAMPLE each), oldest first
WAITING = state_table("StarTracker section", seen=1, t_last=1, inputs=13, k=1, n=1)
#: a sample waiting for its release: its index j and time t_j, q_BI_meas, error_B, valid
SAMPLE = state_table("StarTracker sample", j=1, t=1, q=4, error=3, valid=1)
#: the statuses: more samples wait than the pipeline holds (an internal error)
FULL = 1
#: the inputs :func:`advance` reads (all of them), which the stamp after the two sections
#: keeps (components/sensing.py, reusing the advanced section)
INPUTS = ((U.q_BI, U.r_I + 3),)
STAMP_SIZE = stamp_size(INPUTS)


@step_kernel(StarTracker)
def tracker_step(values, state, t, dt):
    """Every sample up to the model's time t taken, those released kept: committed (the
    advanced section as the output left it if it is that, components/sensing.py)."""
    size = int(state[S.section])
    status = reused(values, state, SECTIONS + 2 * size, INPUTS, t)
    if status < 0:
        status = advance(values, state, t)
    if status == 0:
        for i in range(size):
            state[SECTIONS + i] = state[SECTIONS + size + i]
        unstamp(state, SECTIONS + 2 * size)
    return status


@output_kernel(StarTracker)
def tracker_output(values, state, t):
    """The sample released at t (the committed state advanced to t, not committed)."""
    status = advance(values, state, t)
    if status == 0:
        row = SECTIONS + int(state[S.section]) + WAITING.size  # the oldest sample waiting
        for i in range(4):
            values[Y.q_BI_meas + i] = state[row + SAMPLE.q + i]
        for i in range(3):
            values[Y.error_B + i] = state[row + SAMPLE.error + i]
        values[Y.valid], values[Y.t_meas] = state[row + SAMPLE.valid], state[row + SAMPLE.t]
    return status


@jitable
def advance(values, state, now: float) -> int:
    """The committed section brought to ``now`` (the inputs of ``now``) into the advanced
    one: the samples up to ``now`` taken, those released at ``now`` or later kept.  Between
    communication points the truth is interpolated (slerp, lerp), before the first the
    attitude turned at its rate; stamped (components/sensing.py)."""
    unstamp(state, SECTIONS + 2 * int(state[S.section]))
    v, s = floats(values), floats(state)
    c, a = SECTIONS, SECTIONS + int(s[S.section])
    t0, rate = s[S.t0], v[P.rate]
    released, newest = tick(now - v[P.latency], t0, rate), tick(now, t0, rate)
    q_now = normalized(v[U.q_BI : U.q_BI + 4])
    w_now, sun_now = (
        (v[U.w_BI_B], v[U.w_BI_B + 1], v[U.w_BI_B + 2]),
        (v[U.sun_I], v[U.sun_I + 1], v[U.sun_I + 2]),
    )
    r_now = (v[U.r_I], v[U.r_I + 1], v[U.r_I + 2])
    n = 0
    for i in range(int(s[c + WAITING.n])):  # the samples still waiting
        row = c + WAITING.size + SAMPLE.size * i
        if s[row + SAMPLE.j] >= released:
            for x in range(SAMPLE.size):
                state[a + WAITING.size + SAMPLE.size * n + x] = s[row + x]
            n += 1
    k = int(s[c + WAITING.k])
    if s[c + WAITING.seen] == 0.0:  # the start: the attitude turned at w_now before
        first = min(released, newest)
    else:
        first = max(k + 1, released)  # those before are not kept
        t_last, last = s[c + WAITING.t_last], s[c + WAITING.inputs : c + WAITING.inputs + 13]
        q_last = (last[0], last[1], last[2], last[3])
        w_last, sun_last = (last[4], last[5], last[6]), (last[7], last[8], last[9])
        r_last = (last[10], last[11], last[12])
    for j in range(first, newest + 1):
        if n == int(s[S.capacity]):
            return FULL
        t_j = tick_time(j, t0, rate)
        if s[c + WAITING.seen] == 0.0:
            dt = t_j - now
            q = qmul(q_now, quat_exp((w_now[0] * dt, w_now[1] * dt, w_now[2] * dt)))
            truth = (q, w_now, sun_now, r_now)
        else:
            f = min(1.0, (t_j - t_last) / (now - t_last))
            truth = (
                slerp(q_last, q_now, f),
                lerp(w_last, w_now, f),
                lerp(sun_last, sun_now, f),
                lerp(r_last, r_now, f),
            )
        _sample(values, state, j, t_j, truth, a + WAITING.size + SAMPLE.size * n)
        n += 1
    (
        state[a + WAITING.seen],
        state[a + WAITING.t_last],
        state[a + WAITING.k],
        state[a + WAITING.n],
    ) = 1.0, now, max(newest, k), n
    inputs = (*q_now, *w_now, *sun_now, *r_now)
    for i in range(13):
        state[a + WAITING.inputs + i] = inputs[i]
    stamp(values, state, SECTIONS + 2 * int(s[S.section]), INPUTS, now, 0)
    return 0


@jitable
def _sample(values, state, j: int, t_j: float, truth, row: int) -> None:
    """Sample j (time t_j) of the true state ``truth`` into state[row : row + ROW]."""
    v, s = floats(values), floats(state)
    q, w, sun, r = truth
    sigma = (v[P.nea_cross], v[P.nea_cross], v[P.nea_boresight])
    omega = 2.0 * math.pi / v[P.lf_period]
    error_S = (
        sigma[0] * normal(_key(s, 0), j) + v[P.bias_lf] * math.sin(omega * t_j + s[S.phase]),
        sigma[1] * normal(_key(s, 1), j)
        + v[P.bias_lf + 1] * math.sin(omega * t_j + s[S.phase + 1]),
        sigma[2] * normal(_key(s, 2), j)
        + v[P.bias_lf + 2] * math.sin(omega * t_j + s[S.phase + 2]),
    )
    C_SB = matrix(s, S.C_SB)
    error_B = rotate_back(C_SB, error_S)
    q_meas = normalized(qmul(q, quat_exp(error_B)))
    valid = _valid(v, C_SB, q, w, sun, r) and not v[P.outage_start] <= t_j < v[P.outage_stop]
    state[row + SAMPLE.j], state[row + SAMPLE.t] = j, t_j
    state[row + SAMPLE.valid] = 1.0 if valid else 0.0
    for i in range(4):
        state[row + SAMPLE.q + i] = q_meas[i]
    for i in range(3):
        state[row + SAMPLE.error + i] = error_B[i]


@jitable
def _key(s, stream: int) -> int:
    return joined_key(s[S.keys + 2 * stream], s[S.keys + 2 * stream + 1])


@jitable
def _valid(v, C_SB, q, w, sun, r) -> bool:
    boresight = rotate_back(dcm(q), C_SB[2])  # C_BIᵀ C_SBᵀ ẑ
    if norm(w) > v[P.max_rate]:
        return False
    if norm(sun) > 0.0 and angle_between(boresight, sun) < v[P.sun_exclusion]:
        return False
    radius = norm(r)
    if radius > 0.0:
        limb = math.asin(min(1.0, EARTH_RADIUS / radius))
        nadir = (-r[0], -r[1], -r[2])
        if angle_between(boresight, nadir) < limb + v[P.earth_exclusion]:
            return False
    return True
