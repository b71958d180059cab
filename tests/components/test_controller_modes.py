"""AttitudeController's modes (DESIGN.md §3.2): a gain row per mode, the integral term with
its anti-windup limit, and bumpless switching, against closed forms — the integral's ramp
and clamp under a constant error, the transfer term's exponential decay, and the steady
state of a rigid body under a constant disturbance torque (PD: θ = τ_d/kp; PID: zero)."""

import math

import numpy as np
import pytest

from agilesat.components.attitude_controller import KD, KP, N_MODES, AttitudeController
from agilesat.components.model import ModelError
from agilesat.components.satellite_dynamics import SatelliteDynamics

ERROR = 0.02  # rad about x: the attitude error of the tests' constant errors
Q_ERROR = (math.cos(ERROR / 2), math.sin(ERROR / 2), 0.0, 0.0)


def table(rows: dict, default=(KP, KD, 0.0)) -> dict:
    """kp_modes, kd_modes, ki_modes with ``rows`` {mode: (kp, kd, ki)} given, the others at
    the tables' start values (not given)."""
    gains = [rows.get(m, default) for m in range(N_MODES)]
    return {name: [[g[i]] * 3 for g in gains] for i, name in enumerate(_TABLES)}


_TABLES = ("kp_modes", "kd_modes", "ki_modes")


def held(controller, times, modes, w=(0.0, 0.0, 0.0)):
    """tau_cmd[0] at each time with the error held at ERROR, the mode of each time set at
    that time (as a host sets inputs after reading the outputs and before stepping: the
    output at the time is read again with it)."""
    controller.set("q_BI", Q_ERROR)
    controller.set("w_BI_B", w)
    out = []
    for k, (t, mode) in enumerate(zip(times, modes)):
        if k == 0:
            controller.set("mode", mode)
            controller.start(t)
        else:
            controller.advance(times[k - 1], t - times[k - 1])
            controller.set("mode", mode)
            controller.output()
        out.append(float(controller.get("tau_cmd")[0]))
    return np.array(out)


def test_without_a_table_every_mode_runs_kp_and_kd():
    reference = AttitudeController(kp=[3.0] * 3, kd=[30.0] * 3)
    taus = {m: held(AttitudeController(kp=[3.0] * 3, kd=[30.0] * 3), [0.0], [m])[0] for m in (0, 5)}
    assert taus[0] == taus[5] == held(reference, [0.0], [0])[0] == -3.0 * ERROR


def test_each_mode_runs_its_row_and_a_row_not_given_runs_kp_and_kd():
    gains = table({2: (20.0, 100.0, 0.0)})
    for mode, kp in ((2, 20.0), (0, 3.0), (7, 3.0)):
        c = AttitudeController(kp=[3.0] * 3, kd=[30.0] * 3, **gains)
        w = (1e-3, 0.0, 0.0)
        kd = 100.0 if mode == 2 else 30.0
        assert held(c, [0.0], [mode], w)[0] == pytest.approx(-kp * ERROR - kd * 1e-3, rel=1e-12)


def test_the_integral_ramps_at_ki_times_the_error_and_stops_at_its_limit():
    """u̇_I = ki e under a constant error: u_I = ki e t (the step's forward sum is exact for
    a constant), clamped at integral_limit."""
    ki, limit, dt = 0.5, 0.004, 0.1
    c = AttitudeController(**table({1: (KP, KD, ki)}), integral_limit=[limit] * 3)
    times = np.arange(60) * dt
    tau = held(c, times, [1] * 60)
    integral = -(tau - tau[0])  # tau = PD − u_I with the PD constant
    expected = np.minimum(ki * ERROR * times, limit)
    assert integral == pytest.approx(expected, abs=1e-15)  # clamped: 0.004 N·m at 0.4 s


