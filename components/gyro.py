"""Three-axis rate-integrating gyro: noise, bias, scale factor, misalignment, quantisation.

Sampling.  The unit delivers sample k at t_k = t0 + k T (T = 1/rate; components/sensing.py):
the angle increment over (t_{k−1}, t_k] divided by T, i.e. the *average* rate over the
interval, which is what a rate-integrating gyro measures (an acquisition at ``rate`` that
sums the unit's internal increments gives the same).  The output is the latest sample,
held until the next.  The true rate is known at the communication points; in between it
is taken linear, so the average is exact for a rate varying linearly over a step, and
the noise of sample k is drawn from index k (components/noise.py): the record is the same
for any master step (only the true-rate integral depends on it, through rounding).
Before t0 the body rate and the bias are taken constant, so sample 0 at t0 is valid.
A host that interpolates inputs (FMI 2.0 input derivatives, components/model.py) gives the
rate's slope ẇ at the step's start: between communication points the true rate is then the
parabola through w(t_c) with that slope and w(t_c + h), w_c + ẇ s + (w(t_c + h) − w_c − ẇ h)
s²/h², whose average is exact for a rate quadratic over the step (per axis; the line where
no slope was set).  The step commits the samples the output took when it took them at the
same time from the same inputs (and slopes), bit for bit (components/sensing.py, reusing
the advanced section).

Error model (IEEE Std 952-1997, Annex C; [Farrenkopf 1978]; [Markley 2014] ch. 4).  For
axis i, with the true average rate ω̄ over the interval::

    raw = (I + diag(scale_factor) + misalignment) ω̄ + b̄ + n_v
    b = b_rw + β                                          (true bias, output bias_B)
    ḃ_rw = η_u,  b_rw(t0) = bias0        rate random walk, σ_u = rrw (rad/s^1.5)
    β̇ = −β / T_c + η_β                    bias instability, first-order Gauss–Markov

Over one sample interval, exactly for the white noises and the random walk
([Crassidis 2012] ch. 7, the standard gyro simulation)::

    b_rw,k = b_rw,k−1 + σ_u √T N
    n_v + (b̄_rw − ½(b_rw,k−1 + b_rw,k)) ~ √(σ_v²/T + σ_u² T/12) N     (ARW + bridge)
    β_k = φ β_k−1 + σ_β √(1 − φ²) N,   φ = e^{−T/T_c},  β̄ ≈ ½(β_k−1 + β_k)

(N independent standard normals; σ_v = arw in rad/√s; the β average is the trapezoid,
error O(T/T_c), 5e-5 at the defaults; β_0 is drawn from its stationary N(0, σ_β²)).

Bias step (a fault on the timeline, DESIGN.md §3.2): from ``bias_step_time`` on the bias
is b + ``bias_step``; a sample whose interval contains the step averages it over the part
after it, bias_step · (t_k − bias_step_time)/T, and ``bias_B`` includes it from the first
sample at or after it.

Bias instability.  Datasheets quote it as the floor of the Allan deviation (IEEE Std 952
Annex C).  It is modelled here as the Gauss–Markov β, whose Allan variance is
(IEEE Std 952 Annex C; x = τ/T_c)::

    σ_A²(τ) = σ_β² (2x − 3 + 4e^{−x} − e^{−2x}) / x²

maximal at x = 1.8926, where σ_A = 0.61736 σ_β.  ``bias_instability`` B is that
maximum: σ_β = B / 0.61736.  The Allan deviation of a stationary record is then
σ_A² = arw²/τ + σ_A,β²(τ) + rrw² τ/3 (+ quantisation), which tests/components/test_gyro.py
checks against long records.

Output: saturated at ±saturation per axis (the residual of the quantiser is reset; a
warning when an axis enters saturation), then
quantised to multiples of ``quantization`` (rad/s per LSB) with the remainder carried to
the next sample, as a rate-integrating unit's angle counter does: Σ w_meas T differs from
Σ raw T by less than half an LSB times T at every sample (angle quantisation, IEEE Std
952 Annex C), so quantisation does not accumulate.

Defaults: Safran Sensonor STIM300 (datasheet TS1524 rev. 9): ARW 0.15 °/√h, bias
instability 0.5 °/h (Allan floor, measured per IEEE Std 952), scale-factor accuracy
±500 ppm, misalignment 1 mrad, input range ±400 °/s, rate output 2⁻¹⁴ °/s per LSB
(0.22 °/h).  The datasheet gives no rate random walk and no bias-instability time
constant: estimates are T_c = 1000 s (the Allan peak at 1900 s) and the RRW that reaches
the floor at τ = 2·10⁴ s, rrw = B √(3 / 2·10⁴).  The initial bias is 5 °/h per axis
(the datasheet's bias error over static temperature), signs +, −, +; scale factors
+500, −500, +500 ppm and misalignments of 1 mrad (datasheet limits, signs chosen).
Rate: 20 Hz, an AOCS cycle (the STIM300's 125–2000 Hz samples summed over it).
"""

