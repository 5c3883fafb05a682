"""The block base class and the elementary LTI blocks (state space, gain, sum, PD, PI, integrator).

Every block is a continuous-time LTI map ``dx/dt = A x + B u``, ``y = C x + D u`` where ``u``
stacks its input connectors and ``y`` its output connectors, in the order the block lists them.
Blocks are immutable once built: their matrices are read-only arrays.
"""

from __future__ import annotations

from collections.abc import Sequence

import control as ct
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .connectors import Connector, Element, check_identifier
from .errors import ModelError

__all__ = ["Block", "StateSpace", "Gain", "Sum", "PD", "PI", "Integrator"]


def _readonly(a: ArrayLike) -> NDArray[np.float64]:
    out = np.array(a, dtype=float)
    out.setflags(write=False)
    return out


class Block:
    """Base class: a named LTI block with typed input and output connectors.

    Subclasses compute their matrices and call ``Block.__init__``; the state names are local to
    the block (the compiled system prefixes them with ``"<block>."``).
    """

    kind = "Block"

    def __init__(self, name: str, inputs: Sequence[Connector], outputs: Sequence[Connector],
                 A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike,
                 states: Sequence[str]) -> None:
        check_identifier(name, f"{self.kind} name")
        self._name = name
        self._inputs = tuple(inputs)
        self._outputs = tuple(outputs)
        ports = [c.name for c in self._inputs + self._outputs]
        if len(set(ports)) != len(ports):
            raise ModelError(f"{self._where}: duplicate connector names {ports}")
        self._A, self._B, self._C, self._D = (_readonly(m) for m in (A, B, C, D))
        self._states = tuple(states)
        n, m, p = len(self._states), sum(c.size for c in inputs), sum(c.size for c in outputs)
        for label, mat, shape in (("A", self._A, (n, n)), ("B", self._B, (n, m)),
                                  ("C", self._C, (p, n)), ("D", self._D, (p, m))):
            if mat.shape != shape:  # only reachable through a faulty subclass
                raise ModelError(f"{self._where}: {label} has shape {mat.shape} but should be "
                                 f"{shape}")
        if len(set(self._states)) != n:
            raise ModelError(f"{self._where}: duplicate state names in {list(self._states)}")

    # --- identity and ports -------------------------------------------------------------------
    @property
    def _where(self) -> str:
        return f"{self.kind} {self._name!r}"

    @property
    def name(self) -> str:
        """Block name (unique within a System)."""
        return self._name

    @property
    def inputs(self) -> tuple[Connector, ...]:
        """Input connectors, in the order they are stacked into ``u``."""
        return self._inputs

    @property
    def outputs(self) -> tuple[Connector, ...]:
        """Output connectors, in the order they are stacked into ``y``."""
        return self._outputs

    @property
    def states(self) -> tuple[str, ...]:
        """Block-local state names, in state-vector order."""
        return self._states

    @property
    def connectors(self) -> dict[str, Connector]:
        """All connectors by name (inputs first)."""
        return {c.name: c for c in self._inputs + self._outputs}

    def connector(self, port: str) -> Connector:
        """The connector called ``port``; ModelError listing the block's connectors if none."""
        try:
            return self.connectors[port]
        except KeyError:
            known = ", ".join(c.describe() for c in self.connectors.values())
            raise ModelError(f"{self._where} has no connector {port!r}; its connectors are "
                             f"{known}") from None

    def offset(self, port: str) -> int:
        """Position of the connector's first element in the stacked ``u`` (or ``y``) vector."""
        connector = self.connector(port)
        group = self._inputs if connector.causality == "input" else self._outputs
        return sum(c.size for c in group[:group.index(connector)])

    def elements(self, causality: str) -> list[Element]:
        """All input (or output) elements in stacked-vector order."""
        group = self._inputs if causality == "input" else self._outputs
        return [Element(self._name, c.name, i, f"{self._name}.{c.label(i)}")
                for c in group for i in range(c.size)]

    # --- the LTI model ------------------------------------------------------------------------
    @property
    def A(self) -> NDArray[np.float64]:
        """State matrix (n, n)."""
        return self._A

    @property
    def B(self) -> NDArray[np.float64]:
        """Input matrix (n, m)."""
        return self._B

    @property
    def C(self) -> NDArray[np.float64]:
        """Output matrix (p, n)."""
        return self._C

    @property
    def D(self) -> NDArray[np.float64]:
        """Feedthrough matrix (p, m); its non-zeros define the algebraic paths."""
        return self._D

    def lti(self) -> ct.StateSpace:
        """The block as a continuous-time ``control.StateSpace`` with signals ``port[i]``.

        Signal labels use 1-based indices, so the subsystem signal ``plant.u[1]`` is element 1
        of connector ``u`` of block ``plant``.
        """
        def labels(group: tuple[Connector, ...]) -> list[str]:
            return [f"{c.name}[{i}]" for c in group for i in range(1, c.size + 1)]
        # dt=0 explicitly: python-control gives state-less systems dt=None otherwise.
        return ct.ss(self._A, self._B, self._C, self._D, inputs=labels(self._inputs),
                     outputs=labels(self._outputs), states=list(self._states), name=self._name,
                     dt=0)

    def __repr__(self) -> str:
        ports = ", ".join(c.describe() for c in self.connectors.values())
        return f"<{self.kind} {self._name!r}: {ports}; {len(self._states)} states>"


