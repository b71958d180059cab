"""Parameter values two FMUs of a scenario must share, each produced once here (the rules
and the validator's check of any system are in :mod:`..agreement`)."""

from __future__ import annotations

import numpy as np


def cmg_hardware(**values) -> dict:
    """The cluster's ``h_rotor``, ``gimbal_axis``, ``spin_ref`` (those given) for both the
    CmgCluster and the CmgSteering that steers it."""
    unknown = set(values) - {"h_rotor", "gimbal_axis", "spin_ref"}
    if unknown:
        raise ValueError(f"not CMG hardware parameters: {sorted(unknown)}")
    return {
        f"{fmu}.{name}": value
        for fmu in ("CmgCluster", "CmgSteering")
        for name, value in values.items()
    }


def hub_inertia(inertia, *controllers: str) -> dict:
    """SatelliteDynamics' inertia and the same inertia for the ``controllers`` whose
    feedforward uses it: AttitudeController (the matrix), PitchManeuverController (its
    pitch-axis element)."""
    inertia = np.asarray(inertia, dtype=float)
    values = {"SatelliteDynamics.inertia": inertia}
    for controller in controllers:
        if controller == "AttitudeController":
            values["AttitudeController.inertia"] = inertia
        elif controller == "PitchManeuverController":
            values["PitchManeuverController.inertia"] = float(inertia[1, 1])
        else:
            raise ValueError(f"{controller} takes no hub inertia")
    return values
