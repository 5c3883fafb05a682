"""``System``: blocks, connections and exposed signals, compiled to one ``control.StateSpace``."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import control as ct
import numpy as np

from .algebra import interconnect
from .blocks import Block
from .connectors import Connector, Element, check_identifier, parse_reference
from .errors import ModelError
from .graph import find_algebraic_loop, unconnected_inputs
from .modelica import modelica_source

__all__ = ["System"]

BlockT = TypeVar("BlockT", bound=Block)


@dataclass(frozen=True)
class _SystemInput:
    """A system input as the source driving a block input element."""

    name: str

    def __str__(self) -> str:
        return f"system input {self.name!r}"


@dataclass(frozen=True)
class Interconnection:
    """Blocks and wiring of a System: u_b = wiring @ y_b + entry @ r, y = exit @ y_b."""

    blocks: tuple[Block, ...]
    wiring: np.ndarray  #: L, (block inputs, block outputs)
    entry: np.ndarray  #: E, (block inputs, system inputs)
    exit: np.ndarray  #: F, (system outputs, block outputs)
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]


@dataclass(frozen=True)
class _Selection:
    """The resolved elements of one connector reference."""

    text: str
    block: Block
    connector: Connector
    elements: tuple[Element, ...]

    @property
    def where(self) -> str:
        return f"{self.block.name}.{self.connector.name}"


class System:
    """A block diagram: blocks, connections between their connectors and exposed signals.

    ``compile()`` turns it into one continuous-time ``control.StateSpace`` whose inputs and
    outputs are the exposed signals (in the order they were first exposed) and whose states are
    the blocks' states, block by block in the order of ``add`` (names ``"<block>.<state>"``).
    """

    def __init__(self, name: str) -> None:
        self._name = check_identifier(name, "System name")
        self._blocks: dict[str, Block] = {}
        self._drivers: dict[Element, Element | _SystemInput] = {}  # input element -> its source
        self._inputs: dict[str, list[Element]] = {}  # system input -> elements it drives
        self._outputs: dict[str, Element] = {}  # system output -> block output element

    # --- building -----------------------------------------------------------------------------
    @property
    def name(self) -> str:
        """System name (also the compiled system's and the Modelica model's default name)."""
        return self._name

    @property
    def blocks(self) -> tuple[Block, ...]:
        """The blocks in ``add`` order (= the order of their states in the compiled system)."""
        return tuple(self._blocks.values())

    @property
    def inputs(self) -> tuple[str, ...]:
        """Exposed input names, in compiled-input order."""
        return tuple(self._inputs)

    @property
    def outputs(self) -> tuple[str, ...]:
        """Exposed output names, in compiled-output order."""
        return tuple(self._outputs)

    def add(self, block: BlockT) -> BlockT:
        """Add a block (names unique within the system) and return it."""
        if not isinstance(block, Block):
            raise ModelError(f"system {self._name!r}: add() expects a modelica_like block, got "
                             f"{type(block).__name__}")
        if block.name in self._blocks:
            raise ModelError(f"system {self._name!r} already has a block named {block.name!r} "
                             f"({self._blocks[block.name]!r}); block names must be unique")
        self._blocks[block.name] = block
        return block

    def block(self, name: str) -> Block:
        """The block called ``name``."""
        try:
            return self._blocks[name]
        except KeyError:
            raise ModelError(f"system {self._name!r} has no block {name!r}; its blocks are "
                             f"{', '.join(self._blocks) or '(none)'}") from None

    def connect(self, a: str, b: str) -> None:
        """Connect an output connector (or some of its elements) to an input connector.

        The arguments may come in either order, as in Modelica; the two selections must have
        the same size and no selected input element may already be driven.
        """
        sa, sb = self._select(a), self._select(b)
        kinds = (sa.connector.causality, sb.connector.causality)
        if kinds == ("input", "output"):
            sa, sb = sb, sa
        elif kinds != ("output", "input"):
            raise ModelError(f"connect({a!r}, {b!r}): {sa.where} and {sb.where} are both "
                             f"{kinds[0]}s; expected one output and one input")
        if len(sa.elements) != len(sb.elements):
            raise ModelError(f"connect({a!r}, {b!r}): size mismatch: {sa.text} has size "
                             f"{len(sa.elements)} but {sb.text} has size {len(sb.elements)}")
        self._drive(list(zip(sa.elements, sb.elements)), f"connect({a!r}, {b!r})")

    def expose_input(self, names: str | Sequence[str], ref: str) -> None:
        """Drive the input connector ``ref`` with system input(s) ``names`` (one per element).

        Exposing an existing name again adds a destination (one input may feed many).
        """
        names, sel = self._exposed(names, ref, "input")
        clash = [n for n in names if n in self._outputs]
        if clash:
            raise ModelError(f"expose_input({ref!r}): {clash} already name system outputs; "
                             "input and output names must differ")
        self._drive([(_SystemInput(n), e) for n, e in zip(names, sel.elements)],
                    f"expose_input({ref!r})")
        for n, e in zip(names, sel.elements):
            self._inputs.setdefault(n, []).append(e)

    def expose_output(self, names: str | Sequence[str], ref: str) -> None:
        """Make the output connector ``ref`` system output(s) ``names`` (one per element)."""
        names, sel = self._exposed(names, ref, "output")
        for n in names:
            if n in self._outputs:
                raise ModelError(f"expose_output({ref!r}): system output {n!r} is already "
                                 f"{self._outputs[n]}")
            if n in self._inputs:
                raise ModelError(f"expose_output({ref!r}): {n!r} already names a system input; "
                                 "input and output names must differ")
        self._outputs.update(zip(names, sel.elements))

    def _exposed(self, names: str | Sequence[str], ref: str, causality: str) -> tuple[list[str], _Selection]:
        """Names and the connector they expose, checked for causality and size."""
        method = f"expose_{causality}"
        names = self._names(names, method, ref)
        sel = self._select(ref)
        if sel.connector.causality != causality:
            raise ModelError(f"{method}({ref!r}): {sel.where} is an {sel.connector.causality}; expected a "
                             f"block {causality} connector")
        if len(names) != len(sel.elements):
            raise ModelError(f"{method}({names!r}, {ref!r}): size mismatch: {len(names)} "
                             f"name(s) for {sel.text} of size {len(sel.elements)}")
        return names, sel

    # --- checking and compiling ---------------------------------------------------------------
    def check(self) -> None:
        """Raise ModelError if the diagram cannot be compiled (what ``compile`` checks first)."""
        if not self._outputs:
            raise ModelError(f"system {self._name!r} has no exposed outputs; call "
                             "expose_output(name, 'block.port') first")
        missing = unconnected_inputs(self._blocks.values(), self._drivers)
        if missing:
            raise ModelError(f"system {self._name!r}: {len(missing)} block input element(s) "
                             f"neither connected nor exposed: {', '.join(map(str, missing))}; "
                             "connect() each or expose_input() it")
        if not self._inputs:
            # python-control 0.10 cannot build a LinearICSystem with zero inputs (D gets shape
            # (0, 0) instead of (p, 0)), and an input-output model needs one anyway.
            raise ModelError(f"system {self._name!r} has no exposed inputs; call "
                             "expose_input(name, 'block.port') first")
        internal = {d: s for d, s in self._drivers.items() if isinstance(s, Element)}
        loop = find_algebraic_loop(self._blocks.values(), internal)
        if loop:
            raise ModelError(f"system {self._name!r}: algebraic loop (a cycle of direct-"
                             f"feedthrough paths, D != 0 all the way round): "
                             f"{' -> '.join(map(str, loop))}; put a strictly proper block "
                             "(Integrator, BesselFilter, StateSpace with D = 0) in the loop; a "
                             "PadeDelay does not break it (its D is +-1)")

    def compile(self) -> ct.StateSpace:
        """The whole diagram as one continuous-time ``control.StateSpace``.

        Inputs and outputs are labelled with the exposed names; states are
        ``"<block>.<state>"``, blocks in ``add`` order and each block's states in its own order.
        The matrices come from the wiring algebra (``modelica_like.algebra.interconnect``);
        ``control.interconnect`` gives the same system (tests/iomodel/test_build_equivalence.py) but
        linearises it numerically, which was 42 % of building both MACE models (profiled).
        """
        ic = self.connection_matrices()
        a, b, c, d = interconnect([(blk.A, blk.B, blk.C, blk.D) for blk in ic.blocks], ic.wiring, ic.entry, ic.exit)
        return ct.ss(a, b, c, d, inputs=list(ic.inputs), outputs=list(ic.outputs),
                     states=[f"{blk.name}.{s}" for blk in ic.blocks for s in blk.states], name=self._name,
                     dt=0)  # continuous time, also for all-static diagrams (which would otherwise get dt=None)

    def connection_matrices(self) -> Interconnection:
        """The diagram as data: blocks in ``add`` order and 0/1 matrices that wire them.

        With the blocks' inputs u_b and outputs y_b stacked in block order, u_b = L y_b + E r for
        the system inputs r, and y = F y_b for the system outputs. ``interconnect`` in
        ``modelica_like.algebra`` turns that back into one state-space system (numpy only).
        """
        self.check()
        blocks = list(self._blocks.values())
        in_start, out_start, n_in, n_out = {}, {}, 0, 0
        for b in blocks:
            in_start[b.name], out_start[b.name] = n_in, n_out
            n_in += len(b.elements("input"))
            n_out += len(b.elements("output"))

        def position(e: Element, start: dict[str, int]) -> int:
            return start[e.block] + self._blocks[e.block].offset(e.port) + e.index

        names_in = list(self._inputs)
        wiring, entry = np.zeros((n_in, n_out)), np.zeros((n_in, len(names_in)))
        for dst, src in self._drivers.items():
            if isinstance(src, Element):
                wiring[position(dst, in_start), position(src, out_start)] = 1.0
            else:
                entry[position(dst, in_start), names_in.index(src.name)] = 1.0
        exit_ = np.zeros((len(self._outputs), n_out))
        for k, e in enumerate(self._outputs.values()):
            exit_[k, position(e, out_start)] = 1.0
        return Interconnection(blocks=tuple(blocks), wiring=wiring, entry=entry, exit=exit_,
                               inputs=tuple(names_in), outputs=tuple(self._outputs))

    # --- Modelica -----------------------------------------------------------------------------
    def to_modelica(self, model_name: str | None = None) -> str:
        """Modelica source of a model equivalent to ``compile()`` (see ``modelica_source``).

        ``model_name`` defaults to the system name; either is sanitised to a Modelica identifier.
        """
        lti = self.compile()
        return modelica_source(lti.A, lti.B, lti.C, lti.D, model_name=model_name or self._name,
                               inputs=lti.input_labels, outputs=lti.output_labels,
                               states=lti.state_labels,
                               description=f"LTI model of modelica_like system {self._name!r}")

    def write_modelica(self, path: str | os.PathLike[str], model_name: str | None = None) -> Path:
        """Write ``to_modelica(model_name)`` to ``path`` (usually ``<model>.mo``); return it."""
        path = Path(path)
        path.write_text(self.to_modelica(model_name), encoding="utf-8")
        return path

    # --- internals ----------------------------------------------------------------------------
    def _select(self, text: str) -> _Selection:
        ref = parse_reference(text)
        if ref.block not in self._blocks:
            raise ModelError(f"{text!r}: system {self._name!r} has no block {ref.block!r}; its "
                             f"blocks are {', '.join(self._blocks) or '(none)'}")
        block = self._blocks[ref.block]
        try:
            connector = block.connector(ref.port)
        except ModelError as exc:
            raise ModelError(f"{text!r}: {exc}") from None
        where = f"{block.name}.{connector.name}"
        indices = connector.select(ref.selector, where)
        elements = tuple(Element(block.name, connector.name, i,
                                 f"{block.name}.{connector.label(i)}") for i in indices)
        return _Selection(ref.text, block, connector, elements)

    def _drive(self, pairs: list[tuple[Element | _SystemInput, Element]], context: str) -> None:
        """Record sources of input elements, refusing a second source for any of them."""
        seen: dict[Element, Element | _SystemInput] = {}
        for src, dst in pairs:
            previous = self._drivers.get(dst, seen.get(dst))
            if previous is not None:
                raise ModelError(f"{context}: {dst} is already driven by {previous}; it cannot "
                                 f"also be driven by {src} (an input takes one source)")
            seen[dst] = src
        self._drivers.update(seen)  # all or nothing

    def _names(self, names: str | Sequence[str], method: str, ref: str) -> list[str]:
        names = [names] if isinstance(names, str) else list(names)
        bad = [n for n in names if not isinstance(n, str) or not n.strip()]
        if bad or not names:
            raise ModelError(f"{method}({names!r}, {ref!r}): signal names must be non-empty "
                             "strings")
        if len(set(names)) != len(names):
            raise ModelError(f"{method}({names!r}, {ref!r}): duplicate names")
        return names

    def __repr__(self) -> str:
        return (f"<System {self._name!r}: {len(self._blocks)} blocks, "
                f"{len(self._inputs)} inputs, {len(self._outputs)} outputs>")
