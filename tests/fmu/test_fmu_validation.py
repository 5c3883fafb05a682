"""An FMU whose start value lies outside its declared min/max can neither be written nor pass
validation: FMI 2.0 and 3.0 require min <= start <= max and every host checks it, fmpy's validation did not.

The FMUs are the three-storey frame's native FMUs (FMI 2 and 3), written by the exporter and then given a
damping ratio of 1.5 on the [0, 1] their damping parameters declare, as a structure file's ``default = 1.5``
made them before it was refused at reading (tests/structure/test_structure_values.py).
"""

from __future__ import annotations

import re
import zipfile
from dataclasses import replace

import pytest
from fmpy.validation import validate_fmu as fmpy_validate_fmu
from support.paths import EXAMPLES

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu import check_fmu, validate_fmu
from mace_fmu.fmu.export import export_fmu
from mace_fmu.iomodel.instruments import load_instruments
from mace_fmu.iomodel.volts import volts_model

FRAME = EXAMPLES / "three_storey_frame"


@pytest.fixture(scope="module")
def modes():
    return compute_modes(read_deck(FRAME / "frame.bdf"), configuration="0g", structure_file=FRAME / "frame.toml")


def _with_start(fmu, tmp_path, name: str, start: str):
    """A copy of ``fmu`` whose variable ``name`` starts at ``start`` (the rest of the archive unchanged)."""
    out = tmp_path / f"bad_{fmu.name}"
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as target:
        for info in source.infolist():
            data = source.read(info.filename)
            if info.filename == "modelDescription.xml":
                text = data.decode()
                pattern = r'<(?:ScalarVariable|Float64) name="' + re.escape(name) + r'".*?(?:</ScalarVariable>|/>)'
                element = re.search(pattern, text, re.DOTALL).group(0)
                data = text.replace(element, re.sub(r'start="[^"]*"', f'start="{start}"', element)).encode()
            target.writestr(info, data)
    return out


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_a_start_value_outside_its_declared_range_fails_validation_and_is_refused(modes, tmp_path, fmi_version):
    fmu = export_fmu(volts_model(modes), out_dir=tmp_path, name="frame_0g", fmi_version=fmi_version)
    assert validate_fmu(fmu) == []  # the exporter's own FMU: every start within its range
    bad = _with_start(fmu, tmp_path, "damping_mode_1", "1.5")
    assert fmpy_validate_fmu(str(bad)) == []  # what fmpy's validation alone lets through
    problems = validate_fmu(bad)
    assert problems == [('The start value 1.5 of variable "damping_mode_1" lies outside its declared range [0.0, 1.0] '
                         "(FMI: min <= start <= max).")]
    if fmi_version == 2:  # the FMUs mace-fmu's own commands load (view, simulate)
        with pytest.raises(MaceError, match=re.escape(f"{bad}: {problems[0]}")):
            check_fmu(bad)


def test_a_model_whose_damping_lies_outside_the_declared_range_is_not_exported(modes, tmp_path):
    """A damping table built in Python skips the structure file's check: the exporter still refuses the model."""
    instruments = load_instruments(FRAME / "frame.toml")
    instruments = replace(instruments, damping=replace(instruments.damping, default=1.5))
    model = volts_model(modes, instruments=instruments)
    with pytest.raises(MaceError, match=r"^parameter damping_mode_1 = 1\.5 \(open-loop damping ratio of mode 1: .*\) "
                                        r"lies outside the range its FMU declares, \[0, 1\]: every host would refuse "
                                        r"the FMU$"):
        export_fmu(model, out_dir=tmp_path, name="frame_0g")
    assert not list(tmp_path.glob("*.fmu"))
