"""Faults on a timeline (DESIGN.md §3.2), each against what the physics says it does: a
locked gimbal holds the angle it reached at its fail time (the servo's closed form up to
then); the steering law delivers the wanted torque with the five free gimbals; a failed
wheel coasts down as J Ω̇ = −c_v Ω − c_c; a wheel whose friction rises loses torque by what
the drive does not know about; a blinded star tracker's samples are invalid over the
outage; a gyro's bias steps by the given amount, averaged over the sample it falls in."""

import math

import numpy as np
import pytest

from agilesat.components.cmg_cluster import (
    DEFAULT_SPINS,
    GIMBAL_AXES,
    ClusterGeometry,
    CmgCluster,
)
from agilesat.components.cmg_steering import SR_INVERSE, CmgSteering
from agilesat.components.flywheel import HR12_COULOMB, HR12_INERTIA, VISCOUS, Flywheel
from agilesat.components.gyro import Gyro
from agilesat.components.model import ModelError
from agilesat.components.star_tracker import StarTracker

INF = math.inf
H = 16.65


def test_a_gimbal_locks_at_the_angle_it_reached_at_its_fail_time():
    """Gimbal 2 commanded at 0.1 rad/s from rest (0.5 rad/s² accel limit) locks at 0.25 s:
    δ = δ0 + a t²/2 up to 0.2 s, then + 0.1 (t − 0.2), held from 0.25 s; the others go on."""
    fail = [INF, 0.25, INF, INF, INF, INF]
    cluster = CmgCluster(fail_time=fail, delta_dot_cmd=[0.1] * 6).start(0.0)
    delta0 = cluster.get("delta").copy()
    for k in range(6):
        cluster.advance(0.1 * k, 0.1)
    locked = delta0[1] + 0.5 * 0.5 * 0.2**2 + 0.1 * 0.05
    assert cluster.get("delta")[1] == pytest.approx(locked, abs=1e-15)
    assert cluster.get("delta_dot")[1] == 0.0
    free = delta0[0] + 0.5 * 0.5 * 0.2**2 + 0.1 * 0.4
    assert cluster.get("delta")[0] == pytest.approx(free, abs=1e-15)
    assert cluster.get("healthy").tolist() == [1, 0, 1, 1, 1, 1]
    geometry = ClusterGeometry(H, GIMBAL_AXES, DEFAULT_SPINS)
    A = np.delete(geometry.jacobian(cluster.get("delta")), 1, axis=1)
    assert cluster.get("singularity") == pytest.approx(np.linalg.det(A @ A.T), rel=1e-12)


@pytest.mark.parametrize("law", [0, SR_INVERSE])
@pytest.mark.parametrize("locked", range(6))
def test_the_steering_steers_the_free_gimbals(law, locked):
    """δ̇ = A_hᵀ (A_h A_hᵀ + λ 1)⁻¹ ḣ / h_rotor over the free gimbals' columns A_h, zero for
    the locked one (ḣ = −τ_cmd − w × h; pseudo-inverse: λ = 0, the torque delivered
    exactly; SR inverse: λ = λ0 e^(−μ Q_h)), Q_h = det(A_h A_hᵀ)."""
    healthy = [i != locked for i in range(6)]
    tau, w = np.array([1.0, 0.5, -0.3]), np.array([0.01, -0.02, 0.005])
    steering = CmgSteering(law=law, tau_cmd=tau, w_BI_B=w, healthy=healthy).start(0.0)
    rates = steering.get("delta_dot_cmd")
    geometry = ClusterGeometry(H, GIMBAL_AXES, DEFAULT_SPINS)
    A = geometry.jacobian(steering.u.delta)
    A_h = np.delete(A, locked, axis=1)
    Q = np.linalg.det(A_h @ A_h.T)
    wanted = -tau - np.cross(w, steering.u.h)
    lam = 0.01 * math.exp(-10.0 * Q) if law == SR_INVERSE else 0.0
    expected = A_h.T @ np.linalg.solve(A_h @ A_h.T + lam * np.eye(3), wanted) / H
    assert rates[locked] == 0.0
    assert np.delete(rates, locked) == pytest.approx(expected, rel=1e-10, abs=1e-15)
    assert steering.get("singularity") == pytest.approx(Q, rel=1e-12)
    if law != SR_INVERSE:
        assert H * A @ rates == pytest.approx(wanted, rel=1e-12)