def test_anti_windup_the_integral_leaves_its_limit_as_soon_as_the_error_turns():
    ki, limit, dt = 0.5, 0.004, 0.1
    c = AttitudeController(**table({1: (KP, KD, ki)}), integral_limit=[limit] * 3)
    held(c, np.arange(100) * dt, [1] * 100)  # 10 s at the limit: far beyond 0.4 s of ramp
    c.set("q_BI", (Q_ERROR[0], -Q_ERROR[1], 0.0, 0.0))  # the error reverses at t = 10 s
    u = []
    for k in range(4):
        c.advance(9.9 + k * dt, dt)
        pd = -KP * -ERROR
        u.append(pd - float(c.get("tau_cmd")[0]))
    assert np.diff(u) == pytest.approx([-ki * ERROR * dt] * 3, rel=1e-9)  # at once
    assert u[0] == pytest.approx(limit - ki * ERROR * dt, rel=1e-9)


def test_a_switch_is_bumpless_and_the_transfer_decays_with_transfer_time():
    """Switching from mode 0 (kp = 6) to mode 2 (kp = 20, no integral) with the error held:
    the command does not jump at the switch, then relaxes to the new PD as
    e^(−t/transfer_time)."""
    transfer, dt = 5.0, 0.5
    c = AttitudeController(**table({2: (20.0, KD, 0.0)}), transfer_time=transfer)
    times = np.arange(40) * dt
    modes = [0] * 10 + [2] * 30
    tau = held(c, times, modes)
    assert tau[10] == pytest.approx(tau[9], abs=1e-15)  # mode 0's command, the error held
    after = times[10:] - times[10]
    new, old = -20.0 * ERROR, -KP * ERROR
    assert tau[10:] == pytest.approx(new + (old - new) * np.exp(-after / transfer), rel=1e-12)


def test_switching_into_an_integrating_mode_keeps_the_integral_and_transfers_the_jump():
    """Into a mode with integral action: continuous; the integral ramps at ki e from where
    it was (zero here) and the jump decays with transfer_time."""
    ki, dt, transfer = 0.2, 0.5, 1.0
    c = AttitudeController(**table({3: (20.0, KD, ki)}), integral_limit=[1.0] * 3)
    tau = held(c, np.arange(20) * dt, [0] * 10 + [3] * 10)
    assert tau[10] == pytest.approx(tau[9], abs=1e-15)  # the error and the time as before
    after = np.arange(10) * dt
    new, old = -20.0 * ERROR, -KP * ERROR
    expected = new - ki * ERROR * after + (old - new) * np.exp(-after / transfer)
    assert tau[10:] == pytest.approx(expected, rel=1e-12)


def test_a_constant_disturbance_leaves_tau_over_kp_with_pd_and_nothing_with_pid():
    """One axis of a rigid body (SatelliteDynamics) under a constant disturbance τ_d: PD
    settles at θ = τ_d/kp; PID at zero (the integral takes τ_d)."""
    J, tau_d, dt = 150.0, 2e-3, 0.5
    for ki, expected in ((0.0, tau_d / KP), (0.5, 0.0)):
        body = SatelliteDynamics(inertia=J * np.eye(3), gravity_gradient=False).start(0.0)
        ctrl = AttitudeController(**table({1: (KP, KD, ki)}), integral_limit=[0.01] * 3)
        ctrl.set("mode", 1)
        for k in range(800):
            ctrl.set("q_BI", body.get("q_BI"))
            ctrl.set("w_BI_B", body.get("w_BI_B"))
            ctrl.start(0.0) if k == 0 else ctrl.output()
            body.set("tau_ext", ctrl.get("tau_cmd") + [tau_d, 0.0, 0.0])
            body.advance(k * dt, dt)
            ctrl.step(k * dt, dt)
        ctrl.set("q_BI", body.get("q_BI"))
        ctrl.output()
        assert ctrl.get("att_error")[0] == pytest.approx(expected, abs=1e-7)


@pytest.mark.parametrize("mode", [-1, N_MODES])
def test_a_mode_without_a_row_is_refused(mode):
    c = AttitudeController()
    c.set("mode", mode)
    with pytest.raises(ModelError, match=f"mode {mode} has no row in the gain tables"):
        c.start(0.0)


def test_bad_limits_are_named():
    with pytest.raises(ModelError, match="integral_limit must be >= 0 and transfer_time > 0"):
        AttitudeController(transfer_time=0.0).start(0.0)
