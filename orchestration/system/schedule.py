"""When each FMU steps and when each output is read, from the outputs' dependencies.

The outputs of all FMUs form a graph: output y of A points to output z of B when y drives an
input of B on which z depends directly (``ModelStructure/Outputs``; at initialisation
``InitialUnknowns``).  A cycle is an algebraic loop.  A topological order of the outputs,
grouped into runs of one FMU, is the evaluation sequence: reading the outputs block by block,
after setting that FMU's inputs, gives values consistent at a communication point.

An FMU may appear more than once: a reaction wheel's momentum (a state) feeds the hub's rate,
and the hub's rate feeds the wheel's momentum derivative (feedthrough), so the wheel is read
once before the hub and once after it — the FMUs depend on each other, the variables do not.
Each FMU steps at its first block (:attr:`Schedule.step_order`).  Among ready outputs the
order prefers the FMU of the previous block, then the FMUs in the order of their dependency
graph condensed into strongly connected parts, ties by their order in the system file.
"""

from __future__ import annotations

from dataclasses import dataclass

from .ssp import SystemFileError


@dataclass
class Schedule:
    step_order: list[str]  # every FMU once, at its first block
    blocks: list[tuple[str, tuple[str, ...]]]  # (instance, outputs) in evaluation order


def schedule(instances: dict, sources: dict, kind: str, where: str) -> Schedule:
    """``kind``: "feedthrough" (stepping) or "initial_feedthrough" (initialisation)."""
    outputs = {name: inst.outputs for name, inst in instances.items()}
    needs = {(b, z): set() for b, names in outputs.items() for z in names}
    via = {}  # (B, z), (A, y) -> input of B
    for (b, u), (a, y) in sources.items():
        dependencies = getattr(instances[b], kind)
        for z in outputs[b]:
            deps = dependencies.get(z, set())
            if deps is None or u in deps:
                needs[(b, z)].add((a, y))
                via[((b, z), (a, y))] = u
    rank = _fmu_rank(list(instances), needs)
    blocks: list[tuple[str, tuple[str, ...]]] = []
    done: set = set()
    while len(done) < len(needs):
        ready = [v for v in needs if v not in done and needs[v] <= done]
        if not ready:
            raise SystemFileError(f"{where}: algebraic loop: {_cycle(needs, done, via)}")
        last = blocks[-1][0] if blocks else None
        chosen: str = (
            last
            if last is not None and any(v[0] == last for v in ready)
            else min((v[0] for v in ready), key=rank.__getitem__)
        )
        block = [z for (b, z) in ready if b == chosen]
        done.update((chosen, z) for z in block)
        if blocks and blocks[-1][0] == chosen:
            blocks[-1] = (chosen, blocks[-1][1] + tuple(block))
        else:
            blocks.append((chosen, tuple(block)))
    order = list(dict.fromkeys(b for b, _ in blocks))
    return Schedule(order + [n for n in instances if n not in order], blocks)


def _fmu_rank(names: list[str], needs: dict) -> dict[str, tuple]:
    """Rank of each FMU: its strongly connected part's topological place, then file order."""
    edges = {n: set() for n in names}  # B -> FMUs B needs
    for (b, _), sources in needs.items():
        edges[b].update(a for a, _ in sources if a != b)
    reach = {n: _reachable(n, edges) for n in names}
    part = {n: frozenset(m for m in names if m in reach[n] and n in reach[m]) | {n} for n in names}
    placed, rank = [], {}
    while len(placed) < len(set(part.values())):
        candidates = [
            p
            for p in set(part.values())
            if p not in placed
            and all(part[m] in placed or part[m] == p for n in p for m in edges[n])
        ]
        nxt = min(candidates, key=lambda p: min(names.index(n) for n in p))
        placed.append(nxt)
    for position, p in enumerate(placed):
        for n in p:
            rank[n] = (position, names.index(n))
    return rank


def _reachable(start: str, edges: dict) -> set[str]:
    seen, stack = set(), [start]
    while stack:
        for m in edges[stack.pop()]:
            if m not in seen:
                seen.add(m)
                stack.append(m)
    return seen


def _cycle(needs: dict, done: set, via: dict) -> str:
    """A readable loop among the outputs not yet ordered."""
    node = next(v for v in needs if v not in done)
    path = [node]
    while True:
        node = next(v for v in needs[node] if v not in done)
        if node in path:
            loop = path[path.index(node) :] + [node]
            break
        path.append(node)
    steps = [
        f"{b}.{z} depends on input {b}.{via[((b, z), (a, y))]} driven by {a}.{y}"
        for (b, z), (a, y) in zip(loop, loop[1:])
    ]
    return "; ".join(steps) + " (each output depends directly on the next)"
