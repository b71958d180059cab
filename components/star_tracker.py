"""Star tracker: the body attitude measured through the sensor's mounting, sampled and late.

Frames: sensor S, boresight +z_S, mounted by q_SB (attitude of S relative to B), so
q_SI = q_BI ⊗ q_SB (DESIGN.md §2).  Sample k is taken at t_k = t0 + k / rate
(components/sensing.py) and released ``latency`` later: the output at t is the latest
sample with t_k + latency ≤ t, held until the next, and ``t_meas`` = t_k is its time of
validity (what an estimator needs to use it).  The true attitude at t_k is the input's:
between communication points the rotation from one to the next at a constant rate
(slerp), before t0 the attitude turning at the rate w_BI_B of t0.

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
- rate: |w_BI_B| ≤ max_rate.

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

from .model import Model, ModelError
from .noise import normal, stream_key, uniform
from .rotations import IDENTITY_Q, dcm, qmul, rotate_back
from .sensing import (
    EARTH_RADIUS,
    angle_between,
    lerp,
    norm,
    normalized,
    quat_exp,
    slerp,
    tick,
    tick_time,
)
from .variables import input_, output, parameter

ARCSEC = math.pi / 180.0 / 3600.0
RIGEL_NEA_CROSS = 3.0 * ARCSEC
RIGEL_NEA_BORESIGHT = 28.0 * ARCSEC
RIGEL_RATE = 4.0  # Hz
DEFAULT_LATENCY = 0.2  # s
DEFAULT_BIAS_LF = (1.0 * ARCSEC, 1.0 * ARCSEC, 5.0 * ARCSEC)
DEFAULT_LF_PERIOD = 5900.0  # s
#: noise streams: N₁, N₂, N₃ and the phases of the low-frequency error
NOISE, PHASE = 0, 3
_INPUTS = ("q_BI", "w_BI_B", "sun_I", "r_I")


class StarTracker(Model):
    """Star tracker with noise, low-frequency error, latency and Sun/Earth/rate exclusions."""

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
        if abs(norm(p.q_SB) - 1.0) > 1e-6:
            raise ModelError(f"q_SB must be a unit quaternion, got {p.q_SB.tolist()}")
        self.C_SB = dcm(normalized(p.q_SB.tolist()))
        self.keys = tuple(stream_key(p.seed, NOISE + i) for i in range(3))
        phase = tuple(2.0 * math.pi * uniform(stream_key(p.seed, PHASE + i), 0) for i in range(3))
        self.phase = phase
        self.t0 = t0
        # committed state: the inputs at the last communication point, the last sample
        # taken and the samples not yet superseded (k, t_k, q_meas, error_B, valid)
        self.last = None
        self.k = 0
        self.pipeline = ()
        self.t = t0

    def step(self, t, dt):
        # at the model's clock, as output() (components/gyro.py, step)
        self.last, self.k, self.pipeline = self._advance(self.t, self._inputs())
        self.t = t + dt

    def output(self):
        _, _, pipeline = self._advance(self.t, self._inputs())
        k, t_k, q_meas, error, valid = pipeline[0]
        y = self.y
        y.q_BI_meas[:] = q_meas
        y.error_B[:] = error
        y.valid = valid
        y.t_meas = t_k

    # -- internals -------------------------------------------------------------------
    def _inputs(self) -> tuple:
        u = self.u
        return (
            normalized(u.q_BI.tolist()),
            tuple(u.w_BI_B.tolist()),
            tuple(u.sun_I.tolist()),
            tuple(u.r_I.tolist()),
        )

    def _advance(self, now: float, inputs: tuple):
        """(inputs, last sample index, pipeline) brought to ``now``: the samples up to
        ``now`` taken, those older than the one released at ``now`` dropped.  Pure."""
        p, t0 = self.p, self.t0
        released = tick(now - p.latency, t0, p.rate)
        newest = tick(now, t0, p.rate)
        samples = list(self.pipeline)
        q_now, w_now, sun_now, r_now = inputs
        if self.last is None:  # the start: the attitude turned at w_now before
            for j in range(min(released, newest), newest + 1):
                dt = tick_time(j, t0, p.rate) - now
                q = qmul(q_now, quat_exp((w_now[0] * dt, w_now[1] * dt, w_now[2] * dt)))
                samples.append(self._sample(j, (q, w_now, sun_now, r_now)))
        else:
            t_last, (q_last, w_last, sun_last, r_last) = self.last
            for j in range(self.k + 1, newest + 1):
                s = min(1.0, (tick_time(j, t0, p.rate) - t_last) / (now - t_last))
                truth = (
                    slerp(q_last, q_now, s),
                    lerp(w_last, w_now, s),
                    lerp(sun_last, sun_now, s),
                    lerp(r_last, r_now, s),
                )
                samples.append(self._sample(j, truth))
        kept = tuple(sample for sample in samples if sample[0] >= released)
        return (now, inputs), max(newest, self.k), kept

    def _sample(self, j: int, truth: tuple) -> tuple:
        """(j, t_j, q_BI_meas, error_B, valid) of sample j of the true state ``truth``."""
        p, keys, phase = self.p, self.keys, self.phase
        q, w, sun, r = truth
        t_j = tick_time(j, self.t0, p.rate)
        sigma = (p.nea_cross, p.nea_cross, p.nea_boresight)
        omega = 2.0 * math.pi / p.lf_period
        error_S = tuple(
            sigma[i] * normal(keys[NOISE + i], j) + p.bias_lf[i] * math.sin(omega * t_j + phase[i])
            for i in range(3)
        )
        error_B = rotate_back(self.C_SB, error_S)
        q_meas = normalized(qmul(q, quat_exp(error_B)))
        return (j, t_j, q_meas, error_B, self._valid(q, w, sun, r))

    def _valid(self, q, w, sun, r) -> bool:
        p = self.p
        boresight = rotate_back(dcm(q), self.C_SB[2])  # C_BIᵀ C_SBᵀ ẑ
        if norm(w) > p.max_rate:
            return False
        if norm(sun) > 0.0 and angle_between(boresight, sun) < p.sun_exclusion:
            return False
        radius = norm(r)
        if radius > 0.0:
            limb = math.asin(min(1.0, EARTH_RADIUS / radius))
            nadir = (-r[0], -r[1], -r[2])
            if angle_between(boresight, nadir) < limb + p.earth_exclusion:
                return False
        return True