from __future__ import annotations

import math

from .model import Model, ModelError
from .noise import joined_key, key_halves, normal, stream_key
from .runtime.flat import state_table
from .runtime.jit import floats, jitable, output_kernel, step_kernel
from .sensing import reused, stamp, stamp_size, tick, tick_time, unstamp
from .variables import input_, output, parameter

DEG_PER_HOUR = math.pi / 180.0 / 3600.0  # rad/s
STIM300_ARW = 0.15 * math.pi / 180.0 / 60.0  # 0.15 °/√h in rad/√s
STIM300_BIAS_INSTABILITY = 0.5 * DEG_PER_HOUR
STIM300_LSB = 2.0**-14 * math.pi / 180.0  # rad/s
STIM300_RANGE = math.radians(400.0)
BIAS_TIME_CONSTANT = 1000.0  # s (estimate)
RRW_FLOOR_TAU = 2.0e4  # s: where the default RRW reaches the bias-instability floor
STIM300_RRW = STIM300_BIAS_INSTABILITY * math.sqrt(3.0 / RRW_FLOOR_TAU)
DEFAULT_BIAS0 = (5.0 * DEG_PER_HOUR, -5.0 * DEG_PER_HOUR, 5.0 * DEG_PER_HOUR)
DEFAULT_SCALE_FACTOR = (5e-4, -5e-4, 5e-4)
DEFAULT_MISALIGNMENT = ((0.0, 1e-3, -1e-3), (-1e-3, 0.0, 1e-3), (1e-3, -1e-3, 0.0))
DEFAULT_RATE = 20.0  # Hz
#: peak of the Allan deviation of a first-order Gauss–Markov process, in units of its σ
#: (max over x of √((2x − 3 + 4e^{−x} − e^{−2x}) / x²), at x = τ/T_c = 1.8926)
GAUSS_MARKOV_ALLAN_PEAK = 0.6173642831444414
#: noise streams: angle random walk (+ bridge), rate random walk, bias instability; per axis
ARW, RRW, GM = 0, 3, 6


def filter_bias_walk(rrw: float, bias_instability: float, correlation_time: float) -> float:
    """The random-walk density (rad/s^1.5) a filter modelling the bias as a random walk
    uses for this gyro: √(rrw² + 2 σ_β² / T_c), the Gauss–Markov's drive added."""
    sigma = bias_instability / GAUSS_MARKOV_ALLAN_PEAK
    return math.sqrt(rrw * rrw + 2.0 * sigma * sigma / correlation_time)


FILTER_BIAS_WALK = filter_bias_walk(STIM300_RRW, STIM300_BIAS_INSTABILITY, BIAS_TIME_CONSTANT)


