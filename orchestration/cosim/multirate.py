"""Multi-rate stepping: a component may communicate at a multiple of the base macro step.

A flight computer runs its controller at a fixed rate (a design choice, 10–20 Hz), while
tightly coupled plant FMUs want a finer step.  A component's own communication step is an
annotation on the component in the SSD (after its connectors and parameter bindings,
where the SSD schema puts an element's annotations), in seconds::

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

Rules (:func:`multiples`): the component step P must be positive and finite and an
integer multiple m = P / H of the base macro step H (within 1e-9 relative), and the run
must end on one of its communication points.  A component without the annotation has
m = 1.  The master (:mod:`.master`) then, with k the index of a communication point
t_k = t0 + k H:

- steps the component from t_k over m H when k is a multiple of m;
- sets its inputs and reads its outputs only at t_k with k a multiple of m, when its own
  time equals the master's; in between its outputs hold their last values (zero-order hold).

A controller at P = m H therefore computes its command from the plant at t = j P and holds
it for m plant steps: the sampled-data system of a flight computer.
"""

from __future__ import annotations

import math

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


def multiples(system, base: float, n_steps: int) -> dict[str, int]:
    """Component name -> m (its step over the base step ``base``) for every component of
    ``system``; a StepError naming file, line and component for a step that is not
    positive and finite, not a multiple of the base step, or whose communication points
    miss the stop time (n_steps base steps)."""
    result = {}
    for ref in system.components:
        step = getattr(ref, "step_size", None)
        where = f"{system.path}:{ref.line}: component '{ref.name}'"
        if step is None:
            result[ref.name] = 1
            continue
        if not (math.isfinite(step) and step > 0):
            raise StepError(
                f"{where}: its step must be a positive, finite number of seconds, got {step}"
            )
        m = round(step / base)
        if m < 1 or not math.isclose(m * base, step, rel_tol=1e-9, abs_tol=0.0):
            raise StepError(
                f"{where}: its step {step} s is not an integer multiple of the base macro "
                f"step {base} s"
            )
        if n_steps % m:
            raise StepError(
                f"{where}: the run of {n_steps} macro steps of {base} s does not end on a "
                f"communication point of its step {step} s (make the run a multiple of it)"
            )
        result[ref.name] = m
    return result
