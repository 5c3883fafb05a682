"""FMUs of the bundled deck exported with moduli built in: the synthetic truths and the models of the updating tests.

An update's test is only a test of the FMU's parameter route when its data come from another model than the
one updated. Here the data come from one full re-solve (the deck as it is: Table 4.4's moduli) and the model
updated is the FMU of another (the deck with several moduli off, built in with ``export --parameters``'s
route), which starts at its own nominal values and must reach the data's through the route, never the other
way round (the FMU started off its own nominal and brought back, where the route is exact by construction).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Mapping

from mace_fmu.deck.reader import read_deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.export import export_fmu
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import ParameterSet, deck_values
from mace_fmu.structure.file import bundled_deck_path


def deck_moduli(names) -> dict[str, float]:
    """The bundled deck's values [SI] of ``names``."""
    values = deck_values(read_deck(bundled_deck_path()))
    return {n: values[n] for n in names}


#: (factors, name, configuration, runtime) -> the FMU exported first in this process
_EXPORTED: dict[tuple, Path] = {}


def fmu_with(folder: Path, *, factors: Mapping[str, float], name: str, configuration: str = "1g",
             runtime: str = "native") -> Path:
    """The bundled deck's FMU with each of ``factors``' moduli [or springs] times its factor built in (a full
    re-solve continuing the nominal modes), written into ``folder``. The same FMU asked for again in this process
    (the same factors, name, configuration and runtime) is a copy of the first export."""
    key = (tuple(sorted((n, float(f)) for n, f in factors.items())), name, configuration, runtime)
    first = _EXPORTED.get(key)
    if first is not None and first.is_file():
        target = Path(folder) / first.name
        if target.resolve() == first.resolve():
            return first
        Path(folder).mkdir(parents=True, exist_ok=True)
        return Path(shutil.copyfile(first, target))
    point = {n: v * factors[n] for n, v in deck_moduli(factors).items()}
    modes = compute_modes(configuration=configuration, parameters=ParameterSet(point) if point else None)
    path = Path(export_fmu(volts_model(modes), out_dir=folder, name=name, runtime=runtime))
    _EXPORTED[key] = path
    return path
