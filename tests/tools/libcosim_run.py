"""Run an SSP system in libcosim (libcosimpy) and save every output at every step.

    python libcosim_run.py SYSTEM.ssp STOP OUT.npz [STEP]

Run as a script in a fresh process (tests/interop/test_libcosim.py).  libcosim reads the system
itself (its SSP loader, the step from the package's OSP annotation unless STEP is given);
every libcosimpy call is checked.  Columns as in our master: "time", "<instance>.<name>".
Exit status 2 with libcosim's error message if a call fails; the rows recorded so far are
saved all the same.
"""

import sys

import numpy as np
from libcosimpy._internal import get_last_error_message
from libcosimpy.CosimEnums import CosimVariableCausality, CosimVariableType
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver

READERS = {
    CosimVariableType.REAL.value: "last_real_values",
    CosimVariableType.INTEGER.value: "last_integer_values",
    CosimVariableType.BOOLEAN.value: "last_boolean_values",
}


def check(ok, call):
    if not ok:
        raise RuntimeError(f"libcosim: {call} failed: {get_last_error_message()}")


def main(path, stop, out, step=None):
    log_output_level(CosimLogLevel.WARNING)
    try:
        execution = (
            CosimExecution.from_ssp_file(path)
            if step is None
            else CosimExecution.from_ssp_file(path, step_size=round(float(step) * 1e9))
        )
    except AssertionError:
        raise RuntimeError(f"libcosim cannot load {path}: {get_last_error_message()}") from None
    observer = CosimObserver.create_last_value()
    check(execution.add_observer(observer), "add_observer")
    reads, names = [], ["time"]
    for slave in execution.slave_infos():
        outputs = [
            v
            for v in execution.slave_variables(slave.index)
            if v.causality == CosimVariableCausality.OUTPUT.value and v.type in READERS
        ]
        for kind, reader in READERS.items():
            chosen = [v for v in outputs if v.type == kind]
            if chosen:
                reads.append(
                    (getattr(observer, reader), slave.index, [v.reference for v in chosen])
                )
                names += [f"{slave.name.decode()}.{v.name.decode()}" for v in chosen]
    rows = []
    try:
        while True:
            check(execution.step(), "step")
            status = execution.status()
            check(status.error_code == 0, "status")
            row = [status.current_time * 1e-9]
            for reader, index, references in reads:
                row += reader(index, references)
            rows.append(row)
            if status.current_time * 1e-9 >= float(stop) - 1e-9:
                break
    finally:
        np.savez(out, names=np.array(names), data=np.array(rows, dtype=float))


if __name__ == "__main__":
    try:
        main(*sys.argv[1:])
    except RuntimeError as error:
        print(error, file=sys.stderr)
        sys.exit(2)
