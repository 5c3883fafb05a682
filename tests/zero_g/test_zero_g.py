"""The updated nominal 0-g model and its bounds (thesis 5.3) against Table 5.3; the FMU that carries them.

The command line runs once (``mace-fmu predict-0g --json -o DIR --fmu``); the numbers are then read
back from its JSON, its files and the parameter set it wrote, which rebuilds the nominal model through
``volts_model`` from the FE model again: an independent route to the same poles.
"""

from __future__ import annotations

import csv
import json
import subprocess
import sys
import tomllib
from pathlib import Path

import fmpy
import numpy as np
import pytest
from support.fmu_checks import initialised_slave, make_inputs, run_steps, zoh_reference

from mace_fmu.cli import main
from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.export import export_fmu
from mace_fmu.fmu.validation import validate_fmu
from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.parametric_data import parametric_arrays
from mace_fmu.iomodel.pole_pairing import pair_poles
from mace_fmu.iomodel.poles import closed_loop_poles
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.sets import ParameterSet, Provenance
from mace_fmu.zero_g.nominal import BoundRule
from mace_fmu.zero_g.table import beside_table_5_3, bound_text, table_5_3

pytestmark = pytest.mark.slow  # the module predicts the 0-g model and its bounds first (about 17 s)

#: rows whose nominal damping ratio does not reproduce Table 5.3 (docs/guide/zero_g.md, "Updated nominal 0-g model")
DAMPING_NOT_REPRODUCED = {"1st Y bending", "4th Y bending"}


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """(JSON output, output directory) of one predict-0g run with the bundled deck and Table 4.7."""
    out = tmp_path_factory.mktemp("predict_0g")
    done = subprocess.run([sys.executable, "-m", "mace_fmu.cli", "predict-0g", "--json", "-o", str(out), "--fmu"],
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout), out


@pytest.fixture(scope="module")
def nominal(run):
    """The nominal 0-g model rebuilt from the parameter set predict-0g wrote (modes from the FE model again)."""
    return volts_model(compute_modes(configuration="0g", parameters=ParameterSet.read(run[1] / "zero_g_nominal.toml")))


def _rows(run):
    return run[0]["rows"]


def _relative_damping_ok(ours: float, thesis: float) -> bool:
    return abs(ours - thesis) <= 0.005 or abs(ours / thesis - 1) <= 0.10


def test_nominal_model_and_bounds_reproduce_table_5_3(run):
    rows = _rows(run)
    pairs = list(zip(rows, [t for _, t in beside_table_5_3_from_data(rows)]))
    assert [t.label for _, t in pairs] == [t.label for t in table_5_3()]  # every row of Table 5.3, in order
    failed = set()
    for row, ref in pairs:
        assert abs(row["nominal_hz"] / ref.hz - 1) <= 0.01, (row, ref)
        assert bound_text(row["bound_percent"] / 100) == f"{ref.bound_percent:.1f}", (row, ref)
        if not _relative_damping_ok(row["damping"], ref.zeta):
            failed.add(row["label"])
    assert failed == DAMPING_NOT_REPRODUCED


def beside_table_5_3_from_data(rows):
    """beside_table_5_3 on JSON rows (only the label is used for the pairing)."""
    class Row:
        def __init__(self, label):
            self.label = label
    return beside_table_5_3(tuple(Row(r["label"]) for r in rows))


def test_adjusted_modes_move_by_the_residual_1g_ratio_and_heavy_modes_are_left(run):
    for row in _rows(run):
        ratio_hz = row["measured_1g_hz"] / row["model_1g_hz"]
        ratio_zeta = row["measured_1g_damping"] / row["model_1g_damping"]
        assert row["adjusted"] == (row["measured_1g_damping"] < 0.10), row
        if row["adjusted"]:
            assert abs(row["nominal_hz"] / row["unaltered_hz"] / ratio_hz - 1) < 1e-6, row
            if row["damping_reached"]:
                assert abs(row["damping"] / row["unaltered_damping"] / ratio_zeta - 1) < 1e-6, row
            else:  # servo damping alone exceeds the target: the open-loop damping is 0
                assert row["open_loop_damping"] == 0.0 and row["damping"] > row["unaltered_damping"] * ratio_zeta
        else:
            assert row["frequency_scale"] == 1.0
            assert row["bound_percent"] == pytest.approx(2.5, abs=1e-12)


