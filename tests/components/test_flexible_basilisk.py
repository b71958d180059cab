"""Basilisk beside our hub (its runs recorded by tests/tools/reference/basilisk_flexible.py):
a hinged panel (hingedRigidBodyStateEffector) against one hybrid-coordinate mode of
SatelliteDynamics, and a wheel's imbalance (reactionWheelStateEffector, JitterSimple and
JitterFullyCoupled) against the Flywheel's jitter row in the hub."""

import json
import math

import numpy as np
import pytest

from agilesat.components.flywheel import Flywheel
from agilesat.components.satellite_dynamics import N_MODES, SatelliteDynamics
from helpers import TOOLS
from reference import basilisk_flexible as case

BASILISK = json.loads((TOOLS / "reference" / "basilisk_flexible.json").read_text())
DT = BASILISK["sample"]


def zero_crossing_frequency(t, x) -> float:
    x = x - x.mean()
    k = np.flatnonzero(np.sign(x[:-1]) * np.sign(x[1:]) < 0)
    crossings = t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])
    return math.pi / np.mean(np.diff(crossings))


def panel_run(damper: float) -> tuple[np.ndarray, np.ndarray]:
    """(w_BI_B, θ) of our hub with the panel as its one mode, every DT."""
    mode = case.panel_mode(damper)

    def first(value, shape=()):
        table = np.zeros((N_MODES, *shape))
        table[0] = value
        return table

    hub = SatelliteDynamics(
        inertia=mode["inertia"],
        gravity_gradient=False,
        modal_frequency=first(mode["frequency"]),
        modal_damping=first(mode["damping"]),
        modal_coupling=first(mode["coupling"], (3,)),
        eta0=first(mode["eta0"]),
    ).start()
    w, theta = [hub.get("w_BI_B")], [hub.get("eta")[0] / mode["sqrt_I_h"]]
    for k in range(round(case.PANEL["stop"] / DT)):
        hub.advance(k * DT, DT)
        w.append(hub.get("w_BI_B"))
        theta.append(hub.get("eta")[0] / mode["sqrt_I_h"])
    return np.array(w), np.array(theta)


@pytest.mark.parametrize("variant", case.DAMPER)
def test_a_hinged_panel_is_a_mode_of_the_hub(variant):
    """Released at 0.01 rad: both oscillate at ω_c / √(1 − L J⁻¹ Lᵀ) to 1e-3, and the body
    rate and the panel angle agree to 1 % of their amplitudes over 20 s (Basilisk's panel
    is the nonlinear rigid body, ours the linear mode: O(θ₀) apart)."""
    mode = case.panel_mode(case.DAMPER[variant])
    L, inertia = mode["coupling"], mode["inertia"]
    closed_form = mode["frequency"] / math.sqrt(1.0 - L @ np.linalg.solve(inertia, L))
    theirs = BASILISK["panel"][variant]
    w_b, theta_b = np.array(theirs["w_BI_B"]), np.array(theirs["theta"])
    w, theta = panel_run(case.DAMPER[variant])
    t = np.arange(len(theta)) * DT
    measured = zero_crossing_frequency(t, theta_b), zero_crossing_frequency(t, theta)
    dw = np.abs(w - w_b).max() / np.abs(w_b).max()
    dtheta = np.abs(theta - theta_b).max() / case.PANEL["theta0"]
    print(
        f"panel ({variant}): ω_u closed form {closed_form:.5f}, Basilisk {measured[0]:.5f}, "
        f"ours {measured[1]:.5f} rad/s; rates apart by {dw:.2%}, angles by {dtheta:.2%} of θ₀"
    )
    assert measured == pytest.approx((closed_form, closed_form), rel=1e-3)
    assert dw < 0.01 and dtheta < 0.01


def wheel_run() -> np.ndarray:
    """w_BI_B every DT of our hub with the Flywheel's wheel: its h into h_wheel, its jitter
    row into h_extra[1] at its speed (the hub's steady response); the body at rest at t = 0
    (rate0 = the mean rate M⁻¹ h_u(0) that leaves it so)."""
    w = case.WHEEL
    wheel = Flywheel(
        axis=[w["axis"], [0.0] * 3, [0.0] * 3, [0.0] * 3],
        J_wheel=w["J_s"],
        torque_limit=0.0,
        viscous_friction=0.0,
        coulomb_friction=0.0,
        speed0=[w["speed"], 0.0, 0.0, 0.0],
        static_imbalance=[w["static"], 0.0, 0.0, 0.0],
        dynamic_imbalance=[w["dynamic"], 0.0, 0.0, 0.0],
        rotor_position_B=[w["position"], [0.0] * 3, [0.0] * 3, [0.0] * 3],
    ).start()
    hub = SatelliteDynamics(inertia=case.HUB_INERTIA, gravity_gradient=False)

    def connect():
        hub.set("h_wheel", wheel.get("h"))
        hub.set("hdot_wheel", wheel.get("hdot"))
        hub.u.h_extra[0], hub.u.hdot_extra[0] = wheel.y.h_jitter_B[0], wheel.y.hdot_jitter_B[0]
        hub.u.h_extra_frequency[0] = wheel.y.speed[0]
        wheel.set("w_BI_B", hub.get("w_BI_B"))

    connect()
    hub.set("rate0", np.linalg.solve(case.HUB_INERTIA, wheel.y.h_jitter_B[0]))
    hub.start()
    rates = [hub.get("w_BI_B")]
    for k in range(round(w["stop"] / DT)):
        hub.step(k * DT, DT)
        wheel.step(k * DT, DT)
        wheel.output()
        connect()
        hub.output()
        rates.append(hub.get("w_BI_B"))
    return np.array(rates)


def test_a_wheels_imbalance_shakes_the_hub_as_basilisks_jitter():
    """Sampled every 0.05 s, ours stepped at 0.05 s (the jitter the hub's steady response),
    Basilisk at 1e-4 s: the body rate agrees to 1e-3 of the jitter's amplitude with
    JitterSimple (the same model) and to 1 % with JitterFullyCoupled (which adds the wheel's
    imbalance to its mass and inertia)."""
    ours = wheel_run()
    for model, name, bound in (
        ("simple", "JitterSimple", 1e-3),
        ("coupled", "JitterFullyCoupled", 1e-2),
    ):
        theirs = np.array(BASILISK["wheel"][model]["w_BI_B"])
        apart = np.abs(ours - theirs).max() / np.abs(theirs).max()
        print(f"wheel, Basilisk's {name}: rates apart by {apart:.1e} of "
              f"the jitter's amplitude {np.abs(theirs).max():.3e} rad/s")  # fmt: skip
        assert apart < bound