class Gyro(Model):
    """Three-axis rate-integrating gyro with noise, bias, scale factor and misalignment."""

    INTERPOLATES_INPUTS = True

    VARIABLES = (
        parameter(
            "arw",
            STIM300_ARW,
            "rad/s0.5",
            "angle random walk sigma_v (1 rad/s0.5 = 3437.7 deg/h0.5)",
            display_unit="deg/h0.5",
        ),
        parameter(
            "rrw",
            STIM300_RRW,
            "rad/s1.5",
            "rate random walk sigma_u of the bias",
            display_unit="deg/h1.5",
        ),
        parameter(
            "bias_instability",
            STIM300_BIAS_INSTABILITY,
            "rad/s",
            "bias instability: the peak Allan deviation of the Gauss-Markov bias term (0: none)",
        ),
        parameter(
            "bias_correlation_time",
            BIAS_TIME_CONSTANT,
            "s",
            "correlation time T_c of the Gauss-Markov bias term",
        ),
        parameter("bias0", DEFAULT_BIAS0, "rad/s", "bias at t0 (random-walk part)", shape=(3,)),
        parameter(
            "scale_factor",
            DEFAULT_SCALE_FACTOR,
            "1",
            "scale-factor error per axis (5e-4 = 500 ppm)",
            shape=(3,),
        ),
        parameter(
            "misalignment",
            DEFAULT_MISALIGNMENT,
            "rad",
            "small-angle misalignment matrix M (measured = (I + diag(scale_factor) + M) w)",
            shape=(3, 3),
        ),
        parameter(
            "quantization",
            STIM300_LSB,
            "rad/s",
            "rate per LSB (remainder carried to the next sample); 0: none",
        ),
        parameter("saturation", STIM300_RANGE, "rad/s", "measurement range +-saturation per axis"),
        parameter("rate", DEFAULT_RATE, "Hz", "sample rate (the output is held between samples)"),
        parameter("bias_step_time", math.inf, "s", "time of a step of the bias (inf: none)"),
        parameter(
            "bias_step",
            0.0,
            "rad/s",
            "the step of the bias from bias_step_time on, per axis",
            shape=(3,),
        ),
        parameter("seed", 1, "1", "seed of the noise (components/noise.py)", type="Integer"),
        input_(
            "w_BI_B",
            "rad/s",
            "true angular velocity of B relative to I, in B",
            shape=(3,),
            display_unit="deg/s",
        ),
        output(
            "w_meas_B",
            "rad/s",
            "measured rate: the latest sample (average rate over its interval), in B",
            shape=(3,),
            depends=("w_BI_B",),
            display_unit="deg/s",
        ),
        output(
            "bias_B",
            "rad/s",
            "true bias at the latest sample (random walk + Gauss-Markov), for analysis",
            shape=(3,),
        ),
    )

    def initialize(self, t0):
        p = self.p
        for name in ("arw", "rrw", "bias_instability", "quantization"):
            if not getattr(p, name) >= 0.0:
                raise ModelError(f"{name} must be >= 0, got {getattr(p, name)}")
        for name in ("bias_correlation_time", "saturation", "rate"):
            if not getattr(p, name) > 0.0:
                raise ModelError(f"{name} must be > 0, got {getattr(p, name)}")
        if math.isnan(p.bias_step_time) or not all(map(math.isfinite, p.bias_step.tolist())):
            raise ModelError(
                f"bias_step_time must be a time or inf and bias_step finite, got "
                f"{p.bias_step_time} and {p.bias_step.tolist()}"
            )
        T = 1.0 / p.rate
        phi = math.exp(-T / p.bias_correlation_time)
        sigma_gm = p.bias_instability / GAUSS_MARKOV_ALLAN_PEAK
        matrix = [
            (i == j) + (p.scale_factor[i] if i == j else 0.0) + p.misalignment[i, j]
            for i in range(3)
            for j in range(3)
        ]
        keys = [half for s in range(9) for half in key_halves(stream_key(p.seed, s))]
        self.state = S.zeros()
        self.state[: S.committed] = (
            t0, p.rate, T, *matrix, math.sqrt(p.arw**2 / T + p.rrw**2 * T / 12.0),
            p.arw / math.sqrt(T), p.rrw * math.sqrt(T), sigma_gm, phi,
            sigma_gm * math.sqrt(1.0 - phi * phi), *keys,
        )  # fmt: skip
        # committed state: the latest sample k (none yet) and what sample k + 1 needs
        self.state[COMMITTED.k] = -1
        self.state[COMMITTED.b_rw : COMMITTED.b_rw + 3] = p.bias0
        self.t = t0

    def step(self, t, dt):
        # commit at the model's clock, where output() evaluated (the host's t may differ
        # from it by rounding: the samples must not)
        if gyro_step(self.values, self.state, self.t, dt) == SATURATED:  # nothing committed
            notes: list = []
            advance(self.values, self.state, self.t, notes)
            commit(self.state)
            self.warnings.extend(
                f"t={tick_time(j, self.state[S.t0], self.state[S.rate]):.6g} s: axis {i + 1} "
                f"saturated at +-{self.p.saturation} rad/s (the measurement is clipped)"
                for j, i in notes
            )
        self.t = t + dt

    def output(self):
        gyro_output(self.values, self.state, self.t)


