"""Multi-rate stepping: a component may communicate at a multiple of the base macro step.

A flight computer runs its controller at a fixed rate (a design choice, 10–20 Hz), while
tightly coupled plant FMUs want a finer step.  A component's own communication step is an
annotation on the component in the SSD (:mod:`..system.steps`).

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

from ..system.steps import StepError


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