def test_a_failed_wheel_coasts_down_on_its_friction():
    """J Ω̇ = −c_v Ω − c_c from the fail time: Ω(t) = (Ω0 + c_c/c_v) e^(−c_v t/J) − c_c/c_v;
    its motor torque reads zero, the other wheels are untouched."""
    omega0, dt = 300.0, 0.5
    wheels = Flywheel(speed0=[omega0, omega0, 0.0, 0.0], fail_time=[1.0, INF, INF, INF])
    wheels.start(0.0)
    for k in range(40):
        wheels.advance(k * dt, dt)
    k_v, offset = VISCOUS / HR12_INERTIA, HR12_COULOMB / VISCOUS
    expected = (omega0 + offset) * math.exp(-k_v * (20.0 - 1.0)) - offset
    assert wheels.get("speed")[0] == pytest.approx(expected, rel=1e-12)
    assert wheels.get("motor_torque")[0] == 0.0
    assert wheels.get("speed")[1] == omega0  # driven: friction compensated


def test_more_friction_than_the_drive_knows_is_a_torque_not_delivered():
    """From the change, friction × 4 while the drive compensates the nominal: the wheel
    decelerates at 3 (c_v Ω + c_c)/J at first."""
    omega0 = 300.0
    wheels = Flywheel(speed0=[omega0, 0.0, 0.0, 0.0], friction_factor=[4.0, 1.0, 1.0, 1.0],
                      friction_change_time=[2.0, INF, INF, INF]).start(0.0)  # fmt: skip
    for k in range(2):
        wheels.advance(k * 1.0, 1.0)
    assert wheels.get("speed")[0] == omega0  # before the change
    wheels.advance(2.0, 1e-3)
    deficit = 3 * (VISCOUS * omega0 + HR12_COULOMB) / HR12_INERTIA
    assert (omega0 - wheels.get("speed")[0]) / 1e-3 == pytest.approx(deficit, rel=1e-3)


def test_an_outage_makes_the_star_tracker_samples_of_its_window_invalid():
    tracker = StarTracker(outage_start=1.0, outage_stop=2.5, latency=0.0, rate=4.0).start(0.0)
    seen = {}
    for k in range(16):
        tracker.advance(0.25 * k, 0.25)
        seen[float(tracker.get("t_meas"))] = bool(tracker.get("valid"))
    assert {t for t, valid in seen.items() if not valid} == {1.0, 1.25, 1.5, 1.75, 2.0, 2.25}
    with pytest.raises(ModelError, match="outage_start must not be after outage_stop"):
        StarTracker(outage_start=3.0, outage_stop=2.0).start(0.0)


def test_a_gyro_bias_step_shifts_the_rate_by_the_step_averaged_over_its_sample():
    """A noiseless gyro at rest (rate 20 Hz: samples every 0.05 s) with a 1e-3 rad/s step on
    x at 0.105 s: the sample of (0.1, 0.15] reads 0.9e-3, the later ones 1e-3; bias_B too."""
    exact = dict(arw=0.0, rrw=0.0, bias_instability=0.0, bias0=[0.0] * 3, quantization=0.0,
                 scale_factor=[0.0] * 3, misalignment=np.zeros((3, 3)), rate=20.0)  # fmt: skip
    gyro = Gyro(**exact, bias_step_time=0.105, bias_step=[1e-3, 0.0, 0.0]).start(0.0)
    readings = {}
    for k in range(10):
        gyro.advance(0.05 * k, 0.05)
        readings[round(gyro.t, 3)] = (gyro.get("w_meas_B")[0], gyro.get("bias_B")[0])
    assert readings[0.1] == (0.0, 0.0)
    assert readings[0.15][0] == pytest.approx(0.9e-3, rel=1e-12)
    assert readings[0.15][1] == 1e-3 and readings[0.3] == (1e-3, 1e-3)


def test_a_fault_time_is_a_time_or_inf():
    with pytest.raises(ModelError, match="fail_time must be a time or inf"):
        CmgCluster(fail_time=[math.nan] + [INF] * 5).start(0.0)
    with pytest.raises(ModelError, match="friction_factor must be >= 0"):
        Flywheel(friction_factor=[-1.0, 1.0, 1.0, 1.0]).start(0.0)