# -- kernels (components/runtime/jit.py) ----------------------------------------------
P, U, Y = Gyro.names()
#: the derivative a host set for w_BI_B and whether it set it (per axis)
DU, GIVEN = Gyro.derivative_names()
#: a sample's state (after :func:`advance`): the latest sample k, whether a communication
#: point was seen and its time and true rate, the rate's slope set for the step from it and
#: 1 where one was set (per axis), the integral of the true rate since t_k, the bias terms,
#: the quantiser's remainder, the axes saturated, the measured rate
SAMPLED = state_table(
    "Gyro sample state", k=1, seen=1, t_last=1, w_last=3, slope=3, sloped=3, integral=3,
    b_rw=3, b_gm=3, residual=3, saturated=3, w_meas=3,
)  # fmt: skip
#: the inputs :func:`advance` reads: w_BI_B and the derivative a host set for it
INPUTS = ((U.w_BI_B, U.w_BI_B + 3), (DU.w_BI_B, DU.w_BI_B + 3), (GIVEN.w_BI_B, GIVEN.w_BI_B + 3))
#: the state array: t0, the rate and period, the error matrix I + diag(scale_factor) + M
#: (row-major), the white-noise sigmas (of a sample, of sample 0), the random walk's step,
#: the Gauss-Markov sigma, φ and drive, the 9 stream keys (key_halves), then the committed
#: sample state and the one advanced to the output's time (SAMPLED each), and the stamp of
#: the advanced one (components/sensing.py, reusing the advanced section)
S = state_table(
    "Gyro state", t0=1, rate=1, period=1, matrix=9, white=1, white0=1, walk=1, sigma_gm=1,
    phi=1, drive=1, keys=18, committed=SAMPLED.size, advanced=SAMPLED.size,
    stamp=stamp_size(INPUTS),
)  # fmt: skip
#: the rows of the committed and of the advanced sample state
COMMITTED, ADVANCED = SAMPLED.at(S.committed), SAMPLED.at(S.advanced)
#: gyro_step's status: an axis became saturated (nothing committed: step() warns)
SATURATED = 1


@step_kernel(Gyro)
def gyro_step(values, state, t, dt):
    """Every sample up to the model's time t taken and committed (:func:`advance`; the
    advanced state as the output left it if it is that, components/sensing.py);
    SATURATED (nothing committed) when an axis becomes saturated."""
    status = reused(values, state, S.stamp, INPUTS, t)
    if status < 0:
        notes = [(0, 0)]
        notes.pop()
        advance(values, state, t, notes)
        status = SATURATED if len(notes) > 0 else 0
    if status == SATURATED:
        return SATURATED
    commit(state)
    return 0


@output_kernel(Gyro)
def gyro_output(values, state, t):
    """The latest sample at t (the committed state advanced to t, not committed) and the
    true bias of it."""
    notes = [(0, 0)]
    notes.pop()
    advance(values, state, t, notes)
    t_k = tick_time(int(state[ADVANCED.k]), state[S.t0], state[S.rate])
    stepped = t_k >= values[P.bias_step_time]
    for i in range(3):
        values[Y.w_meas_B + i] = state[ADVANCED.w_meas + i]
        values[Y.bias_B + i] = state[ADVANCED.b_rw + i] + state[ADVANCED.b_gm + i]
        if stepped:
            values[Y.bias_B + i] += values[P.bias_step + i]
    return 0


