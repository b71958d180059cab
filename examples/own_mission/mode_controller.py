"""Detumble, then point: an attitude controller of your own, on agilesat's model API.

``agilesat build mode_controller.py`` makes it the FMU ``build/ModeController.fmu`` (model
description from the variable table below, validated); ``mission.py`` names this file and
builds it when it is missing or stale.

Mode 1, DETUMBLE: rate damping on the measured rate ω̃, τ = −k ω̃.  It hands over to mode 2
once |ω̃| < ``rate_threshold`` has held for ``dwell`` seconds (the modes change at the
communication points: the controller runs at the master's step).

Mode 2, POINT: a rate-limited quaternion PD towards the target attitude q_TI, with e the
rotation vector of q_BT = q_TI* ⊗ q_BI (the shorter way round)::

    ω_c = −(k_p / k_d) e,  scaled down to |ω_c| ≤ slew_rate,      τ = −k_d (ω̃ − ω_c)

a slew at the rate limit that turns into a critically damped PD near the target.

The measured rate is ω̃ = ω + σ n_k, white noise of σ = ``gyro_noise`` per axis (a rate
gyro's angle random walk seen at the controller's sample period).  The noise is the
pattern every stochastic model follows: n_k comes from ``agilesat.components.noise``, a pure
function of (seed, stream, index), index = 3 k + axis with k the sample count.  So a run is
reproducible from the Integer ``seed`` alone, a campaign disperses it by ``--vary
Controller.seed=values(...)``, and an FMU state, which holds k, continues the same noise
bit for bit after a restore: nothing of a generator object needs saving.
"""

import math

import numpy as np

from agilesat.components.model import Model, ModelError
from agilesat.components.noise import normal, stream_key
from agilesat.components.rotations import qmul
from agilesat.components.variables import input_, output, parameter

DETUMBLE, POINT = 1, 2
DEG = math.pi / 180


class ModeController(Model):
    """Detumble by rate damping, then a rate-limited slew to a target attitude."""

    VARIABLES = (
        parameter("detumble_gain", 1.0, "N.m.s/rad", "rate damping gain k in mode 1"),
        parameter(
            "rate_threshold",
            0.05 * DEG,
            "rad/s",
            "|measured rate| below which the detumble is done",
            display_unit="deg/s",
        ),
        parameter("dwell", 5.0, "s", "how long the rate must stay below the threshold"),
        parameter(
            "q_target",
            (0.5, 0.5, 0.5, 0.5),
            "1",
            "target attitude q_TI of mode 2 (unit quaternion, scalar first)",
            shape=(4,),
        ),
        parameter("kp", 0.56, "N.m/rad", "attitude gain k_p of mode 2"),
        parameter("kd", 5.6, "N.m.s/rad", "rate gain k_d of mode 2"),
        parameter(
            "slew_rate", 2.0 * DEG, "rad/s", "largest commanded slew rate", display_unit="deg/s"
        ),
        parameter(
            "gyro_noise",
            0.001 * DEG,
            "rad/s",
            "1-sigma white noise of the measured rate, per axis (0: none)",
            display_unit="deg/s",
        ),
        parameter(
            "seed", 1, "1", "seed of the rate noise (agilesat.components.noise)", type="Integer"
        ),
        input_("q_BI", "1", "attitude of B relative to I", (1.0, 0.0, 0.0, 0.0), shape=(4,)),
        input_(
            "w_BI_B",
            "rad/s",
            "angular velocity of B relative to I, in B",
            shape=(3,),
            display_unit="deg/s",
        ),
        output(
            "tau_cmd",
            "N.m",
            "torque wanted on the body, in B",
            shape=(3,),
            depends=("q_BI", "w_BI_B"),
        ),
        output("mode", "1", "1 = DETUMBLE, 2 = POINT", type="Integer"),
        output(
            "att_error",
            "rad",
            "rotation vector of B relative to the target, in B",
            shape=(3,),
            depends=("q_BI",),
            display_unit="deg",
        ),
        output("q_ref", "1", "the target attitude q_TI (for the pointing error)", shape=(4,)),
        output(
            "w_meas",
            "rad/s",
            "the measured rate ω̃, in B",
            shape=(3,),
            depends=("w_BI_B",),
            display_unit="deg/s",
        ),
    )

    def initialize(self, t0):
        p = self.p
        q = p.q_target
        if not abs(float(np.dot(q, q)) - 1.0) < 1e-9:
            raise ModelError(f"q_target must be a unit quaternion, got {q.tolist()}")
        for name in ("detumble_gain", "kp", "kd", "slew_rate", "dwell"):
            if not getattr(p, name) > 0.0:
                raise ModelError(f"{name} must be > 0, got {getattr(p, name)}")
        if not p.gyro_noise >= 0.0:
            raise ModelError(f"gyro_noise must be >= 0, got {p.gyro_noise}")
        self.t = t0
        self.mode = DETUMBLE
        self.below_since = None  # time the rate went below the threshold
        self.k = 0  # the sample count: the noise index
        self.key = stream_key(int(p.seed), 0)

    def measured(self) -> tuple:
        """ω̃ at sample k."""
        sigma = float(self.p.gyro_noise)
        return tuple(
            w + sigma * normal(self.key, 3 * self.k + i)
            for i, w in enumerate(self.u.w_BI_B.tolist())
        )

    def step(self, t, dt):
        if self.mode == DETUMBLE:
            w = self.measured()
            if math.sqrt(sum(x * x for x in w)) < self.p.rate_threshold:
                self.below_since = t if self.below_since is None else self.below_since
                if t + dt - self.below_since >= self.p.dwell - 1e-9:
                    self.mode = POINT
            else:
                self.below_since = None
        self.k += 1
        self.t = t + dt

    def output(self):
        p, u, y = self.p, self.u, self.y
        w = self.measured()
        t0, t1, t2, t3 = p.q_target.tolist()
        q0, q1, q2, q3 = qmul((t0, -t1, -t2, -t3), u.q_BI.tolist())  # q_BT
        if q0 < 0.0:
            q0, q1, q2, q3 = -q0, -q1, -q2, -q3
        s = math.sqrt(q1 * q1 + q2 * q2 + q3 * q3)
        f = 2.0 * math.atan2(s, q0) / s if s > 0.0 else 2.0
        e = (f * q1, f * q2, f * q3)
        if self.mode == DETUMBLE:
            tau = [-p.detumble_gain * x for x in w]
        else:
            wc = [-p.kp / p.kd * x for x in e]
            size = math.sqrt(sum(x * x for x in wc))
            if size > p.slew_rate:
                wc = [x * p.slew_rate / size for x in wc]
            tau = [-p.kd * (a - b) for a, b in zip(w, wc)]
        y.tau_cmd[:] = tau
        y.mode = self.mode
        y.att_error[:] = e
        y.q_ref[:] = p.q_target
        y.w_meas[:] = w
