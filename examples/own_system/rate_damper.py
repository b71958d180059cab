"""The user's own FMU: a rate damper, tau_cmd = −gain · w_BI_B (three axes).

Any FMI 2.0 co-simulation FMU will do; this one is written with pythonfmu and built with
``pythonfmu build -f rate_damper.py``.  Array elements are FMI structured names
(``w_BI_B[1]``), so that they connect to agilesat's vectors element by element.
"""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class RateDamper(Fmi2Slave):
    author = "An AOCS engineer"
    description = "Rate damping: tau_cmd = -gain * w_BI_B"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.gain = 1.0  # N·m·s/rad
        self.w = [0.0, 0.0, 0.0]
        self.register_variable(
            Real("gain", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        )
        for i in range(3):
            self.register_variable(
                Real(
                    f"w_BI_B[{i + 1}]",
                    causality=Fmi2Causality.input,
                    getter=lambda i=i: self.w[i],
                    setter=lambda v, i=i: self.w.__setitem__(i, v),
                )
            )
            self.register_variable(
                Real(  # direct feedthrough
                    f"tau_cmd[{i + 1}]",
                    causality=Fmi2Causality.output,
                    getter=lambda i=i: -self.gain * self.w[i],
                )
            )

    def do_step(self, current_time, step_size):
        return True
