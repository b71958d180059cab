"""Parameters two FMUs must share (orchestration/system/agreement.py), checked on the shipped
systems: they agree, and a system file that breaks one is refused naming file and line."""

import dataclasses
import re

import pytest

from agilesat.orchestration.scenarios import NAMES, get
from agilesat.orchestration.system.agreement import disagreements
from agilesat.orchestration.system.description import Description
from agilesat.orchestration.system.parameters import typed_parameters
from agilesat.orchestration.system.ssp import ParameterValue, SystemFileError, read_system
from agilesat.orchestration.system.validation import check_system

_SYSTEMS: dict = {}


def system(name, fmus):
    """(the shipped system file, its FMUs' descriptions), read once per session."""
    if name not in _SYSTEMS:
        ssd = read_system(get(name).ssd)
        _SYSTEMS[name] = ssd, {c.name: Description(c.name, fmus[c.name]) for c in ssd.components}
    return _SYSTEMS[name]


def sources_of(ssd):
    return {
        (c.end_element, c.end_connector): (c.start_element, c.start_connector)
        for c in ssd.connections
    }


def changed(bindings, component, name, value):
    """The bindings with one system-file value replaced (origin kept) or added."""
    if not any((p.component, p.name) == (component, name) for p in bindings):
        return [*bindings, ParameterValue(component, name, "Real", value, "edited.ssd:7")]
    return [
        dataclasses.replace(p, value=value) if (p.component, p.name) == (component, name) else p
        for p in bindings
    ]


@pytest.mark.parametrize("scenario", NAMES)
def test_the_shipped_systems_agree(scenario, fmus):
    ssd, instances = system(scenario, fmus)
    assert disagreements(instances, ssd.parameters, sources_of(ssd)) == []


@pytest.mark.parametrize(
    "component, name, value, message",
    [
        ("CmgSteering", "h_rotor", 20.0, "CmgSteering.h_rotor must equal CmgCluster.h_rotor"),
        (
            "CmgSteering",
            "spin_ref[2,3]",
            0.5,
            "CmgSteering.spin_ref must equal CmgCluster.spin_ref",
        ),
        (
            "PitchManeuverController",
            "inertia",
            900.0,
            "PitchManeuverController.inertia must equal SatelliteDynamics.inertia[2,2]",
        ),
    ],
)
def test_a_system_file_that_breaks_an_agreement_is_refused(fmus, component, name, value, message):
    ssd, instances = system("scan_pitch", fmus)
    bindings = changed(ssd.parameters, component, name, value)
    line = next(p.origin for p in bindings if (p.component, p.name) == (component, name))
    with pytest.raises(SystemFileError, match=re.escape(message)) as refused:
        check_system(ssd, instances, bindings)
    assert f"{line}: {component}." in str(refused.value)


def test_the_feedforward_inertia_is_the_satellites_when_the_feedforward_is_on(fmus):
    ssd, instances = system("video_sar", fmus)
    sources = sources_of(ssd)
    wrong = changed(ssd.parameters, "AttitudeController", "inertia[3,3]", 1000.0)
    off = changed(wrong, "AttitudeController", "acceleration_feedforward", False)
    assert disagreements(instances, off, sources) == []  # not used
    [problem] = disagreements(instances, wrong, sources)
    assert "AttitudeController.inertia must equal SatelliteDynamics.inertia" in problem
    assert "AttitudeController.inertia[3,3] = 1000.0" in problem


def test_a_value_given_at_run_time_is_the_users_choice(fmus):
    """A robustness study: the satellite's inertia changed, the controller's model not."""
    ssd, instances = system("scan_pitch", fmus)
    given = typed_parameters(instances, {"SatelliteDynamics.inertia[2,2]": 900.0})
    bindings = ssd.parameters + list(given.values())
    assert disagreements(instances, bindings, sources_of(ssd)) == []