@jitable
def commit(state) -> None:
    """The advanced sample state becomes the committed one."""
    for i in range(SAMPLED.size):
        state[S.committed + i] = state[S.advanced + i]
    unstamp(state, S.stamp)


@jitable
def advance(values, state, now: float, notes) -> None:
    """The committed state brought to ``now`` (the input w_BI_B of ``now``), into the
    advanced one: every sample up to ``now`` taken, the true rate linear (or the parabola
    with the slope set, :func:`_add_rate`) between the last communication point and now
    (constant before t0); (sample, axis) of each axis becoming saturated appended to
    ``notes``; stamped (components/sensing.py), SATURATED when it appended any."""
    unstamp(state, S.stamp)
    noted = len(notes)
    s, v = floats(state), floats(values)
    t0, rate, T = s[S.t0], s[S.rate], s[S.period]
    w_now = (v[U.w_BI_B], v[U.w_BI_B + 1], v[U.w_BI_B + 2])
    k = int(s[COMMITTED.k])
    slope = (s[COMMITTED.slope], s[COMMITTED.slope + 1], s[COMMITTED.slope + 2])
    sloped = (
        s[COMMITTED.sloped] != 0.0,
        s[COMMITTED.sloped + 1] != 0.0,
        s[COMMITTED.sloped + 2] != 0.0,
    )
    if s[COMMITTED.seen] == 0.0:  # nothing seen yet: the rate was w_now over (t0 − T, t0]
        t_last, w_last, sloped = t0 - T, w_now, (False, False, False)
    else:
        t_last, w_last = (
            s[COMMITTED.t_last],
            (s[COMMITTED.w_last], s[COMMITTED.w_last + 1], s[COMMITTED.w_last + 2]),
        )
    integral = (s[COMMITTED.integral], s[COMMITTED.integral + 1], s[COMMITTED.integral + 2])
    for i in range(COMMITTED.b_rw, S.committed + SAMPLED.size):  # the bias terms and on
        state[S.advanced + i - S.committed] = s[i]
    span = now - t_last
    segment = t_last  # start of the part of (t_last, now] not yet integrated
    for j in range(k + 1, tick(now, t0, rate) + 1):
        end = min(tick_time(j, t0, rate), now)
        integral = _add_rate(integral, segment, end, t_last, span, w_last, w_now, slope, sloped)
        _sample(values, state, j, (integral[0] / T, integral[1] / T, integral[2] / T), notes)
        integral, segment, k = (0.0, 0.0, 0.0), end, j
    integral = _add_rate(integral, segment, now, t_last, span, w_last, w_now, slope, sloped)
    state[ADVANCED.k], state[ADVANCED.seen], state[ADVANCED.t_last] = k, 1.0, now
    for i in range(3):
        state[ADVANCED.w_last + i], state[ADVANCED.integral + i] = w_now[i], integral[i]
        given = v[GIVEN.w_BI_B + i] != 0.0  # the slope set for the step from now
        state[ADVANCED.slope + i] = v[DU.w_BI_B + i] if given else 0.0
        state[ADVANCED.sloped + i] = 1.0 if given else 0.0
    stamp(values, state, S.stamp, INPUTS, now, SATURATED if len(notes) > noted else 0)