def test_bounds_follow_the_rule_with_its_numbers():
    rule = BoundRule()
    assert rule.bound(heavy=False, frequency_error=-0.0352) == pytest.approx(0.0176, abs=1e-15)
    assert rule.bound(heavy=False, frequency_error=0.004) == 0.01
    assert rule.bound(heavy=True, frequency_error=0.5) == 0.025
    wide = BoundRule(minimum_bound=0.02, error_fraction=1.0, heavy_bound=0.05)
    assert wide.bound(heavy=False, frequency_error=-0.0352) == pytest.approx(0.0352, abs=1e-15)
    assert wide.bound(heavy=False, frequency_error=0.004) == 0.02
    assert wide.bound(heavy=True, frequency_error=0.0) == 0.05
    assert bound_text(0.0105) == "1.1" and bound_text(0.0175) == "1.8" and bound_text(0.01) == "1.0"


def test_files_hold_the_rows_and_the_parameter_set_rebuilds_the_nominal_poles(run, nominal):
    data, out = run
    with open(out / "table_5_3.csv", newline="") as f:
        table = list(csv.DictReader(f))
    toml = tomllib.loads((out / "table_5_3.toml").read_text())
    assert [r["label"] for r in table] == [r["label"] for r in data["rows"]] == [m["label"] for m in toml["mode"]]
    for row, csv_row, toml_row in zip(data["rows"], table, toml["mode"]):
        assert float(csv_row["nominal_hz"]) == row["nominal_hz"] == toml_row["nominal_hz"]
        assert float(csv_row["bound_percent"]) == row["bound_percent"] == toml_row["bound_percent"]
    assert toml["rule"] == {"heavy_damping": 0.1, "minimum_bound": 0.01, "error_fraction": 0.5, "heavy_bound": 0.025,
                            "correct_heavy": False}
    # the set's zero damping of 2nd Y bending says why, where it is read
    written = tomllib.loads((out / "zero_g_nominal.toml").read_text())
    assert written["values"]["damping:2nd Y bending"] == 0.0
    assert "open-loop damping 0 for 2nd Y bending: the servos alone give more closed-loop damping" in \
        written["provenance"]["notes"]
    poles = closed_loop_poles(nominal)
    patterns = [p for p in _zero_g_patterns() if p]
    index = pair_poles([(p, r["nominal_hz"]) for p, r in zip(patterns, data["rows"])], poles)
    for row, i in zip(data["rows"], index):
        assert abs(poles[i].frequency_hz / row["nominal_hz"] - 1) < 1e-9, row
        assert abs(poles[i].damping / row["damping"] - 1) < 1e-7, row


def _zero_g_patterns():
    from mace_fmu.zero_g.nominal import table_4_7_zero_g_patterns

    return table_4_7_zero_g_patterns()


# ---- the FMU that carries the uncertainty ------------------------------------------------------------

@pytest.fixture(scope="module")
def fmus(run, nominal, tmp_path_factory):
    """(native FMU from the command line, pythonfmu FMU of the same model and bounds, extracted folders)."""
    data, out = run
    bounds = {int(k): v for k, v in data["frequency_bounds"].items()}
    native = Path(data["files"]["fmu"])
    python = export_fmu(nominal, out_dir=tmp_path_factory.mktemp("zero_g_python"), name="MACE_0g_nominal_py",
                        arrays=parametric_arrays(nominal, physical=False), frequency_bounds=bounds, runtime="pythonfmu")
    return {kind: (path, fmpy.extract(str(path), unzipdir=str(tmp_path_factory.mktemp(f"unzipped_{kind}"))))
            for kind, path in (("native", native), ("pythonfmu", python))}


