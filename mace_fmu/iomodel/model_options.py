"""What a volts-volts model includes besides the structure: the modelled electronics and the signals kept.

A model is built in stages, each from the one before: the modes (:func:`~mace_fmu.fe.modes.compute_modes`),
the instruments (from the structure file), then :func:`~mace_fmu.iomodel.volts.volts_model` with these two
records. Each record checks itself when it is made, so a bad choice is refused before any work.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, Sequence

import numpy as np

from mace_fmu.errors import MaceError

if TYPE_CHECKING:
    from mace_fmu.iomodel.instruments import Instruments

BesselKind = Literal["full", "delay", "none"]
BESSEL_KINDS: tuple[str, ...] = ("full", "delay", "none")


#: highest Pade order: the native runtime's coefficients are exact integer ratios up to it, and higher orders
#: gain nothing at millisecond delays (3 reproduces Tables 4.7 and 5.2) while their realisation's conditioning
#: grows with factorials (order 99 overflowed)
MAX_PADE_ORDER = 10


@dataclass(frozen=True)
class ModelledElectronics:
    """Which parts of the control electronics the model contains, and how.

    Parameters
    ----------
    servos : bool
        Close the local loops the structure file declares (MACE: wheel speed loops and gimbal servos).
    bessel : {"full", "delay", "none"}
        The analog anti-aliasing filters as filters, as their equivalent time delay, or left out.
    delays : bool
        The actuator and sensor time delays [s] of the structure file (or the parameter set).
    pade_order : int
        Order of the Pade approximation of every delay, 1 to :data:`MAX_PADE_ORDER`.

    Raises
    ------
    MaceError
        A ``bessel`` kind or a ``pade_order`` outside what is allowed.
    """

    servos: bool = True
    bessel: BesselKind = "full"
    delays: bool = True
    pade_order: int = 3

    def __post_init__(self) -> None:
        if self.bessel not in BESSEL_KINDS:
            raise MaceError(f"bessel must be 'full', 'delay' or 'none', got {self.bessel!r}")
        if isinstance(self.pade_order, bool) or not isinstance(self.pade_order, int) \
                or not 1 <= self.pade_order <= MAX_PADE_ORDER:
            raise MaceError(f"pade_order must be an integer from 1 to {MAX_PADE_ORDER}, got {self.pade_order!r}")

    def describe(self, *, instruments: Instruments | None = None) -> str:
        """One line for reports and FMU descriptions, e.g. "servos closed, Bessel filters full, delays on".

        Parameters
        ----------
        instruments : Instruments, optional
            The structure's instruments, loops and electronics: a part the structure file does not declare is
            said to be absent ("no servos", "no anti-aliasing filters", "no delays"), whatever the choice for
            it, and the filters are named by their kind (Bessel, Butterworth). Without them: the choices alone.

        Returns
        -------
        str
            E.g. "servos closed, Bessel filters full, delays on" (MACE) or "no servos, no anti-aliasing
            filters, no delays" (a structure file with sensors and actuators only).
        """
        if instruments is None:
            return (f"servos {'closed' if self.servos else 'open'}, Bessel filters {self.bessel}, "
                    f"delays {'on' if self.delays else 'off'}")
        el, loops = instruments.electronics, instruments.servos
        servos = f"servos {'closed' if self.servos else 'open'}" if loops.wheels or loops.gimbals else "no servos"
        filtered = el.filter_order > 0 and bool(el.analog_sensors)
        filters = f"{el.filter_kind.capitalize()} filters {self.bessel}" if filtered else "no anti-aliasing filters"
        delayed = bool(el.actuator_delays_s) or bool(el.sensor_delays_s)
        delays = f"delays {'on' if self.delays else 'off'}" if delayed else "no delays"
        return f"{servos}, {filters}, {delays}"


@dataclass(frozen=True)
class SignalSelection:
    """Which inputs and outputs a model keeps, and which grids' motion it adds as outputs.

    Parameters
    ----------
    inputs, outputs : sequence of str, optional
        Keep only these inputs and outputs, by name, in this order (None: all).
    motion_grids : sequence of int or "all"
        Adds each grid's translations [m] and rotations [rad] in basic axes as outputs
        ``grid_<id>_<tx|ty|tz|rx|ry|rz>`` after the sensors, for animation ("all": every grid).

    Raises
    ------
    MaceError
        ``motion_grids`` that are neither grid IDs nor "all".
    """

    inputs: Sequence[str] | None = None  #: inputs kept, by name and in this order (None: all)
    outputs: Sequence[str] | None = None
    motion_grids: Sequence[int] | Literal["all"] = ()

    def __post_init__(self) -> None:
        grids = self.motion_grids
        if isinstance(grids, str):
            if grids != "all":
                raise MaceError(f"motion_grids must be grid IDs or 'all', got {grids!r}")
        elif not (isinstance(grids, (Sequence, np.ndarray))
                  and all(isinstance(g, (int, np.integer)) and not isinstance(g, bool) for g in grids)):
            raise MaceError(f"motion_grids must be a list of grid IDs or 'all', got {grids!r}")
        for name in ("inputs", "outputs"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, str) or not all(isinstance(v, str) for v in value)):
                raise MaceError(f"{name} must be a list of signal names, got {value!r}")
        # stored as tuples: a frozen record must not change under its holder
        object.__setattr__(self, "inputs", None if self.inputs is None else tuple(self.inputs))
        object.__setattr__(self, "outputs", None if self.outputs is None else tuple(self.outputs))
        if not isinstance(grids, str):
            object.__setattr__(self, "motion_grids", tuple(int(g) for g in grids))