@jitable
def _sample(values, state, j: int, w_true, notes) -> None:
    """Sample j from the true average rate over its interval, on the advanced state."""
    s = floats(state)
    b_rw = (s[ADVANCED.b_rw], s[ADVANCED.b_rw + 1], s[ADVANCED.b_rw + 2])
    b_gm = (s[ADVANCED.b_gm], s[ADVANCED.b_gm + 1], s[ADVANCED.b_gm + 2])
    if j == 0:
        gm = (
            s[S.sigma_gm] * normal(_key(s, GM), 0),
            s[S.sigma_gm] * normal(_key(s, GM + 1), 0),
            s[S.sigma_gm] * normal(_key(s, GM + 2), 0),
        )
        bias_mean, gm_mean, white, b_gm = b_rw, gm, s[S.white0], gm
    else:
        rw = (
            b_rw[0] + s[S.walk] * normal(_key(s, RRW), j),
            b_rw[1] + s[S.walk] * normal(_key(s, RRW + 1), j),
            b_rw[2] + s[S.walk] * normal(_key(s, RRW + 2), j),
        )
        gm = (
            s[S.phi] * b_gm[0] + s[S.drive] * normal(_key(s, GM), j),
            s[S.phi] * b_gm[1] + s[S.drive] * normal(_key(s, GM + 1), j),
            s[S.phi] * b_gm[2] + s[S.drive] * normal(_key(s, GM + 2), j),
        )
        bias_mean = (0.5 * (b_rw[0] + rw[0]), 0.5 * (b_rw[1] + rw[1]), 0.5 * (b_rw[2] + rw[2]))
        gm_mean = (0.5 * (b_gm[0] + gm[0]), 0.5 * (b_gm[1] + gm[1]), 0.5 * (b_gm[2] + gm[2]))
        white, b_rw, b_gm = s[S.white], rw, gm
    quantum, limit = values[P.quantization], values[P.saturation]
    # the part of the sample's interval (t_j − T, t_j] after the bias step
    after = min(1.0, (tick_time(j, s[S.t0], s[S.rate]) - values[P.bias_step_time]) / s[S.period])
    for i in range(3):
        m = S.matrix + 3 * i
        raw = (
            s[m] * w_true[0] + s[m + 1] * w_true[1] + s[m + 2] * w_true[2]
            + bias_mean[i] + gm_mean[i] + white * normal(_key(s, ARW + i), j)
        )  # fmt: skip
        if after > 0.0:
            raw += after * values[P.bias_step + i]
        saturated = raw >= limit or raw <= -limit
        if saturated:
            measured, residual = limit if raw > 0.0 else -limit, 0.0
            if s[ADVANCED.saturated + i] == 0.0:
                notes.append((j, i))
        elif quantum > 0.0:
            carried = s[ADVANCED.residual + i] + raw
            measured = math.floor(carried / quantum + 0.5) * quantum
            residual = carried - measured
        else:
            measured, residual = raw, 0.0
        state[ADVANCED.w_meas + i], state[ADVANCED.residual + i] = measured, residual
        state[ADVANCED.saturated + i] = 1.0 if saturated else 0.0
        state[ADVANCED.b_rw + i], state[ADVANCED.b_gm + i] = b_rw[i], b_gm[i]


@jitable
def _key(s, stream: int) -> int:
    return joined_key(s[S.keys + 2 * stream], s[S.keys + 2 * stream + 1])


@jitable
def _add_rate(integral, a, b, t_last, span, w_last, w_now, slope, sloped) -> tuple:
    """integral + ∫_a^b w dt for w from w_last at t_last to w_now at t_last + span: per
    axis linear, or where ``sloped`` the parabola with the slope ẇ = ``slope`` at t_last."""
    if b <= a:
        return integral
    s = (0.5 * (a + b) - t_last) / span  # the midpoint value integrates a line exactly
    out = [0.0, 0.0, 0.0]
    for k in range(3):
        i, wl, wn, d = integral[k], w_last[k], w_now[k], slope[k]
        if not sloped[k]:
            out[k] = i + (b - a) * (wl + s * (wn - wl))
            continue
        sa, sb = a - t_last, b - t_last  # ∫ (wl + d x + c x²) dx over [sa, sb] / (sb − sa)
        c = (wn - wl - d * span) / (span * span)
        out[k] = i + (b - a) * (wl + d * 0.5 * (sa + sb) + c * (sa * sa + sa * sb + sb * sb) / 3.0)
    return out[0], out[1], out[2]
