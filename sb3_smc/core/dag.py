"""Graphs of names that call or use each other (an SMC library's children, a curriculum's ``uses``): children
before parents, and the cycle that prevents it."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence

from sb3_smc.errors import SMCError

__all__ = ["CycleError", "children_first", "reachable"]


class CycleError(SMCError):
    """The graph has a cycle: ``cycle`` lists it, its first name repeated at the end (``a -> b -> a``); callers turn
    it into their own error, naming their file."""

    def __init__(self, cycle: list[str]) -> None:
        super().__init__(" -> ".join(cycle))
        self.cycle = cycle


def children_first(graph: Mapping[str, Sequence[str]]) -> list[str]:
    """The names of ``graph`` (name -> the names it calls, all of them keys), each after those it calls, otherwise
    in the graph's order (depth first); :class:`CycleError` if names call each other in a cycle."""
    order: list[str] = []
    state: dict[str, int] = {}  # 1 visiting, 2 done

    def visit(name: str, path: list[str]) -> None:
        if state.get(name) == 2:
            return
        if state.get(name) == 1:
            raise CycleError(path[path.index(name):] + [name])
        state[name] = 1
        for called in graph[name]:
            visit(called, [*path, name])
        state[name] = 2
        order.append(name)

    for name in graph:
        visit(name, [])
    return order


def reachable(names: Iterable[str], calls: Callable[[str], Iterable[str]]) -> set[str]:
    """``names`` and every name they call (``calls(name)``), directly or not."""
    seen: set[str] = set()
    stack = list(names)
    while stack:
        name = stack.pop()
        if name not in seen:
            seen.add(name)
            stack.extend(calls(name))
    return seen
