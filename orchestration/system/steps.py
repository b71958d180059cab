"""A component's own communication step, as an SSD says it (read and written here; what the
master makes of it: :mod:`..cosim.multirate`).

The step is an annotation on the component in the SSD (after its connectors and parameter
bindings, where the SSD schema puts an element's annotations), in seconds::

    <ssd:Annotations>
      <ssc:Annotation type="org.agilesat.step">
        <agilesat:Step xmlns:agilesat="http://agilesat.org/ssp/master" stepSize="0.05"/>
      </ssc:Annotation>
      <ssc:Annotation type="com.opensimulationplatform">
        <osp:StepSizeHint xmlns:osp="https://opensimulationplatform.com/SSP/1.0" value="0.05"/>
      </ssc:Annotation>
    </ssd:Annotations>

The second is libcosim's own equivalent (its SSP parser reads ``osp:StepSizeHint`` of a
component into the simulator's step size hint; its fixed-step algorithm then steps that
simulator every ceil(hint / base step) base steps).  We read only ours.
"""

from __future__ import annotations

from lxml import etree

STEP_ANNOTATION = "org.agilesat.step"
NAMESPACE = "http://agilesat.org/ssp/master"
_SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
_SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
_OSP_ANNOTATION = "com.opensimulationplatform"
_OSP = "https://opensimulationplatform.com/SSP/1.0"


class StepError(ValueError):
    """A component step that the master cannot honour (the message names file, line and
    component)."""


def read_step(component, where: str) -> float | None:
    """The ``org.agilesat.step`` step size of an ``ssd:Component`` element, or None."""
    for annotation in component.findall(f"{{{_SSD}}}Annotations/{{{_SSC}}}Annotation"):
        if annotation.get("type") != STEP_ANNOTATION:
            continue
        settings = annotation.find(f"{{{NAMESPACE}}}Step")
        text = None if settings is None else settings.get("stepSize")
        try:
            return float(text or "")
        except ValueError:
            raise StepError(
                f"{where}: component '{component.get('name')}': the {STEP_ANNOTATION} "
                f'annotation needs <agilesat:Step stepSize="seconds"/> (got {text!r})'
            ) from None
    return None


def write_step(component, step: float | None) -> None:
    """Append the step annotations (ours and libcosim's) to an ``ssd:Component``."""
    if step is None:
        return
    annotations = etree.SubElement(component, f"{{{_SSD}}}Annotations")
    ours = etree.SubElement(annotations, f"{{{_SSC}}}Annotation", type=STEP_ANNOTATION)
    etree.SubElement(ours, f"{{{NAMESPACE}}}Step", nsmap={"agilesat": NAMESPACE}).set(
        "stepSize", repr(float(step))
    )
    # libcosim matches the literal prefix "osp:" (see ssp.render_ssd): declared here
    osp = etree.SubElement(
        annotations, f"{{{_SSC}}}Annotation", nsmap={"osp": _OSP}, type=_OSP_ANNOTATION
    )
    etree.SubElement(osp, f"{{{_OSP}}}StepSizeHint").set("value", repr(float(step)))
