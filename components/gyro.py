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
no slope was set).

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
from .noise import normal, stream_key
from .sensing import tick, tick_time
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
        T = 1.0 / p.rate
        phi = math.exp(-T / p.bias_correlation_time)
        self.t0, self.rate, self.period = t0, p.rate, T
        self.matrix = tuple(
            tuple((i == j) + (p.scale_factor[i] if i == j else 0.0) + p.misalignment[i, j]
                  for j in range(3))
            for i in range(3)
        )  # fmt: skip
        self.white = math.sqrt(p.arw**2 / T + p.rrw**2 * T / 12.0)
        self.white0 = p.arw / math.sqrt(T)  # sample 0: bias constant before t0
        self.walk = p.rrw * math.sqrt(T)
        self.sigma_gm = p.bias_instability / GAUSS_MARKOV_ALLAN_PEAK
        self.phi, self.drive = phi, self.sigma_gm * math.sqrt(1.0 - phi * phi)
        self.keys = tuple(stream_key(p.seed, s) for s in range(9))
        # committed state: the latest sample k and what sample k + 1 needs
        self.k = -1
        self.t_last = None  # last communication point seen (None: none yet)
        self.w_last = (0.0, 0.0, 0.0)
        self.slope_last = (None, None, None)  # ẇ set for the step from t_last (None: none)
        self.integral = (0.0, 0.0, 0.0)  # of the true rate since t_k
        self.b_rw = tuple(p.bias0.tolist())
        self.b_gm = (0.0, 0.0, 0.0)
        self.residual = (0.0, 0.0, 0.0)  # quantiser remainder (rad/s)
        self.saturated = (False, False, False)
        self.w_meas = (0.0, 0.0, 0.0)
        self.t = t0

    def step(self, t, dt):
        # commit at the model's clock, where output() evaluated (the host's t may differ
        # from it by rounding: the samples must not)
        state = self._advance(self.t, tuple(self.u.w_BI_B.tolist()))
        self.warnings.extend(state.pop("notes"))
        vars(self).update(state)
        self.t = t + dt

    def output(self):
        state = self._advance(self.t, tuple(self.u.w_BI_B.tolist()))
        self.y.w_meas_B[:] = state["w_meas"]
        b_rw, b_gm = state["b_rw"], state["b_gm"]
        self.y.bias_B[:] = (b_rw[0] + b_gm[0], b_rw[1] + b_gm[1], b_rw[2] + b_gm[2])

    # -- internals -------------------------------------------------------------------
    def _advance(self, now: float, w_now: tuple) -> dict:
        """The committed state brought to ``now`` (input ``w_now``): every sample up to
        ``now`` taken, the true rate linear between the last communication point and now
        (constant before t0).  Pure: returns the new state."""
        t0, rate, T = self.t0, self.rate, self.period
        k, t_last, w_last, integral = self.k, self.t_last, self.w_last, self.integral
        slope = self.slope_last
        if t_last is None:  # nothing seen yet: the rate was w_now over (t0 − T, t0]
            t_last, w_last, slope = t0 - T, w_now, (None, None, None)
        span = now - t_last
        state = {"b_rw": self.b_rw, "b_gm": self.b_gm, "residual": self.residual}
        state.update(w_meas=self.w_meas, saturated=self.saturated, notes=[])
        segment = t_last  # start of the part of (t_last, now] not yet integrated
        for j in range(k + 1, tick(now, t0, rate) + 1):
            end = min(tick_time(j, t0, rate), now)
            integral = _add_rate(integral, segment, end, t_last, span, w_last, w_now, slope)
            self._sample(j, tuple(x / T for x in integral), state)
            integral, segment, k = (0.0, 0.0, 0.0), end, j
        integral = _add_rate(integral, segment, now, t_last, span, w_last, w_now, slope)
        given = self._given("w_BI_B").tolist()
        now_slope = tuple(
            x if g else None for g, x in zip(given, self.input_rate("w_BI_B").tolist())
        )
        state.update(k=k, t_last=now, w_last=w_now, integral=integral, slope_last=now_slope)
        return state

    def _sample(self, j: int, w_true: tuple, state: dict) -> None:
        """Sample j from the true average rate over its interval: updates ``state``."""
        keys, p = self.keys, self.p
        if j == 0:
            b_rw = state["b_rw"]
            b_gm = tuple(self.sigma_gm * normal(keys[GM + i], 0) for i in range(3))
            bias_mean, white = b_rw, self.white0
            b_gm_mean = b_gm
        else:
            b_rw = tuple(
                b + self.walk * normal(keys[RRW + i], j) for i, b in enumerate(state["b_rw"])
            )
            b_gm = tuple(
                self.phi * b + self.drive * normal(keys[GM + i], j)
                for i, b in enumerate(state["b_gm"])
            )
            bias_mean = tuple(0.5 * (a + b) for a, b in zip(state["b_rw"], b_rw))
            b_gm_mean = tuple(0.5 * (a + b) for a, b in zip(state["b_gm"], b_gm))
            white = self.white
        quantum, limit = p.quantization, p.saturation
        measured, residual, saturated = [], [], []
        for i, row in enumerate(self.matrix):
            raw = (
                row[0] * w_true[0] + row[1] * w_true[1] + row[2] * w_true[2]
                + bias_mean[i] + b_gm_mean[i] + white * normal(keys[ARW + i], j)
            )  # fmt: skip
            saturated.append(raw >= limit or raw <= -limit)
            if saturated[i]:
                measured.append(limit if raw > 0.0 else -limit)
                residual.append(0.0)
                if not state["saturated"][i]:
                    state["notes"].append(
                        f"t={tick_time(j, self.t0, self.rate):.6g} s: axis {i + 1} saturated "
                        f"at +-{limit} rad/s (the measurement is clipped)"
                    )
            elif quantum > 0.0:
                carried = state["residual"][i] + raw
                value = math.floor(carried / quantum + 0.5) * quantum
                measured.append(value)
                residual.append(carried - value)
            else:
                measured.append(raw)
                residual.append(0.0)
        state.update(b_rw=b_rw, b_gm=b_gm, residual=tuple(residual), w_meas=tuple(measured))
        state["saturated"] = tuple(saturated)


def _add_rate(integral, a, b, t_last, span, w_last, w_now, slope) -> tuple:
    """integral + ∫_a^b w dt for w from w_last at t_last to w_now at t_last + span: per
    axis linear, or where ``slope`` gives ẇ at t_last the parabola with that slope."""
    if b <= a:
        return integral
    s = (0.5 * (a + b) - t_last) / span  # the midpoint value integrates a line exactly
    out = []
    for i, wl, wn, d in zip(integral, w_last, w_now, slope):
        if d is None:
            out.append(i + (b - a) * (wl + s * (wn - wl)))
            continue
        sa, sb = a - t_last, b - t_last  # ∫ (wl + d x + c x²) dx over [sa, sb] / (sb − sa)
        c = (wn - wl - d * span) / (span * span)
        out.append(
            i + (b - a) * (wl + d * 0.5 * (sa + sb) + c * (sa * sa + sa * sb + sb * sb) / 3.0)
        )
    return tuple(out)