def test_fmus_declare_each_bound_as_the_min_max_of_a_frequency_scale(run, fmus):
    data, _ = run
    bounds = {int(k): v for k, v in data["frequency_bounds"].items()}
    assert sorted(bounds) == sorted(r["mode"] for r in data["rows"] if r["mode"] is not None)
    for kind, (path, _) in fmus.items():
        assert validate_fmu(str(path)) == [], kind
        variables = {v.name: v for v in fmpy.read_model_description(str(path)).modelVariables}
        for mode, bound in bounds.items():
            v = variables[f"frequency_scale_mode_{mode}"]
            assert (v.causality, v.variability, float(v.start), v.unit) == ("parameter", "fixed", 1.0, "1"), kind
            assert float(v.min) == 1.0 - bound and float(v.max) == 1.0 + bound, (kind, mode)
        free = [v for n, v in variables.items() if n.startswith("frequency_scale_mode_") and int(n.rsplit("_", 1)[1])
                not in bounds]
        # the others keep the range every frequency scale has (mace_fmu.parameters.kinds), raised for slow modes
        assert free and all(0.1 <= float(v.min) < 1.0 and float(v.max) == 10.0 for v in free), kind


@pytest.mark.parametrize("side", [-1.0, 1.0])
def test_every_scale_at_its_bound_moves_its_open_loop_frequency_by_the_bound(run, nominal, fmus, side):
    bounds = {int(k): v for k, v in run[0]["frequency_bounds"].items()}
    start = {f"frequency_scale_mode_{k}": 1.0 + side * b for k, b in bounds.items()}
    expected = np.array([nominal.plant.frequencies_hz[k - 1] * (1.0 + side * b) for k, b in bounds.items()])
    for kind, (_, folder) in fmus.items():
        fmu = initialised_slave(nominal, folder, start, name=f"all{kind}{side}")
        vr = {v.name: v.valueReference for v in fmpy.read_model_description(folder).modelVariables}
        got = np.array(fmu.getReal([vr[f"frequency_mode_{k}"] for k in bounds]))
        fmu.terminate()
        fmu.freeInstance()
        assert np.max(np.abs(got / expected - 1)) <= 1e-6, kind


def test_fmutool_finds_no_error_in_the_nominal_fmus(fmus):
    fmutool = Path(sys.executable).with_name("fmutool")
    for kind, (path, _) in fmus.items():
        done = subprocess.run([str(fmutool), "-input", str(path), "-check"], capture_output=True, text=True,
                              timeout=300)
        text = done.stdout + done.stderr
        assert "compliant with FMI-2.0" in text and "No semantic error" in text and "ERROR" not in text, (kind, text)


@pytest.mark.parametrize("kind", ["native", "pythonfmu"])
@pytest.mark.parametrize("side", [-1.0, 1.0])
def test_a_scale_at_its_bound_moves_the_mode_by_the_bound_and_matches_the_state_space(run, nominal, fmus, kind,
                                                                                        side):
    """1st Y bending at 1 -+ its bound: the open-loop frequency moves by the bound exactly, the closed-loop pole
    by nearly as much, and the FMU's response is the exact ZOH of volts_model with that scale in the set."""
    data, out = run
    row = next(r for r in data["rows"] if r["label"] == "1st Y bending")
    mode, scale = row["mode"], 1.0 + side * row["bound_percent"] / 100
    path, folder = fmus[kind]
    fmu = initialised_slave(nominal, folder, {f"frequency_scale_mode_{mode}": scale}, name=f"{kind}{side}")
    vr = {v.name: v.valueReference for v in fmpy.read_model_description(folder).modelVariables}
    open_loop = fmu.getReal([vr[f"frequency_mode_{mode}"]])[0]
    assert abs(open_loop / (nominal.plant.frequencies_hz[mode - 1] * scale) - 1) <= 1e-6
    step = 2e-3
    t = np.arange(0.0, 0.6 + step / 2, step)
    u = make_inputs("multisine", t, nominal.system.ninputs)
    y = run_steps(nominal, fmu, folder, t, u)
    fmu.terminate()
    fmu.freeInstance()
    base = ParameterSet.read(out / "zero_g_nominal.toml")
    name = f"frequency_scale:{row['mode_label']}"
    moved = volts_model(compute_modes(configuration="0g", parameters=base.updated({name: base[name] * scale},
                                                      provenance=base.provenance)))
    reference = zoh_reference(moved, t, u)
    span = np.ptp(reference, axis=1, keepdims=True)
    assert np.max(np.abs(y - reference) / span) <= 1e-8
    assert np.max(np.abs(zoh_reference(nominal, t, u) - reference) / span) > 1e-4  # the scale does matter
    pole = min((p for p in closed_loop_poles(moved) if p.mode == mode - 1),
               key=lambda p: abs(p.frequency_hz - row["nominal_hz"] * scale))
    shift = pole.frequency_hz / row["nominal_hz"] - 1
    reported = row["shift_at_upper_bound_percent" if side > 0 else "shift_at_lower_bound_percent"] / 100
    assert abs(shift - reported) < 1e-8  # the shift predict-0g reports, from the rebuild the FMUs do
    assert 0.8 < shift / (scale - 1) < 1.1  # the closed-loop pole follows the open-loop one


