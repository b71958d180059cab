"""Thin pythonfmu wrappers, one per component, and the build step that packs them.

``FMUS`` maps each FMU name (= modelIdentifier = class name) to the module in this
package that holds its slave class.  Nothing here imports pythonfmu at import time.
"""
FMUS = {
    "OrbitEnvironment": "orbit_environment",
    "SatelliteDynamics": "satellite_dynamics",
    "CmgCluster": "cmg_cluster",
    "CmgSteering": "cmg_steering",
    "PitchManeuverController": "pitch_maneuver_controller",
    "PayloadGimbals": "payload_gimbals",
    "SweepPlanner": "sweep_planner",
    "Flywheel": "flywheel",
    "AttitudeController": "attitude_controller",
    "StaringGuidance": "staring_guidance",
}


def slave_class(name: str):
    """The pythonfmu slave class of the FMU ``name`` (a :class:`.slave.ModelSlave`)."""
    import importlib
    if name not in FMUS:
        raise KeyError(f"unknown FMU {name!r}; FMUs: {', '.join(FMUS)}")
    return getattr(importlib.import_module(f"{__name__}.{FMUS[name]}"), name)


def model_class(name: str):
    """The component model class (``components``) of the FMU ``name``."""
    return slave_class(name).model_class
