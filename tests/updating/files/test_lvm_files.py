"""LabVIEW measurement files (.lvm) read as they come: channel names and units from the header,
through the channel map, times from the header's X0 and Delta_X; errors that name the file, the line and the
channel.

Two files are lvm_read's own test data (tests/data/lvm/provenance.toml), their numbers read off the files' text
by eye; the others are written here as LabVIEW writes them (tests/support/lvm_files.py).
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
from support.cli import run_cli
from support.lvm_files import write_lvm
from support.paths import ROOT

from mace_fmu.errors import MaceError
from mace_fmu.updating.files import read_channel_map, read_measured_data, read_time_history

DATA = ROOT / "tests" / "data" / "lvm"
MAP = "channel,signal,role,unit\n{rows}\n"


def _map(tmp_path, rows: str, name: str = "map.csv"):
    path = tmp_path / name
    path.write_text(MAP.format(rows=rows))
    return read_channel_map(path)


def _error(call) -> str:
    with pytest.raises(MaceError) as caught:
        call()
    return str(caught.value)


def test_the_files_are_lvm_read_s_unedited():
    import tomllib

    files = tomllib.loads((DATA / "provenance.toml").read_text())["files"]
    for name, entry in files.items():
        body = (DATA / name).read_bytes()
        assert hashlib.sha1(b"blob %d\0" % len(body) + body).hexdigest() == entry["blob"], name


def test_a_labview_file_without_a_time_column_and_with_decimal_commas(tmp_path):
    """short.lvm: Delta_X 3,906250E-5 s, no X column, the first row 0,914018 N and 1,204792 m/s^2; its units
    "Newtons" read as N."""
    channels = _map(tmp_path, "Excitation (Trigger),force,input,N\nResponse (Trigger),acc,output,m/s^2")
    history = read_measured_data(DATA / "short.lvm", channel_map=channels)
    assert history.units == {"force": "N", "acc": "m/s^2"}
    np.testing.assert_array_equal(history.times_s, np.arange(10) * 3.90625e-5)
    assert history.inputs["force"][[0, 9]].tolist() == [0.914018, 0.680572]
    assert history.outputs["acc"][[0, 9]].tolist() == [1.204792, 1.212775]


def test_a_labview_file_with_a_time_column_per_channel(tmp_path):
    """multi_time_column.lvm: X_Value before each channel, Delta_X 1.953125E-5 s, units Volts (V) and g."""
    channels = _map(tmp_path, "Voltage,u,input,V\nAcceleration,y,output,g")
    history = read_measured_data(DATA / "multi_time_column.lvm", channel_map=channels)
    assert history.units == {"u": "V", "y": "g"}
    np.testing.assert_array_equal(history.times_s, np.arange(3) * 1.953125e-5)
    assert history.inputs["u"].tolist() == [-0.035229, -0.034882, -0.034191]
    assert history.outputs["y"].tolist() == [0.532608, 0.502991, 0.467541]


def _record(samples: int = 2000, dt: float = 1.0 / 2048):
    """A 2048 Hz record: its six-decimal X column is off the sample grid by up to 2.4e-7 s (not uniform to 1e-6)."""
    rng = np.random.default_rng(48)
    t = np.arange(samples) * dt
    return t, {"Dev1/ai0": ("Newtons", rng.standard_normal(samples)),
               "Dev1/ai1": ("m/s^2", rng.standard_normal(samples)),
               "Dev1/ai2": ("m/s^2", rng.standard_normal(samples)),
               "Dev1/ai7": ("Deg C", 21.0 + 0.01 * rng.standard_normal(samples))}


ROWS = "Dev1/ai0,force_floor_1,input,N\nDev1/ai1,acc_floor_1,output,m/s^2\nDev1/ai2,acc_floor_2,output,m/s^2\n" \
       "Dev1/ai7,,ignore,Deg C"


@pytest.mark.parametrize("layout", [dict(), dict(segments=3), dict(x_columns="No"), dict(x_columns="Multi"),
                                    dict(decimal=",")])
def test_a_record_as_labview_writes_it_reads_back_through_the_channel_map(tmp_path, layout):
    t, channels = _record()
    path = write_lvm(tmp_path / "run.lvm", t, channels, **layout)
    history = read_time_history(path, channel_map=_map(tmp_path, ROWS), sample_time_s=1.0 / 2048)
    assert history.units == {"force_floor_1": "N", "acc_floor_1": "m/s^2", "acc_floor_2": "m/s^2"}
    np.testing.assert_allclose(history.times_s, t, rtol=0, atol=1e-12)  # X0 + k Delta_X, not the X column
    for signal, channel in (("force_floor_1", "Dev1/ai0"), ("acc_floor_1", "Dev1/ai1")):
        table = history.inputs if signal.startswith("force") else history.outputs
        np.testing.assert_allclose(table[signal], channels[channel][1], rtol=1e-8)


def test_data_check_reads_an_lvm_file_on_the_command_line(tmp_path, capsys):
    t, channels = _record()
    path = write_lvm(tmp_path / "run.lvm", t, channels)
    (tmp_path / "map.csv").write_text(MAP.format(rows=ROWS))
    code, out, err = run_cli(capsys, ["data", "check", str(path), "--map", str(tmp_path / "map.csv")])
    assert code == 0, err
    assert "time history: 2000 samples, 0 to 0.976074219 s, sample time 0.00048828125 s (2048 Hz)" in out
    assert "inputs: force_floor_1 [N]" in out and "outputs: acc_floor_1 [m/s^2], acc_floor_2 [m/s^2]" in out


def test_errors_name_the_file_the_line_and_the_channel(tmp_path):
    t, channels = _record(samples=50)
    names = _map(tmp_path, ROWS)
    header = 23  # the line of names: 13 lines of file header, 9 of segment header
    bad = write_lvm(tmp_path / "bad.lvm", t, channels, cells={(7, "Dev1/ai1"): "1.2x"})
    assert _error(lambda: read_time_history(bad, channel_map=names)) == \
        f"{bad}:{header + 8}: channel 'Dev1/ai1': '1.2x' is not a number"
    empty = write_lvm(tmp_path / "empty.lvm", t, channels, cells={(3, "Dev1/ai0"): ""})
    assert _error(lambda: read_time_history(empty, channel_map=names)) == \
        f"{empty}:{header + 4}: channel 'Dev1/ai0': an empty cell is not a number"
    volts = _map(tmp_path, ROWS.replace("force_floor_1,input,N", "force_floor_1,input,V"), name="volts.csv")
    assert _error(lambda: read_time_history(bad, channel_map=volts)) == \
        f"{bad}:{header}: channel 'Dev1/ai0': unit 'N', expected 'V' (channel map {tmp_path / 'volts.csv'}:2)"
    assert _error(lambda: read_time_history(bad)) == (
        f"{bad}:{header}: channel 'Dev1/ai0': no role; give a channel map (--map CSV with columns channel, signal, "
        "role, unit) or name the channel 'in:Dev1/ai0' or 'out:Dev1/ai0' in LabVIEW")
    missing = _map(tmp_path, ROWS.replace("Dev1/ai2", "Dev1/ai3"), name="missing.csv")
    assert "channel 'Dev1/ai2' is not in the channel map" in _error(lambda: read_time_history(bad, channel_map=missing))
    # a sample the header's clock did not take: the X column 1 ms off at sample 5
    shifted = t.copy()
    shifted[5] += 1e-3
    write_lvm(tmp_path / "clock.lvm", shifted, channels)
    assert _error(lambda: read_time_history(tmp_path / "clock.lvm", channel_map=names)).startswith(
        f"{tmp_path / 'clock.lvm'}:{header + 6}: channel 'time': X_Value 0.003441 s, but the header's X0 and Delta_X "
        "(0.00048828125 s) put this sample at 0.00244140625 s")
    not_lvm = tmp_path / "run.lvm"
    not_lvm.write_text("time [s],in:u [V]\n0,1\n")
    assert _error(lambda: read_time_history(not_lvm)) == (
        f"{not_lvm}:1: not a LabVIEW measurement file (its first line is 'time [s],in:u [V]', expected 'LabVIEW "
        "Measurement')")


def test_a_channel_without_a_unit_takes_the_map_s_and_without_a_map_is_refused(tmp_path):
    t, channels = _record(samples=20)
    path = write_lvm(tmp_path / "plain.lvm", t, channels)
    path.write_text("\n".join(line for line in path.read_text().splitlines() if not line.startswith("Y_Unit_Label")))
    history = read_time_history(path, channel_map=_map(tmp_path, ROWS))
    assert history.units == {"force_floor_1": "N", "acc_floor_1": "m/s^2", "acc_floor_2": "m/s^2"}
    renamed = path.read_text().replace("Dev1/ai0", "in:force").replace("Dev1/ai1", "out:acc")
    path.write_text(renamed)
    assert _error(lambda: read_time_history(path)) == (
        f"{path}:22: channel 'force' has no unit in the header (no Y_Unit_Label): give a channel map (--map) that "
        "states each channel's unit")


def _keep_every(path, step: int, *, samples: int | None = None):
    """``path`` as a file resampled after LabVIEW wrote it: every ``step``-th data row kept, the header as it was
    (or its ``Samples`` set to ``samples``)."""
    head, _, body = path.read_text().partition("X_Value")
    names, *rows = body.splitlines()
    if samples is not None:
        head = "\n".join("\t".join(["Samples"] + [str(samples)] * (len(line.split("\t")) - 2) + [""])
                         if line.startswith("Samples") else line for line in head.splitlines()) + "\n"
    path.write_text(head + "X_Value" + names + "\n" + "\n".join(rows[::step]) + "\n")
    return path


def test_a_file_resampled_after_labview_wrote_it_takes_the_time_column_s_clock(tmp_path):
    """A public record's downsampled files keep the original header (Delta_X 1.953125e-5 s, Samples 1050000) over
    every 128th row (X column 0.0025 s steps): read as the X column's clock, not the header's (which refused the
    file, saying its samples were not a uniform clock's). The same disagreement under a header whose Samples is the
    file's own row count is refused, naming both clocks."""
    t, channels = _record(samples=400)
    names = _map(tmp_path, ROWS)
    path = _keep_every(write_lvm(tmp_path / "down.lvm", t, channels), 4)
    history = read_time_history(path, channel_map=names)
    assert history.times_s.size == 100
    np.testing.assert_allclose(np.diff(history.times_s), 4 / 2048, rtol=1e-4)
    np.testing.assert_allclose(history.inputs["force_floor_1"], channels["Dev1/ai0"][1][::4], rtol=1e-8)
    own = _keep_every(write_lvm(tmp_path / "own.lvm", t, channels), 4, samples=100)
    message = _error(lambda: read_time_history(own, channel_map=names))
    assert message.endswith(
        "the X column is a uniform clock of 0.00195312 s (512 Hz), the header's Delta_X 0.00048828125 s (2048 Hz), "
        "and the header (Samples 100, the rows it has) gives no sign of being another record's: one of them is "
        "wrong; correct Delta_X, or write the file without an X column if the header is right")


def test_pounds_and_g_are_read_as_newtons_and_m_s2_when_the_map_says_so(tmp_path):
    """Dataset-4's shaker record (examples/shaker_beam/data, unedited): channels Force [Pounds] and Acceleratio [g],
    the first data row 0.000000, -0.170586, -3.399325, -0.016694 and the last 19.700000 s, read by eye. With the
    map's N and m/s^2: x 4.4482216152605 (the international pound-force) and x 9.80665 (standard gravity); with the
    map's own labels they are kept."""
    from support.paths import EXAMPLES

    data = EXAMPLES / "shaker_beam" / "data"
    history = read_time_history(data / "data_set_1_downsampled_by_128.lvm", channel_map=read_channel_map(
        data / "channels.csv"))
    assert history.units == {"force_shaker": "N", "acc_beam": "m/s^2"}
    assert history.times_s.size == 7881 and history.times_s[-1] == pytest.approx(19.7, abs=1e-9)
    assert history.inputs["force_shaker"][0] == pytest.approx(-3.399325 * 4.4482216152605, rel=1e-12)
    assert history.outputs["acc_beam"][0] == pytest.approx(-0.016694 * 9.80665, rel=1e-12)
    kept = _map(tmp_path, "Voltage,,ignore,V\nForce,f,input,Pounds\nAcceleratio,a,output,g")
    raw = read_time_history(data / "data_set_1_downsampled_by_128.lvm", channel_map=kept)
    assert raw.units == {"f": "Pounds", "a": "g"} and raw.inputs["f"][0] == -3.399325
