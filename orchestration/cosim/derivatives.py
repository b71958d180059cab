"""FMI 2.0 input and output derivatives between FMUs (FMI 2.0 section 4.2.1): which
inputs get their first derivative from which outputs, and the calls that pass them
(``fmi2GetRealOutputDerivatives`` at t_n for extrapolation, the slope (y_{n+1} − y_n)/H
for interpolation of an output of an FMU that already stepped)."""

from __future__ import annotations

import ctypes

import numpy as np

from .fmu import Instance


def derivative_links(described: dict, sources: dict, every: dict, algorithm: str) -> dict:
    """{consumer: [(input, source, output, interpolated?), ...]}: the inputs that get their
    first derivative, from the model descriptions alone (``described``: {instance: its
    :class:`..system.description.Description`}, in step order; ``sources``: {(B, input):
    (A, output)}; ``every``: each instance's step in base steps)."""
    order = list(described)  # the step order: in Gauss-Seidel, who steps first
    links: dict[str, list] = {}
    for (b, u), (a, y) in sorted(sources.items()):
        consumer, source = described[b], described[a]
        du, dy = consumer.derivatives.get(u), source.derivatives.get(y)
        if (
            consumer.can_interpolate_inputs
            and source.max_output_derivative_order >= 1
            and du is not None
            and consumer.variables[du].causality == "input"
            and dy is not None
            and source.variables[dy].causality == "output"
            and (b, du) not in sources  # an explicit derivative wire wins
            and every.get(a, 1) == every.get(b, 1) == 1
        ):
            after = algorithm == "gauss-seidel" and order.index(a) < order.index(b)
            links.setdefault(b, []).append((u, a, y, after))
    return links


def describe(links: dict) -> list[str]:
    """'A.y -> B.u (extrapolated)' for each link of :func:`derivative_links`."""
    return [
        f"{a}.{y} -> {b}.{u} ({'interpolated' if after else 'extrapolated'})"
        for b, entries in links.items()
        for u, a, y, after in entries
    ]


class Derivatives:
    """The input-derivative links of a run (:mod:`.master`'s docstring, step 3): per source
    FMU the outputs whose derivatives are read, per consumer FMU the inputs whose
    derivatives are set.  ``slopes`` (the value vector's layout) holds the output
    derivatives of the last communication point."""

    def __init__(self, nodes: dict, sources: dict, layout: dict, algorithm: str):
        links = derivative_links(
            {name: node.instance for name, node in nodes.items()},
            sources,
            {name: node.every for name, node in nodes.items()},
            algorithm,
        )
        self.described = describe(links)
        self.consumers = {b: _InputSlopes(nodes[b].instance, e, layout) for b, e in links.items()}
        outputs: dict[str, list] = {}  # read for the extrapolated links only
        for entries in links.values():
            for _, a, y, after in entries:
                if not after and y not in outputs.setdefault(a, []):
                    outputs[a].append(y)
        self.sources = [_OutputSlopes(nodes[a].instance, ys, layout) for a, ys in outputs.items()]
        self.interpolating = any(c.interpolated.any() for c in self.consumers.values())
        self.slopes = np.zeros(len(layout))
        self.previous = np.zeros(len(layout))  # the values at t_n (Gauss-Seidel)

    def read(self) -> None:
        """The output derivatives at the current communication point."""
        for source in self.sources:
            source.read(self.slopes)


class _OutputSlopes:
    """fmi2GetRealOutputDerivatives (order 1) of some outputs of one FMU."""

    def __init__(self, instance: Instance, names: list[str], layout: dict):
        self.instance, self.n = instance, len(names)
        self.vrs = (ctypes.c_uint * self.n)(*(instance.variables[y].valueReference for y in names))
        self.orders = (ctypes.c_int * self.n)(*[1] * self.n)
        self.buffer = np.zeros(self.n)
        self.ptr = self.buffer.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
        self.index = np.array([layout[(instance.name, y)] for y in names], dtype=np.intp)

    def read(self, slopes: np.ndarray) -> None:
        self.instance.call("fmi2GetRealOutputDerivatives", self.vrs, self.n, self.orders, self.ptr)
        slopes[self.index] = self.buffer


class _InputSlopes:
    """fmi2SetRealInputDerivatives (order 1) of some inputs of one FMU, from the outputs
    feeding them; the interpolated ones also get their values at t_n."""

    def __init__(self, instance: Instance, entries: list, layout: dict):
        self.instance, self.n = instance, len(entries)
        self.vrs = (ctypes.c_uint * self.n)(
            *(instance.variables[u].valueReference for u, *_ in entries)
        )
        self.orders = (ctypes.c_int * self.n)(*[1] * self.n)
        self.index = np.array([layout[(a, y)] for _, a, y, _ in entries], dtype=np.intp)
        self.interpolated = np.array([after for *_, after in entries], dtype=bool)
        self.buffer = np.zeros(self.n)
        chosen = [u for u, *_, after in entries if after]
        self.at_start = (ctypes.c_uint * len(chosen))(
            *(instance.variables[u].valueReference for u in chosen)
        )
        self.start_buffer = np.zeros(len(chosen))
