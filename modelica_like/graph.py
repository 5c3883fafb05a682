"""Structural checks run before compiling: unconnected inputs and algebraic loops.

The signal graph has one node per scalar block element. Edges run from each driving output
element to the input elements it feeds (the connections) and, inside a block, from input
element ``j`` to output element ``i`` wherever ``D[i, j] != 0`` (a direct-feedthrough path).
A cycle in this graph is an algebraic loop: an equation that no state separates.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from .blocks import Block
from .connectors import Element


def unconnected_inputs(blocks: Iterable[Block], driven: Mapping[Element, object]) -> list[Element]:
    """Block input elements that nothing drives, in block and port order."""
    return [e for b in blocks for e in b.elements("input") if e not in driven]


def feedthrough_edges(block: Block) -> list[tuple[Element, Element]]:
    """``(input element, output element)`` pairs joined by a non-zero entry of ``block.D``."""
    ins, outs = block.elements("input"), block.elements("output")
    return [(ins[j], outs[i]) for i in range(len(outs)) for j in range(len(ins))
            if block.D[i, j] != 0]


def find_algebraic_loop(blocks: Iterable[Block],
                        drivers: Mapping[Element, Element]) -> list[Element] | None:
    """One cycle of direct-feedthrough paths as ``[e0, e1, ..., e0]``, or ``None`` if none.

    ``drivers`` maps each connected input element to the output element driving it (system
    inputs are not in it: they cannot lie on a cycle).
    """
    successors: dict[Element, list[Element]] = {}
    for block in blocks:
        for a, b in feedthrough_edges(block):
            successors.setdefault(a, []).append(b)
    for dst, src in drivers.items():
        successors.setdefault(src, []).append(dst)

    # Iterative depth-first search (no recursion limit on big diagrams); a grey node met again
    # closes a cycle, whose nodes are the tail of the current path.
    WHITE, GREY, BLACK = 0, 1, 2
    colour: dict[Element, int] = {}
    for root in successors:
        if colour.get(root, WHITE) != WHITE:
            continue
        path: list[Element] = [root]
        stack = [iter(successors.get(root, ()))]
        colour[root] = GREY
        while stack:
            nxt = next(stack[-1], None)
            if nxt is None:
                colour[path.pop()] = BLACK
                stack.pop()
            elif colour.get(nxt, WHITE) == GREY:
                return path[path.index(nxt):] + [nxt]
            elif colour.get(nxt, WHITE) == WHITE:
                colour[nxt] = GREY
                path.append(nxt)
                stack.append(iter(successors.get(nxt, ())))
    return None
