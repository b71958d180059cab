"""Sweep planner: the symmetric two-payload sweep of [Chang 2015] (Chang et al. 2015, §1.2).

Each axis (roll φ, pitch θ) of payload 1 sweeps between +A and −A at the constant rate r
(the imaging rate) and reverses at each end in the ``turnaround_time`` τ with constant
acceleration (the paper's §1.2 (3): "reverses with uniform acceleration").  The rate
ramps linearly from +r to −r over τ, centred on the turning point, so the turning angle is
exactly ±A and the period is::

    P = 4A/r + τ                 (τ = 0: the paper's triangle wave, P = 4A/r)

Payload 1 starts at rest at the upper turning point (+A_roll, +A_pitch) and moves toward
negative roll and pitch (§1.2 (1)–(2)); that is, t = 0 is the middle of a reversal.  With
s = t mod P, the first half period (0 ≤ s < P/2, descending from +A) is::

    0 ≤ s < τ/2:             angle = A − r s²/τ,           rate = −2r s/τ,   accel = −2r/τ
    τ/2 ≤ s < P/2 − τ/2:     angle = A + rτ/4 − r s,       rate = −r,        accel = 0
    P/2 − τ/2 ≤ s < P/2:     angle = −A + r w²/τ,          rate = −2r w/τ,   accel = +2r/τ
                             (w = P/2 − s)

and the second half mirrors it: f(s) = −f(s − P/2).  Angle, rate and acceleration are
exact functions of t; at a switch between a ramp and the constant rate the acceleration
is the one of the piece that begins there (the right limit: the value a sample at that
instant holds over the step after it).  A time within ``SNAP`` = 1 ns of a switch counts as
on it, so that a time grid n·H landing on a switch up to rounding (t mod P is inexact)
samples the piece ahead, not a 0 acceleration for a whole step.

During a reversal the angle moves by rτ/4 beyond the constant-rate stretch, so the
constant-rate (imaging) part of a stroke is 2A − rτ/2 and τ ≤ 4A/r; at τ = 4A/r the whole
motion is uniformly accelerated (rate a triangle wave of period 8A/r).

Paper's values (body text and stated periods; the English abstract swaps the two rates):
roll ±15° at 6 °/s (period 10 s), pitch ±45° at 0.6 °/s (period 300 s).

Default τ = 1 s (the paper gives no number).  It keeps the paper's periods within 10 %
(roll 11 s, pitch 301 s), keeps 90 % of each roll stroke (27° of 30°) at the imaging rate,
and asks the roll drive for 2r/τ = 12 °/s², i.e. Jx φ̈ ≈ 45.5 × 0.21 ≈ 9.5 N·m of motor
torque on a 45.5 kg·m² payload, which a gimbal torque motor of that size delivers.  The
price is on the satellite: every roll reversal swings the pair's yaw momentum by about
4 |Jz − Jx| r sinθ cosθ cos A ≈ 1.8 N·m·s (at θ = ±45°), i.e. a yaw torque ≈ 1.8 N·m·s / τ
(see :mod:`.payload`); a longer τ lowers it in proportion but shortens the imaging stretch.

``symmetric`` true: payload 2 = −payload 1 (angles and rates; §1.2, "synchronous and
opposite").  False: payload 2 moves exactly as payload 1 (the non-compensating reference
case, in which nothing cancels).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .model import Model, ModelError
from .runtime.flat import state_table
from .runtime.jit import floats, jitable, output_kernel
from .variables import output, parameter

DEG = math.pi / 180.0
DEFAULT_TURNAROUND = 1.0  # s; see the module docstring
SNAP = 1e-9  # s; a time this close to a switch of pieces is on it (module docstring)


@dataclass(frozen=True)
class SweepAxis:
    """The sweep of one axis: (angle, rate, acceleration) as exact functions of time."""

    amplitude: float
    rate: float
    turnaround: float
    name: str = "axis"
    period: float = field(init=False, repr=False, compare=False)  # set by __post_init__

    def __post_init__(self):
        A, r, tau, name = self.amplitude, self.rate, self.turnaround, self.name
        if not (math.isfinite(A) and A >= 0):
            raise ModelError(f"{name}_amplitude must be finite and >= 0, got {A}")
        if not (math.isfinite(tau) and tau >= 0):
            raise ModelError(f"turnaround_time must be finite and >= 0, got {tau} s")
        if A == 0:  # axis parked at zero
            object.__setattr__(self, "period", math.inf)
            return
        if not (math.isfinite(r) and r > 0):
            raise ModelError(f"{name}_rate must be finite and > 0, got {r} rad/s")
        stroke_time = 4 * A / r
        if tau > stroke_time * (1 + 1e-12):
            raise ModelError(
                f"turnaround_time {tau:g} s is too long for the {name} sweep: the reversal "
                f"ramp (rate +r to -r) must fit in the stroke, turnaround_time <= "
                f"4 * {name}_amplitude / {name}_rate = {stroke_time:g} s"
            )
        tau = min(tau, stroke_time)  # absorb rounding at the limit
        object.__setattr__(self, "turnaround", tau)
        object.__setattr__(self, "period", stroke_time + tau)

    def __call__(self, t: float) -> tuple[float, float, float]:
        """(angle, rate, acceleration) at time t (t = 0: at +A, starting toward −A)."""
        return sweep_at(self.amplitude, self.rate, self.turnaround, self.period, t)


@jitable
def sweep_at(A: float, r: float, tau: float, period: float, t: float) -> tuple:
    """(angle, rate, acceleration) at time t of the sweep of amplitude A, rate r,
    turnaround τ and period P (module docstring; A = 0: parked at zero)."""
    if A == 0:
        return 0.0, 0.0, 0.0
    half = 0.5 * period
    s = t % period
    sign = 1.0
    if s >= half:
        s -= half
        sign = -1.0
    ramp = 0.5 * tau
    if s < ramp - SNAP:  # leaving the upper turning point
        return (
            sign * (A - r * s * s / tau),
            sign * (-2.0 * r * s / tau),
            sign * (-2.0 * r / tau),
        )
    w = half - s
    if tau > 0 and w <= ramp + SNAP:  # arriving at the lower turning point
        return (
            sign * (-A + r * w * w / tau),
            sign * (-2.0 * r * w / tau),
            sign * (2.0 * r / tau),
        )
    return sign * (A + 0.25 * r * tau - r * s), -sign * r, 0.0


class SweepPlanner(Model):
    """Roll/pitch sweep commands of two payloads ([Chang 2015] §1.2, Figs 3–4)."""

    DEFAULT_STOP = 300.0  #: one pitch period of the default sweep

    VARIABLES = (
        parameter(
            "roll_amplitude",
            15 * DEG,
            "rad",
            "roll sweep amplitude A (roll in +-A)",
            display_unit="deg",
        ),
        parameter(
            "roll_rate",
            6 * DEG,
            "rad/s",
            "constant roll rate between reversals",
            display_unit="deg/s",
        ),
        parameter(
            "pitch_amplitude",
            45 * DEG,
            "rad",
            "pitch sweep amplitude (pitch in +-A)",
            display_unit="deg",
        ),
        parameter(
            "pitch_rate",
            0.6 * DEG,
            "rad/s",
            "constant pitch rate between reversals",
            display_unit="deg/s",
        ),
        parameter(
            "turnaround_time",
            DEFAULT_TURNAROUND,
            "s",
            "duration of each rate reversal (+r to -r at constant acceleration, "
            "centred on the turning point); 0 = triangle wave",
        ),
        parameter(
            "symmetric",
            True,
            "1",
            "true: payload 2 = -payload 1; false: payload 2 = payload 1",
            type="Boolean",
        ),
        output(
            "roll_cmd", "rad", "commanded roll of payloads 1 and 2", shape=(2,), display_unit="deg"
        ),
        output(
            "pitch_cmd",
            "rad",
            "commanded pitch of payloads 1 and 2",
            shape=(2,),
            display_unit="deg",
        ),
        output(
            "roll_rate_cmd",
            "rad/s",
            "commanded roll rate of payloads 1 and 2",
            shape=(2,),
            display_unit="deg/s",
        ),
        output(
            "pitch_rate_cmd",
            "rad/s",
            "commanded pitch rate of payloads 1 and 2",
            shape=(2,),
            display_unit="deg/s",
        ),
        output(
            "roll_accel_cmd",
            "rad/s2",
            "commanded roll acceleration of payloads 1 and 2",
            shape=(2,),
            display_unit="deg/s2",
        ),
        output(
            "pitch_accel_cmd",
            "rad/s2",
            "commanded pitch acceleration of payloads 1 and 2",
            shape=(2,),
            display_unit="deg/s2",
        ),
    )

    #: step() only advances t (the commands are functions of time only)
    STATELESS = True

    def initialize(self, t0):
        p = self.p
        self.roll = roll = SweepAxis(p.roll_amplitude, p.roll_rate, p.turnaround_time, "roll")
        self.pitch = pitch = SweepAxis(p.pitch_amplitude, p.pitch_rate, p.turnaround_time, "pitch")
        self.state = state = S.zeros()
        state[S.roll : S.roll + 4] = roll.amplitude, roll.rate, roll.turnaround, roll.period
        state[S.pitch : S.pitch + 4] = pitch.amplitude, pitch.rate, pitch.turnaround, pitch.period
        state[S.sign2] = -1.0 if p.symmetric else 1.0
        self.t = t0

    def step(self, t, dt):
        self.t = t + dt

    def output(self):
        sweep_output(self.values, self.state, self.t)


# -- kernel (components/runtime/jit.py) -----------------------------------------------
P, U, Y = SweepPlanner.names()
#: the state array: each axis's (A, r, τ, P), and the sign of payload 2 (−1: symmetric)
S = state_table("SweepPlanner state", roll=4, pitch=4, sign2=1)


@output_kernel(SweepPlanner)
def sweep_output(values, state, t):
    """Both payloads' commands at time t: payload 2 = sign2 × payload 1."""
    s = floats(state)
    roll, roll_rate, roll_accel = sweep_at(
        s[S.roll], s[S.roll + 1], s[S.roll + 2], s[S.roll + 3], t
    )
    pitch, pitch_rate, pitch_accel = sweep_at(
        s[S.pitch], s[S.pitch + 1], s[S.pitch + 2], s[S.pitch + 3], t
    )
    k = s[S.sign2]
    values[Y.roll_cmd], values[Y.roll_cmd + 1] = roll, k * roll
    values[Y.pitch_cmd], values[Y.pitch_cmd + 1] = pitch, k * pitch
    values[Y.roll_rate_cmd], values[Y.roll_rate_cmd + 1] = roll_rate, k * roll_rate
    values[Y.pitch_rate_cmd], values[Y.pitch_rate_cmd + 1] = pitch_rate, k * pitch_rate
    values[Y.roll_accel_cmd], values[Y.roll_accel_cmd + 1] = roll_accel, k * roll_accel
    values[Y.pitch_accel_cmd], values[Y.pitch_accel_cmd + 1] = pitch_accel, k * pitch_accel
    return 0
