"""Build the user's FMU and write a detumbling system with two of agilesat's FMUs:

    SatelliteDynamics.w_BI_B -> RateDamper.w_BI_B          (the user's FMU)
    RateDamper.tau_cmd       -> Flywheel.tau_cmd
    SatelliteDynamics.w_BI_B -> Flywheel.w_BI_B
    Flywheel.h, Flywheel.hdot -> SatelliteDynamics.h_wheel, hdot_wheel

A 50 kg·m² satellite tumbling at about 1.5 °/s, gain 5 N·m·s/rad (time constant J/gain =
10 s), 100 s at 0.05 s.  Usage: python make_system.py [OUT_DIR]  (default: out/own_system).
"""

import os
import subprocess
import sys
from pathlib import Path

from agilesat.fmus.build import build_fmu

HERE = Path(__file__).resolve().parent
OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "out/own_system").resolve()
OUT.mkdir(parents=True, exist_ok=True)

# 1. the user's FMU (pythonfmu's command line), and ours
subprocess.run(
    [
        sys.executable,
        "-m",
        "pythonfmu",
        "build",
        "-f",
        str(HERE / "rate_damper.py"),
        "-d",
        str(OUT),
    ],
    check=True,
    capture_output=True,
)
sources = {
    "SatelliteDynamics": build_fmu("SatelliteDynamics"),
    "Flywheel": build_fmu("Flywheel"),
    "RateDamper": OUT / "RateDamper.fmu",
}

# 2. the system: whole vectors, written element by element as SSP wants them
WIRES = [
    ("SatelliteDynamics.w_BI_B", "RateDamper.w_BI_B"),
    ("RateDamper.tau_cmd", "Flywheel.tau_cmd"),
    ("SatelliteDynamics.w_BI_B", "Flywheel.w_BI_B"),
    ("Flywheel.h", "SatelliteDynamics.h_wheel"),
    ("Flywheel.hdot", "SatelliteDynamics.hdot_wheel"),
]
PARAMETERS = {
    "SatelliteDynamics": {
        "gravity_gradient": False,
        **{f"inertia[{i},{j}]": 50.0 * (i == j) for i in (1, 2, 3) for j in (1, 2, 3)},
        "rate0[1]": 0.02,
        "rate0[2]": -0.01,
        "rate0[3]": 0.015,
    },
    "RateDamper": {"gain": 5.0},
}


def parameter(name, value):
    kind, text = ("Boolean", str(value).lower()) if isinstance(value, bool) else ("Real", value)
    return f'<ssv:Parameter name="{name}"><ssv:{kind} value="{text}"/></ssv:Parameter>'


def component(name, source):
    values = "".join(parameter(k, v) for k, v in PARAMETERS.get(name, {}).items())
    bindings = (
        (
            f"<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>"
            f'<ssv:ParameterSet version="1.0" name="{name}"><ssv:Parameters>{values}'
            f"</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues>"
            f"</ssd:ParameterBinding></ssd:ParameterBindings>"
        )
        if values
        else ""
    )
    relative = Path(os.path.relpath(source, OUT)).as_posix()  # a URI reference
    return (
        f'<ssd:Component name="{name}" source="{relative}" '
        f'type="application/x-fmu-sharedlibrary">{bindings}</ssd:Component>'
    )


connections = "".join(
    f'<ssd:Connection startElement="{a.split(".")[0]}" startConnector="{a.split(".")[1]}[{i}]" '
    f'endElement="{b.split(".")[0]}" endConnector="{b.split(".")[1]}[{i}]"/>'
    for a, b in WIRES
    for i in (1, 2, 3)
)
ssd = f"""<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="detumble"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
  <ssd:System name="detumble">
    <ssd:Elements>{"".join(component(n, s) for n, s in sources.items())}</ssd:Elements>
    <ssd:Connections>{connections}</ssd:Connections>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0.0" stopTime="100.0">
    <ssd:Annotations>
      <ssc:Annotation type="org.agilesat.master">
        <agilesat:Master xmlns:agilesat="http://agilesat.org/ssp/master" stepSize="0.05"/>
      </ssc:Annotation>
    </ssd:Annotations>
  </ssd:DefaultExperiment>
</ssd:SystemStructureDescription>
"""
(OUT / "detumble.ssd").write_text(ssd)
print(OUT / "detumble.ssd")