# ---- bad input: one line, exit status 2, nothing written ---------------------------------------------

def _measured_csv(path: Path, rows: list[tuple[str, str, float, float, str]], *, column: str = "pattern_0g") -> Path:
    lines = [f"label,pattern,frequency_hz,damping,{column}"] + [",".join(str(x) for x in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


BAD_INPUTS = [
    (["--minimum-bound-percent", "-1"], "argument --minimum-bound-percent: expected a percentage in [0, 100), got '-1'"),
    (["--heavy-bound-percent", "150"], "argument --heavy-bound-percent: expected a percentage in [0, 100), got '150'"),
    (["--error-fraction", "nan"], "argument --error-fraction: expected a finite number >= 0, got 'nan'"),
    (["--heavy-damping", "1.5"], "argument --heavy-damping: expected a fraction in [0, 1), got '1.5'"),
]


@pytest.mark.parametrize("options, message", BAD_INPUTS)
def test_negative_or_absurd_bound_rules_are_refused(options, message, tmp_path, capsys):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as stopped:  # by the parser, before any work
        main(["predict-0g", "-o", str(out), *options])
    assert stopped.value.code == 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == f"mace-fmu predict-0g: error: {message}"
    assert not out.exists()


def test_a_bound_rule_out_of_range_is_refused_by_the_rule_itself():
    from mace_fmu.errors import MaceError
    from mace_fmu.zero_g.nominal import BoundRule

    with pytest.raises(MaceError, match=r"^bound rule: error_fraction = 12.0 must be a number in \[0, 10\)"):
        BoundRule(error_fraction=12.0)


def test_an_updated_nominal_set_is_no_starting_point(run, tmp_path, capsys):
    """Its frequency scales would act on the 1-g model too (thesis 5.3: 1-g frequencies are never adjusted)."""
    out = tmp_path / "out"
    assert main(["predict-0g", "--parameters", str(run[1] / "zero_g_nominal.toml"), "-o", str(out)]) == 2
    assert "predict-0g starts from physical parameters" in capsys.readouterr().err
    assert not out.exists()


def test_a_parameter_file_for_another_deck_is_refused(tmp_path, capsys):
    path = ParameterSet({"E_lexan_center": 2.3e9}, Provenance(created="2026-01-01T00:00:00+00:00", tool="test",
                                                              deck="other.bdf", deck_sha256="0" * 64)).write(
        tmp_path / "other.toml")
    out = tmp_path / "out"
    assert main(["predict-0g", "--parameters", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()[-1]
    assert err.startswith("mace-fmu: error:") and "made for deck 'other.bdf'" in err, err
    assert not out.exists()


@pytest.mark.parametrize("rows, column, message", [
    ([("1st Y bending", "* Y bending", 3.38, 0.038, "* Y bending"), ("nothing", "* X bending", 5.0, 0.02, "")],
     "pattern_0g", "'nothing' (5.000 Hz, pattern '* X bending') pair with no pole of the 1-g model"),
    ([("1st Y bending", "* Y bending", 3.38, 0.038, "* W bending")], "pattern_0g",
     "pair with no pole of the 0-g model"),
    ([("1st Y bending", "* Y bending", 3.38, 0.038, "")], "pattern_0g", "no measured mode has a 0-g counterpart"),
    ([("1st Y bending", "* Y bending", 3.38, 0.038, "* Y bending")], "zero_g", "no column pattern_0g"),
])
def test_measured_modes_that_cannot_be_paired_are_refused(rows, column, message, tmp_path, capsys):
    measured = _measured_csv(tmp_path / "measured.csv", rows, column=column)
    out = tmp_path / "out"
    assert main(["predict-0g", "--measured", str(measured), "-o", str(out), "--fmu"]) == 2
    err = capsys.readouterr().err.splitlines()[-1]
    assert err.startswith("mace-fmu: error:") and message in err, err
    assert not out.exists()


def test_export_with_the_nominal_set_and_bounds_gives_the_same_fmu_variables(run, tmp_path, capsys):
    """`mace-fmu export 0g --parameters zero_g_nominal.toml --frequency-bounds table_5_3.toml` = predict-0g --fmu."""
    _, out = run
    assert main(["export", "0g", "--parameters", str(out / "zero_g_nominal.toml"), "--frequency-bounds",
                 str(out / "table_5_3.toml"), "-o", str(tmp_path)]) == 0
    # named after the set and its bounds, never the plain model's MACE_0g_native.fmu (which `build` writes)
    assert not (tmp_path / "MACE_0g_native.fmu").exists()
    from mace_fmu.parameters.sets import ParameterSet

    digest = ParameterSet.read(out / "zero_g_nominal.toml").digest()[:6]
    exported = {v.name: v for v in fmpy.read_model_description(
        str(tmp_path / f"MACE_0g_native_zero_g_nominal_{digest}_bounded.fmu")).modelVariables}
    predicted = {v.name: v for v in fmpy.read_model_description(
        str(out / "MACE_0g_native_nominal.fmu")).modelVariables}
    assert exported.keys() == predicted.keys()
    for name, v in predicted.items():
        if v.causality == "parameter":
            assert (exported[name].start, exported[name].min, exported[name].max) == (v.start, v.min, v.max), name
    # bounds made for another model (modes up to 30 Hz only): refused before anything is written
    assert main(["export", "0g", "--max-hz", "30", "--frequency-bounds", str(out / "table_5_3.toml"), "-o",
                 str(tmp_path / "other")]) == 2
    assert "no such mode" in capsys.readouterr().err
    assert not (tmp_path / "other").exists()


def test_scales_outside_their_bounds_are_named_by_the_rebuild_the_pythonfmu_slave_checks(run, nominal):
    """The pythonfmu slave refuses what ParametricSystem.parameter_problems names (the native runtime: test_native_fmu)."""
    bounds = {int(k): v for k, v in run[0]["frequency_bounds"].items()}
    system = ParametricSystem(parametric_arrays(nominal, physical=False, frequency_bounds=bounds))
    mode, bound = next(iter(bounds.items()))
    name = f"frequency_scale_mode_{mode}"
    for value, reason in ((1.0 + 1.01 * bound, "outside its declared range"),
                          (1.0 - 1.01 * bound, "outside its declared range"),
                          (1.0 + bound, None)):
        params = system.nominal.copy()
        params[system.index(name)] = value
        problems = system.parameter_problems(params)
        assert (problems == []) if reason is None else (len(problems) == 1 and name in problems[0]
                                                         and reason in problems[0]), problems
    free = next(n for n in system.parameter_names if n.startswith("frequency_scale_mode_")
                and int(n.rsplit("_", 1)[1]) not in bounds)
    params = system.nominal.copy()
    params[system.index(free)] = 0.0  # below every scale's own minimum (0.1: mace_fmu.parameters.kinds)
    assert system.parameter_problems(params) == [f"{free} = 0 is outside its declared range [0.1, 10]"]


def test_a_1g_parameter_set_from_an_update_is_carried_to_0g(run):
    """A set like `mace-fmu update` writes (1-g provenance, a modulus, damping of suspension modes the 0-g
    structure lacks): the modulus reaches the 0-g modes, the 1-g-only damping is dropped, the deck is kept."""
    from mace_fmu.parameters.sets import deck_fingerprint, parameter_kind
    from mace_fmu.structure.file import bundled_deck_path
    from mace_fmu.zero_g.nominal import predict_zero_g

    deck = bundled_deck_path()
    start = ParameterSet({"E_lexan_center": 2.3e9, "damping:Y suspension twist (Y rotation)": 0.09,
                          "damping:1st Z bending": 0.02},
                         Provenance(created="2026-01-01T00:00:00+00:00", tool="test", deck=deck.name,
                                    deck_sha256=deck_fingerprint(deck), configuration="1g"))
    steps = []
    prediction = predict_zero_g(parameters=start, progress=steps.append)
    assert [(s.task, s.done, s.total) for s in steps] == [
        ("1-g closed-loop model and the residual errors", 0, 4), ("0-g closed-loop model", 1, 4),
        (f"adjusting {sum(r.adjusted for r in prediction.rows)} open-loop 0-g modes", 2, 4),
        ("updated nominal 0-g model", 3, 4)]
    values = prediction.parameters.values
    assert values["E_lexan_center"] == 2.3e9 and "damping:Y suspension twist (Y rotation)" not in values
    assert {parameter_kind(n) for n in values} == {"modulus", "damping", "frequency_scale"}
    prov = prediction.parameters.provenance
    assert (prov.configuration, prov.deck_sha256) == ("0g", deck_fingerprint(deck))
    default = {r["label"]: r for r in _rows(run)}
    first = next(r for r in prediction.rows if r.label == "1st Y bending")
    assert abs(first.unaltered_hz / default["1st Y bending"]["unaltered_hz"] - 1) > 1e-4  # the modulus acts in 0-g
    assert abs(first.nominal_hz / first.unaltered_hz / (first.measured_1g_hz / first.model_1g_hz) - 1) < 1e-6


def test_a_1g_set_by_mode_number_predicts_as_the_same_set_by_label():
    """An FMU update's 1-g set names modes by the 1-g FMU's numbers (``damping_mode_<k>``); predict-0g takes each
    as its label in the 1-g structure (numbers count other modes in 0-g), so the prediction is the set's by label:
    the same rows, the same nominal 0-g set, the 1-g-only suspension damping dropped."""
    from mace_fmu.zero_g.nominal import predict_zero_g

    provenance = Provenance(created="2026-01-01T00:00:00+00:00", tool="test", configuration="1g")
    damping = {"Y suspension twist (Y rotation)": 0.09, "1st Z bending": 0.02}
    labels = compute_modes(configuration="1g").labels  # predict-0g's 1-g structure: the bundled deck's, large preload
    by_number = {"E_lexan_center": 2.3e9, **{f"damping_mode_{labels.index(x) + 1}": z for x, z in damping.items()}}
    by_label = {"E_lexan_center": 2.3e9, **{f"damping:{x}": z for x, z in damping.items()}}
    number, label = (predict_zero_g(parameters=ParameterSet(values, provenance)) for values in (by_number, by_label))
    assert number.rows == label.rows
    assert dict(number.parameters.values) == dict(label.parameters.values)
    assert "damping:1st Z bending" in number.parameters.values  # by label: the 0-g structure numbers it otherwise
    assert "damping:Y suspension twist (Y rotation)" not in number.parameters.values  # no such 0-g mode
    assert not [n for n in number.parameters.values if n.startswith("damping_mode_")]


def test_frequency_scales_of_a_0g_set_leave_a_1g_model_alone(run, nominal):
    """scale_frequencies applies a set's scales to the structure its provenance names, and only to that one."""
    from mace_fmu.iomodel.volts import scale_frequencies

    nominal_set = ParameterSet.read(run[1] / "zero_g_nominal.toml")
    modes = nominal.structure_modes
    assert scale_frequencies(modes, nominal_set, configuration="1g") is modes
    label, factor = next((n.split(":", 1)[1], v) for n, v in nominal_set.values.items()
                         if n.startswith("frequency_scale:"))
    scaled = scale_frequencies(modes, nominal_set, configuration="0g")
    k = modes.labels.index(label)
    assert scaled.frequencies_hz[k] == modes.frequencies_hz[k] * factor
    others = np.array([n for n in range(len(modes.labels))
                       if f"frequency_scale:{modes.labels[n]}" not in nominal_set])
    assert np.array_equal(scaled.frequencies_hz[others], modes.frequencies_hz[others])
