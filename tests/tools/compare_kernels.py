"""Do two builds of the FMUs run the same kernels?  For each model, its declared kernels from
two built FMUs (the code packed in each, imported side by side): the machine code numba
compiles them to (the assembly of the C step path's signature, symbol names and pickled
error locations taken out) and the bytecodes their Python executes per call over a short
run at the defaults (callees included: the Python tier's cost, counted, not timed, so a
loaded machine does not blur it).  Prints a report (not a test: a tool for refactors and
speed work, beside compare_results.py).

    python tests/tools/compare_kernels.py OLD_BUILD_DIR NEW_BUILD_DIR [NAME ...]
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
import tempfile
import zipfile
from pathlib import Path

STEP = 0.05
STEPS = 20


def load(fmu: Path, name: str):
    """(model class, its jit module) of the code packed in ``fmu``."""
    folder = tempfile.mkdtemp()
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(folder)
    resources = Path(folder, "resources")
    sys.path.insert(0, str(resources))
    package = next(p.name for p in resources.iterdir() if p.name.startswith("agilesat_"))
    model = importlib.import_module(package + ".fmus").model_class(name)
    for path in (".components.runtime.jit", ".components.jit"):  # this layout, the one before
        try:
            jit = importlib.import_module(package + path)
        except ImportError:
            continue
        jit._numba()  # numba told about the jitable functions the kernels call
        return model, jit
    raise ImportError(f"no jit module in {fmu}")


def assembly(kernel, role: str) -> list[str]:
    """The instructions numba compiles ``kernel`` to, for the C entry's argument types."""
    import numba

    array = numba.types.float64[::1]
    times = (numba.float64, numba.float64) if role == "step" else (numba.float64,)
    signature = (array, array, *times)
    dispatcher = numba.njit(kernel.py_func)
    dispatcher.compile(signature)
    lines = []
    for line in dispatcher.inspect_asm(signature).splitlines():
        line = line.split("#")[0].strip()
        if not line or line.startswith(".") and not line.startswith(".L") or "pickle" in line:
            continue  # directives, and the pickled error locations (file, line)
        lines.append(re.sub(r"\.L[\w$.]+|_ZN[\w$.]+", "NAME", line))
    return lines


def bytecodes(model_class, jit) -> dict[str, float]:
    """{role: bytecodes per call} of the kernels' Python over a run at the defaults."""
    counts: dict[str, int] = {}
    role = ""

    def trace(frame, event, arg):
        frame.f_trace_opcodes = True

        def local(frame, event, arg):
            if event == "opcode":
                counts[role] = counts.get(role, 0) + 1
            return local

        return local

    def counted(function, name):
        def run(*args):
            nonlocal role
            role = name
            sys.settrace(trace)
            try:
                return function(*args)
            finally:
                sys.settrace(None)

        return run

    for name, kernel in zip(("step", "output"), jit.declared(model_class)):
        if kernel is not None:
            kernel._run = counted(kernel.py_func, name)
    model = model_class().start(0.0)
    counts.clear()
    for k in range(STEPS):
        model.advance(k * STEP, STEP)
    return {name: n / STEPS for name, n in counts.items()}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("names", nargs="*")
    args = parser.parse_args(argv)
    names = args.names or sorted(p.stem for p in args.new.glob("*.fmu"))
    print(f"{'model':>24} {'kernel':>7} {'machine code (instructions)':>36} {'bytecodes/call':>22}")
    for name in names:
        old, new = load(args.old / f"{name}.fmu", name), load(args.new / f"{name}.fmu", name)
        old_counts, new_counts = bytecodes(*old), bytecodes(*new)
        for role, before, after in zip(
            ("step", "output"), old[1].declared(old[0]), new[1].declared(new[0])
        ):
            if before is None and after is None:
                continue
            a, b = assembly(before, role), assembly(after, role)
            code = "identical" if a == b else "differs"
            x, y = old_counts.get(role, 0.0), new_counts.get(role, 0.0)
            print(
                f"{name:>24} {role:>7} {code:>10} {len(a):>6} -> {len(b):<6} "
                f"{x:>8.0f} -> {y:<6.0f} ({y / x if x else 0:.3f})"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