# --- helpers for the concrete blocks ------------------------------------------------------------
def owner_label(kind: str, name: str) -> str:
    """Validate a block name first (so it is checked before any parameter) and label the block."""
    check_identifier(name, f"{kind} name")
    return f"{kind} {name!r}"


def channels(owner: str, size: int,
             signals: Sequence[str] | None) -> tuple[int, Sequence[str] | None]:
    """Validate a block's channel count and optional per-channel signal names."""
    if signals is not None:
        signals = [signals] if isinstance(signals, str) else list(signals)
        if size != 1 and len(signals) != size:
            raise ModelError(f"{owner}: {len(signals)} signal names given for size={size}")
        size = len(signals)
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 1:
        raise ModelError(f"{owner}: size must be an integer >= 1, got {size!r}")
    return int(size), signals


def per_channel(owner: str, what: str, value: ArrayLike, size: int) -> NDArray[np.float64]:
    """A scalar or per-channel vector parameter as a finite vector of length ``size``."""
    v = np.asarray(value, dtype=float)
    if v.ndim == 0:
        v = np.full(size, float(v))
    if v.shape != (size,):
        raise ModelError(f"{owner}: {what} must be a scalar or a vector of length {size}, got "
                         f"shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ModelError(f"{owner}: {what} must be finite, got {v.tolist()}")
    return v


def channel_states(size: int, per_channel_states: int) -> list[str]:
    """State names of ``size`` independent copies: ``x[j]`` for one copy, ``x[i,j]`` for more."""
    if size == 1:
        return [f"x[{j}]" for j in range(1, per_channel_states + 1)]
    return [f"x[{i},{j}]" for i in range(1, size + 1) for j in range(1, per_channel_states + 1)]


def _matrix(owner: str, label: str, value: ArrayLike) -> NDArray[np.float64]:
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ModelError(f"{owner}: {label} is not a numeric matrix ({exc})") from None
    if a.ndim > 2:
        raise ModelError(f"{owner}: {label} must be 2-D, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ModelError(f"{owner}: {label} has non-finite entries")
    return a


# --- concrete blocks ----------------------------------------------------------------------------
class StateSpace(Block):
    """A general LTI block ``dx/dt = A x + B u``, ``y = C x + D u``: ports ``u`` and ``y``.

    Parameters
    ----------
    name : str
        Block name.
    A, B, C, D : array_like
        Shapes (n, n), (n, m), (p, n), (p, m). ``D=0`` means no feedthrough; empty A/B/C give a
        static block.
    inputs, outputs : sequence of str, optional
        Element names of ``u`` (m of them) and ``y`` (p); default ``u[i]`` / ``y[i]``.
    states : sequence of str, optional
        State names (n); default ``x[i]``.
    """

    kind = "StateSpace"

    def __init__(self, name: str, A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike = 0.0,
                 inputs: Sequence[str] | None = None, outputs: Sequence[str] | None = None,
                 states: Sequence[str] | None = None) -> None:
        owner = owner_label("StateSpace", name)
        A, B, C, D = (_matrix(owner, k, v) for k, v in zip("ABCD", (A, B, C, D)))
        # Like scipy's abcd_normalize: empty matrices take the shape the others imply.
        A = A.reshape(0, 0) if A.size == 0 else np.atleast_2d(A)
        n = A.shape[0]
        if A.shape != (n, n):
            raise ModelError(f"{owner}: A has shape {A.shape} but should be square (n, n)")
        B, C = np.atleast_2d(B), np.atleast_2d(C)
        D2 = np.atleast_2d(D)  # where B or C are empty, D alone fixes the port sizes
        m = len(inputs) if inputs is not None else (B.shape[1] if n else D2.shape[1])
        p = len(outputs) if outputs is not None else (C.shape[0] if n else D2.shape[0])
        if n == 0:
            B, C = np.zeros((0, m)), np.zeros((p, 0))
        if D.ndim == 0 and float(D) == 0.0:
            D = np.zeros((p, m))  # D=0: "no feedthrough" for any size
        D = np.atleast_2d(D)
        for label, mat, shape in (("B", B, (n, m)), ("C", C, (p, n)), ("D", D, (p, m))):
            if mat.shape != shape:
                raise ModelError(f"{owner}: {label} has shape {mat.shape} but should be {shape} "
                                 f"(n={n} states from A, m={m} inputs, p={p} outputs)")
        if states is not None and len(states) != n:
            raise ModelError(f"{owner}: {len(states)} state names given but A has {n} states")
        u = Connector.make("u", "input", m, inputs, owner=owner)
        y = Connector.make("y", "output", p, outputs, owner=owner)
        names = list(states) if states is not None else [f"x[{i}]" for i in range(1, n + 1)]
        super().__init__(name, [u], [y], A, B, C, D, names)


class Gain(Block):
    """Static matrix gain ``y = K u`` (K scalar or 2-D): ports ``u`` and ``y``.

    A scalar K acts on every element: its size comes from ``inputs``/``outputs`` (default 1).
    """

    kind = "Gain"

    def __init__(self, name: str, K: ArrayLike, inputs: Sequence[str] | None = None,
                 outputs: Sequence[str] | None = None) -> None:
        owner = owner_label("Gain", name)
        K = _matrix(owner, "K", K)
        if K.ndim == 0:
            sizes = {len(s) for s in (inputs, outputs) if s is not None} or {1}
            if len(sizes) > 1:  # both given: the set has two sizes only then
                assert inputs is not None and outputs is not None
                raise ModelError(f"{owner}: scalar K needs as many inputs as outputs, got "
                                 f"{len(inputs)} inputs and {len(outputs)} outputs")
            K = float(K) * np.eye(sizes.pop())
        elif K.ndim != 2:
            raise ModelError(f"{owner}: K must be a scalar or a 2-D array (p, m), got shape "
                             f"{K.shape}")
        p, m = K.shape
        u = Connector.make("u", "input", m, inputs, owner=owner)
        y = Connector.make("y", "output", p, outputs, owner=owner)
        super().__init__(name, [u], [y], np.zeros((0, 0)), np.zeros((0, m)), np.zeros((p, 0)),
                         K, [])


class Sum(Block):
    """Weighted sum ``y = sum(signs[i] * u{i+1})``: ports ``u1``, ``u2``, ... and ``y``."""

    kind = "Sum"

    def __init__(self, name: str, signs: Sequence[float] = (+1, -1), size: int = 1,
                 signals: Sequence[str] | None = None) -> None:
        owner = owner_label("Sum", name)
        size, signals = channels(owner, size, signals)
        w = np.asarray(signs, dtype=float).ravel()
        if w.size == 0 or not np.all(np.isfinite(w)):
            raise ModelError(f"{owner}: signs must be a non-empty sequence of finite numbers, "
                             f"got {signs!r}")
        ins = [Connector.make(f"u{k}", "input", size, signals, owner=owner)
               for k in range(1, w.size + 1)]
        y = Connector.make("y", "output", size, signals, owner=owner)
        D = np.hstack([wk * np.eye(size) for wk in w])
        super().__init__(name, ins, [y], np.zeros((0, 0)), np.zeros((0, w.size * size)),
                         np.zeros((size, 0)), D, [])


class PD(Block):
    """Static PD law ``y = kp*x + kd*dx`` on a measured value ``x`` and its measured rate ``dx``.

    No derivative is taken, so the block is proper (a pure feedthrough). ``kp`` and ``kd`` are
    scalars or per-element vectors.
    """

    kind = "PD"

    def __init__(self, name: str, kp: ArrayLike, kd: ArrayLike, size: int = 1,
                 signals: Sequence[str] | None = None) -> None:
        owner = owner_label("PD", name)
        size, signals = channels(owner, size, signals)
        kp_v, kd_v = per_channel(owner, "kp", kp, size), per_channel(owner, "kd", kd, size)
        x = Connector.make("x", "input", size, signals, owner=owner)
        dx = Connector.make("dx", "input", size, signals, owner=owner)
        y = Connector.make("y", "output", size, signals, owner=owner)
        super().__init__(name, [x, dx], [y], np.zeros((0, 0)), np.zeros((0, 2 * size)),
                         np.zeros((size, 0)), np.hstack([np.diag(kp_v), np.diag(kd_v)]), [])


class PI(Block):
    """PI law ``y = kp*u + ki*integral(u)``: ports ``u``, ``y``; state ``x[i]`` = integral of u."""

    kind = "PI"

    def __init__(self, name: str, kp: ArrayLike, ki: ArrayLike, size: int = 1,
                 signals: Sequence[str] | None = None) -> None:
        owner = owner_label("PI", name)
        size, signals = channels(owner, size, signals)
        kp_v, ki_v = per_channel(owner, "kp", kp, size), per_channel(owner, "ki", ki, size)
        u = Connector.make("u", "input", size, signals, owner=owner)
        y = Connector.make("y", "output", size, signals, owner=owner)
        super().__init__(name, [u], [y], np.zeros((size, size)), np.eye(size), np.diag(ki_v),
                         np.diag(kp_v), [f"x[{i}]" for i in range(1, size + 1)])


class Integrator(Block):
    """Integrator ``y = integral(u)`` per element: ports ``u`` and ``y``; states ``x[i]``."""

    kind = "Integrator"

    def __init__(self, name: str, size: int = 1, signals: Sequence[str] | None = None) -> None:
        owner = owner_label("Integrator", name)
        size, signals = channels(owner, size, signals)
        u = Connector.make("u", "input", size, signals, owner=owner)
        y = Connector.make("y", "output", size, signals, owner=owner)
        super().__init__(name, [u], [y], np.zeros((size, size)), np.eye(size), np.eye(size),
                         np.zeros((size, size)), [f"x[{i}]" for i in range(1, size + 1)])
