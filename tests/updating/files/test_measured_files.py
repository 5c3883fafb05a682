"""Measured data files (CSV, npz, UFF58): round trips, the H1 estimate against exact responses, bad data.

H1 references are independent: the exact discrete-time response C (zI - A)^-1 B + D of the
zero-order-hold system at z = exp(j 2 pi f dt), with the records simulated by ``scipy.signal.lfilter``.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy import signal
from support.paths import EXAMPLES

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory
from mace_fmu.updating.files import (Channel, ChannelMap, h1_estimate, read_channel_map, read_frequency_response,
                                     read_measured_data, read_time_history, write_frequency_response,
                                     write_time_history)

FS_HZ = 100.0
DT_S = 1.0 / FS_HZ


def _history(n: int = 200, *, seed: int = 0) -> TimeHistory:
    rng = np.random.default_rng(seed)
    # Times as a data logger writes them (k * dt, not exactly representable): the CSV must keep every bit.
    return TimeHistory(np.arange(n) * DT_S, {"gimbal_primary_x": rng.standard_normal(n)},
                       {"gyro_bus_x": rng.standard_normal(n), "gyro_payload_z": 1e-7 * rng.standard_normal(n)},
                       source="simulated")


def _frd(seed: int = 0) -> MeasuredFrf:
    rng = np.random.default_rng(seed)
    f = np.sort(rng.uniform(0.1, 40.0, 37))
    h = rng.standard_normal((37, 2, 3)) + 1j * rng.standard_normal((37, 2, 3))
    return MeasuredFrf(f, ("gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_z"),
                                 ("gyro_bus_x", "gyro_payload_z"), h * np.logspace(-6, 2, 37)[:, None, None])


def _same_history(a: TimeHistory, b: TimeHistory) -> None:
    assert np.array_equal(a.times_s, b.times_s)
    assert list(a.inputs) == list(b.inputs) and list(a.outputs) == list(b.outputs)
    for name in a.inputs:
        assert np.array_equal(a.inputs[name], b.inputs[name])
    for name in a.outputs:
        assert np.array_equal(a.outputs[name], b.outputs[name])
    assert a.units == b.units


# --- round trips -------------------------------------------------------------------------------

@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_time_history_round_trip_is_exact(tmp_path, suffix):
    history = _history()
    path = write_time_history(history, tmp_path / f"run{suffix}")
    back = read_time_history(path, sample_time_s=DT_S)
    _same_history(history, back)
    assert back.source == str(path)
    assert isinstance(read_measured_data(path), TimeHistory)


def test_time_history_csv_layout(tmp_path):
    path = write_time_history(_history(3), tmp_path / "run.csv")
    lines = path.read_text().splitlines()
    assert lines[0] == "time [s],in:gimbal_primary_x [V],out:gyro_bus_x [V],out:gyro_payload_z [V]"
    assert lines[2].split(",")[0] == "0.01" and len(lines) == 4


def test_frequency_response_csv_round_trip_is_exact(tmp_path):
    frd = _frd()
    path = write_frequency_response(frd, tmp_path / "frf.csv")
    back = read_frequency_response(path)
    assert np.array_equal(back.frequencies_hz, frd.frequencies_hz)
    assert np.array_equal(back.response, frd.response)
    assert (back.inputs, back.outputs, back.units) == (frd.inputs, frd.outputs, frd.units)
    assert path.read_text().splitlines()[0].split(",")[:3] == [
        "frequency [Hz]", "re:gyro_bus_x/gimbal_primary_x [V/V]", "im:gyro_bus_x/gimbal_primary_x [V/V]"]
    assert isinstance(read_measured_data(path), MeasuredFrf)


def test_h1_with_coherence_round_trips_through_csv(tmp_path):
    frd = h1_estimate(_history(400), segment_length=64, band_hz=(5.0, 40.0))
    path = write_frequency_response(frd, tmp_path / "h1.csv")
    back = read_frequency_response(path)
    assert np.array_equal(back.coherence, frd.coherence) and np.array_equal(back.response, frd.response)
    # 400 samples in half-overlapping 64-sample segments: 1 + (400 - 64) // 32 = 11 averages, stated and read back
    assert frd.averages == back.averages == 11
    first, header = path.read_text().splitlines()[:2]
    assert first == "# averages = 11"
    assert header.endswith(",coherence:gyro_bus_x [1],coherence:gyro_payload_z [1]")


@pytest.mark.parametrize("suffix", [".csv", ".uff"])
def test_the_averages_travel_with_the_file_and_a_bad_count_names_its_line(tmp_path, suffix):
    """The coherence's noise needs the averages: written and read back by both formats; a file's own count that
    is no whole number >= 1 is refused at its line (CSV) or dataset (UFF)."""
    frd = h1_estimate(_history(400), segment_length=64, band_hz=(5.0, 40.0))
    path = write_frequency_response(frd, tmp_path / f"h1{suffix}")
    assert read_frequency_response(path).averages == 11
    text = path.read_text()
    bad = text.replace("averages = 11", "averages = 2.5") if suffix == ".csv" else text.replace("averages: 11",
                                                                                                 "averages: 0 ")
    path.write_text(bad)
    with pytest.raises(MaceError, match=r"(h1\.csv:1|dataset 1 \(ID line 3\)): averages '(2\.5|0)', expected a whole "
                                        r"number >= 1"):
        read_frequency_response(path)


@pytest.mark.parametrize("suffix", [".uff", ".unv"])
def test_frequency_response_uff58_round_trip_to_the_digits_the_format_keeps(tmp_path, suffix):
    """Dataset 58 stores frequencies as E13.5 (6 significant digits), values as E20.11 (12 digits)."""
    frd = _frd()
    path = write_frequency_response(frd, tmp_path / f"frf{suffix}")
    back = read_frequency_response(path)
    assert (back.inputs, back.outputs, back.units) == (frd.inputs, frd.outputs, frd.units)
    # half a unit in the 6th (12th) significant digit, relative to the leading digit (>= 1)
    assert np.max(np.abs(back.frequencies_hz / frd.frequencies_hz - 1)) <= 5e-6
    for part in (np.real, np.imag):
        assert np.max(np.abs(part(back.response) / part(frd.response) - 1)) <= 5e-11 + 1e-15
    import pyuff
    datasets = pyuff.UFF(str(path)).read_sets()
    assert len(datasets) == 6 and {d["func_type"] for d in datasets} == {4}
    assert (datasets[1]["id4"], datasets[1]["id5"]) == ("output: gyro_bus_x", "input: gimbal_primary_z")
    assert isinstance(read_measured_data(path), MeasuredFrf)


def test_uff_writer_refuses_frequencies_the_format_would_merge(tmp_path):
    frd = MeasuredFrf(np.array([1.0, 1.000001, 2.0]), ("u",), ("y",), np.ones((3, 1, 1)))
    with pytest.raises(MaceError, match=r"frf.uff: frequencies 1.0 and 1.000001 Hz \(rows 0, 1\)"):
        write_frequency_response(frd, tmp_path / "frf.uff")
    assert not (tmp_path / "frf.uff").exists()


def _lab_uff(path, *, nan: bool = False, units: str = "V") -> None:
    """A UFF file as modal-test software writes it: channels named by node and direction only."""
    import pyuff
    f = np.linspace(1.0, 10.0, 10)
    datasets = []
    for ref_node, ref_dir in ((1, 3), (2, -1)):
        h = (ref_node + 1j) * f / 10
        datasets.append(pyuff.prepare_58(
            binary=0, func_type=4, rsp_node=101, rsp_dir=3, ref_node=ref_node, ref_dir=ref_dir, data=h, x=f,
            abscissa_spacing=1, abscissa_spec_data_type=18, ordinate_spec_data_type=1, orddenom_spec_data_type=1,
            ordinate_axis_units_lab=units, orddenom_axis_units_lab="V", abscissa_axis_units_lab="Hz"))
    pyuff.UFF(str(path)).write_sets(datasets, mode="overwrite")
    if nan:  # pyuff writes NaN as 0: put the NaN in the text, at row 4 of dataset 2
        text = path.read_text()
        row = "   1.00000000000e+00   5.00000000000e-01"  # (2 + 1j) * 5 / 10
        assert text.count(row) == 1
        path.write_text(text.replace(row, "                 nan   5.00000000000e-01"))


def _write_map(path, rows: str) -> ChannelMap:
    path.write_text("channel,signal,role,unit\n" + rows)
    return read_channel_map(path)


def test_uff_from_a_lab_read_through_a_channel_map(tmp_path):
    _lab_uff(tmp_path / "lab.unv")
    cmap = _write_map(tmp_path / "map.csv", "101+Z,gyro_bus_z,output,V\n1+Z,gimbal_primary_z,input,V\n"
                                            "2-X,gimbal_secondary_x,input,V\n")
    frd = read_frequency_response(tmp_path / "lab.unv", channel_map=cmap)
    assert frd.outputs == ("gyro_bus_z",) and frd.inputs == ("gimbal_primary_z", "gimbal_secondary_x")
    f = np.linspace(1.0, 10.0, 10)
    assert np.allclose(frd.frequencies_hz, f, rtol=5e-6, atol=0)
    assert np.allclose(frd.response[:, 0, 0], (2 + 1j) * f / 10 - f / 10, rtol=1e-11)  # (1 + 1j) f / 10
    assert np.allclose(frd.response[:, 0, 1], (2 + 1j) * f / 10, rtol=1e-11)


def test_ignored_channels_drop_their_frequency_responses(tmp_path):
    _lab_uff(tmp_path / "lab.uff")
    cmap = _write_map(tmp_path / "map.csv", "101+Z,gyro_bus_z,output,V\n1+Z,gimbal_primary_z,input,V\n"
                                            "2-X,,ignore,V\n")
    frd = read_frequency_response(tmp_path / "lab.uff", channel_map=cmap)
    assert frd.inputs == ("gimbal_primary_z",) and frd.response.shape == (10, 1, 1)
    csv_path = write_frequency_response(read_frequency_response(tmp_path / "lab.uff", channel_map=_write_map(
        tmp_path / "names.csv", "101+Z,y,output,V\n1+Z,u1,input,V\n2-X,u2,input,V\n")), tmp_path / "lab.csv")
    cmap = _write_map(tmp_path / "csv_map.csv", "y,gyro_bus_z,output,V\nu1,,ignore,V\nu2,gimbal_secondary_x,input,V\n")
    frd = read_frequency_response(csv_path, channel_map=cmap)
    assert frd.inputs == ("gimbal_secondary_x",)
    assert np.allclose(frd.response[:, 0, 0], frd.frequencies_hz * (0.2 + 0.1j))


def test_time_history_through_a_channel_map(tmp_path):
    (tmp_path / "daq.csv").write_text(
        "# exported by the lab's logger\n"
        "time [s],ai0 [V],ai1 [V],ai7 [degC]\n"
        "0,1,2,20\n0.01,3,4,20\n\n0.02,5,6,21\n")
    cmap = _write_map(tmp_path / "map.csv", "ai0,gimbal_primary_x,input,V\nai1,gyro_bus_x,output,V\n"
                                            "ai7,,ignore,degC\n")
    history = read_time_history(tmp_path / "daq.csv", channel_map=cmap, sample_time_s=0.01)
    assert np.array_equal(history.inputs["gimbal_primary_x"], [1.0, 3.0, 5.0])
    assert np.array_equal(history.outputs["gyro_bus_x"], [2.0, 4.0, 6.0])
    assert list(history.outputs) == ["gyro_bus_x"] and cmap.inputs == ("gimbal_primary_x",)


def test_other_units_travel_with_the_data(tmp_path):
    history = TimeHistory(np.arange(4.0), {"force_1": np.ones(4)}, {"displacement_1": np.zeros(4)},
                          units={"force_1": "N", "displacement_1": "m"})
    path = write_time_history(history, tmp_path / "two_mass.npz")
    assert read_time_history(path).units == {"force_1": "N", "displacement_1": "m"}  # checked where they meet a model
    # with a map, an in:/out: prefix is a role the map must agree with; the name after it is the channel
    cmap = ChannelMap((Channel("force_1", "force_1", "input", "N"), Channel("displacement_1", "displacement_1",
                                                                           "output", "m")))
    _same_history(history, read_time_history(path, channel_map=cmap))
    assert read_time_history(path, channel_map=cmap).units == {"force_1": "N", "displacement_1": "m"}
    swapped = ChannelMap((Channel("force_1", "force_1", "output", "N"), Channel("displacement_1", "displacement_1",
                                                                               "input", "m")))
    with pytest.raises(MaceError, match=r"two_mass.npz: channel 'force_1' is marked input, the channel map "
                                        r"<memory> says output"):
        read_time_history(path, channel_map=swapped)


# --- H1 -----------------------------------------------------------------------------------------

def _exact(ad, bd, cd, dd, f_hz):
    """C (zI - A)^-1 B + D at z = exp(j 2 pi f dt): (k, output, input)."""
    eye = np.eye(ad.shape[0])
    return np.array([cd @ np.linalg.solve(z * eye - ad, bd) + dd for z in np.exp(2j * np.pi * f_hz * DT_S)])


def _simulate(ad, bd, cd, dd, u):
    """Outputs of the discrete system for inputs u (n, m), one lfilter per input/output pair."""
    y = np.zeros((u.shape[0], cd.shape[0]))
    for j in range(u.shape[1]):
        b, a = signal.ss2tf(ad, bd, cd, dd, input=j)
        for i in range(cd.shape[0]):
            y[:, i] += signal.lfilter(b[i], a, u[:, j])
    return y


def _oscillator(fn_hz=5.0, zeta=0.05):
    w = 2 * np.pi * fn_hz
    a = np.array([[0.0, 1.0], [-w * w, -2 * zeta * w]])
    return signal.cont2discrete((a, np.array([[0.0], [w * w]]), np.array([[1.0, 0.0]]), np.zeros((1, 1))), DT_S,
                                method="zoh")[:4]


#: two masses (1, 0.5 kg) on springs 4000, 2500 N/m, dampers 6, 3 N s/m; forces on both, both displacements
M1, M2, K1, K2, C1, C2 = 1.0, 0.5, 4000.0, 2500.0, 6.0, 3.0


def _two_mass():
    m = np.diag([M1, M2])
    k = np.array([[K1 + K2, -K2], [-K2, K2]])
    c = np.array([[C1 + C2, -C2], [-C2, C2]])
    mi = np.linalg.inv(m)
    a = np.block([[np.zeros((2, 2)), np.eye(2)], [-mi @ k, -mi @ c]])
    b = np.vstack([np.zeros((2, 2)), mi])
    return a, signal.cont2discrete((a, b, np.hstack([np.eye(2), np.zeros((2, 2))]), np.zeros((2, 2))), DT_S,
                                   method="zoh")[:4]


def test_h1_of_periodic_noise_is_the_exact_response():
    """Periodic excitation, one period per segment, rectangular window: no leakage, H1 = H at every bin."""
    sys_d = _oscillator()
    segment = 512
    period = np.random.default_rng(2).standard_normal(segment)
    u = np.tile(period, 12)
    y = _simulate(*sys_d, u[:, None])[:, 0]
    keep = slice(4 * segment, None)  # the transient has decayed by exp(-zeta w 4 T) = exp(-32)
    history = TimeHistory(np.arange(u[keep].size) * DT_S, {"u": u[keep]}, {"y": y[keep]})
    frd = h1_estimate(history, segment_length=segment, window="boxcar", overlap=0.0)
    assert np.allclose(frd.frequencies_hz, np.arange(1, segment // 2 + 1) * FS_HZ / segment)
    exact = _exact(*sys_d, frd.frequencies_hz)
    assert np.max(np.abs(frd.response - exact) / np.abs(exact)) < 1e-9
    assert np.min(frd.coherence) > 1 - 1e-9
    assert "512-sample segments" in frd.source and "boxcar window" in frd.source and "0% overlap" in frd.source


def test_h1_single_input_agrees_with_the_scalar_welch_ratio():
    sys_d = _oscillator()
    rng = np.random.default_rng(3)
    u = rng.standard_normal(4096)
    history = TimeHistory(np.arange(u.size) * DT_S, {"u": u}, {"y": _simulate(*sys_d, u[:, None])[:, 0]})
    ours = h1_estimate(history, segment_length=256, band_hz=(1.0, 30.0))
    # the scalar route, computed apart: S_uy / S_uu from scipy's csd and welch
    f, s_uy = signal.csd(history.inputs["u"], history.outputs["y"], fs=1 / DT_S, nperseg=256, window="hann")
    _, s_uu = signal.welch(history.inputs["u"], fs=1 / DT_S, nperseg=256, window="hann")
    keep = (f >= 1.0) & (f <= 30.0)
    assert np.array_equal(ours.frequencies_hz, f[keep])
    assert np.allclose(ours.response[:, 0, 0], (s_uy / s_uu)[keep], rtol=1e-12, atol=0)


@pytest.mark.parametrize("correlated", [False, True])
def test_matrix_h1_recovers_both_columns_of_a_two_input_system(correlated):
    """White noise on both masses; H1 = S_yu S_uu^-1 against the exact response, away from modes and zeros.

    Noise-free data: the error is the leakage of the finite Hann segments (2048 samples, 0.049 Hz),
    largest next to the lightly damped modes (7.36 Hz, zeta 3.3 %; 15.4 Hz, 6.2 %). One hertz
    (two half-power bandwidths and more) from every pole and antiresonance the measured error is
    at most 1.35 %; the tolerance is 2 %. With correlated inputs (correlation rho = 0.8) the scalar
    S_uy / S_uu is off by the other input's share, which the matrix form removes; inverting S_uu
    amplifies the leakage error by about 1 / (1 - rho^2) = 2.8 (measured 3.4 %): tolerance 2 % * 2.8.
    """
    a, sys_d = _two_mass()
    rng = np.random.default_rng(1)
    n, segment = 2**16, 2048
    u = rng.standard_normal((n, 2))
    if correlated:
        u[:, 1] = 0.8 * u[:, 0] + 0.6 * u[:, 1]
    y = _simulate(*sys_d, u)
    history = TimeHistory(np.arange(n) * DT_S, {"force_1": u[:, 0], "force_2": u[:, 1]},
                          {"x_1": y[:, 0], "x_2": y[:, 1]})
    frd = h1_estimate(history, segment_length=segment, band_hz=(0.5, 0.4 * FS_HZ))
    assert frd.inputs == ("force_1", "force_2") and frd.outputs == ("x_1", "x_2")
    f = frd.frequencies_hz
    exact = _exact(*sys_d, f)
    poles = np.unique(np.round(np.abs(np.linalg.eigvals(a)) / (2 * np.pi), 6))
    antiresonance = {0: np.sqrt(K2 / M2) / (2 * np.pi), 1: np.sqrt((K1 + K2) / M1) / (2 * np.pi)}  # of H_ii
    worst = 0.0
    for i in range(2):
        for j in range(2):
            critical = np.append(poles, antiresonance[i]) if i == j else poles
            away = np.all(np.abs(f[:, None] - critical[None, :]) > 1.0, axis=1)
            error = np.abs(frd.response[away, i, j] - exact[away, i, j]) / np.abs(exact[away, i, j])
            worst = max(worst, float(error.max()))
    assert worst < (0.02 / (1 - 0.8**2) if correlated else 0.02)
    if correlated:  # the scalar estimate of one column is badly wrong here, so the test can tell them apart
        f_welch, s_uy = signal.csd(u[:, 0], y[:, 0], fs=FS_HZ, nperseg=segment)
        _, s_uu = signal.welch(u[:, 0], fs=FS_HZ, nperseg=segment)
        scalar = (s_uy / s_uu)[np.isin(f_welch, f)]
        assert np.median(np.abs(scalar - exact[:, 0, 0]) / np.abs(exact[:, 0, 0])) > 0.2


def test_h1_coherence_with_output_noise_is_the_analytic_value():
    """White input, output noise of std s: gamma^2 = |H|^2 / (|H|^2 + s^2); H1 error ~ eps_r (Bendat & Piersol)."""
    sys_d = _oscillator()
    rng = np.random.default_rng(2)
    n, segment = 2**15, 1024
    u = rng.standard_normal(n)
    y = _simulate(*sys_d, u[:, None])[:, 0]
    noise = 0.5 * np.std(y)
    history = TimeHistory(np.arange(n) * DT_S, {"u": u}, {"y": y + noise * rng.standard_normal(n)})
    frd = h1_estimate(history, segment_length=segment)
    h = _exact(*sys_d, frd.frequencies_hz)[:, 0, 0]
    gamma2 = np.abs(h) ** 2 / (np.abs(h) ** 2 + noise**2)
    band = (gamma2 > 0.1) & (gamma2 < 0.99)
    assert band.sum() > 100
    # the coherence estimate scatters by ~ sqrt(2 / n_d) (1 - gamma^2) per bin; its mean over the band does not
    assert abs(np.mean(frd.coherence[band, 0] - gamma2[band])) < 0.02
    # normalised random error of H1, eps_r = sqrt((1 - g2) / (2 n_d g2)), n_d = disjoint segments
    # (fewer than the overlapped ones: conservative); |error| > 4 eps_r has probability exp(-16) per bin
    eps = np.sqrt((1 - gamma2) / (2 * gamma2 * (n // segment)))
    error = np.abs(frd.response[:, 0, 0] - h) / np.abs(h)
    assert np.all(error[band] < 4 * eps[band])


def test_h1_refuses_fully_correlated_inputs_and_bad_settings():
    u = np.random.default_rng(0).standard_normal(1024)
    history = TimeHistory(np.arange(1024) * DT_S, {"u1": u, "u2": 2 * u}, {"y": u}, source="run.csv")
    with pytest.raises(MaceError, match="run.csv: the input cross-spectral matrix is singular .* u1, u2"):
        h1_estimate(history, segment_length=128)
    with pytest.raises(MaceError, match=r"segment length 2048 samples, expected an integer in \[2, 1024\]"):
        h1_estimate(history, segment_length=2048)
    with pytest.raises(MaceError, match=r"no Welch frequency in \(60.0, 70.0\) Hz"):
        h1_estimate(history.head(1024), segment_length=128, band_hz=(60.0, 70.0))


# --- bad data: every message names the file, the channel and the row ----------------------------

def _csv(tmp_path, text: str, name: str = "run.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


HEADER = "time [s],in:gimbal_primary_x [V],out:gyro_bus_x [V]\n"


def _error(call) -> str:
    with pytest.raises(MaceError) as info:
        call()
    return str(info.value)


def test_nan_names_file_channel_and_line(tmp_path):
    path = _csv(tmp_path, HEADER + "0,1,2\n0.01,1,2\n0.02,1,nan\n0.03,1,2\n")
    assert _error(lambda: read_time_history(path)) == \
        f"{path}:4: channel 'gyro_bus_x': value is NaN or inf (1 of 4 rows)"


def test_nan_in_npz_names_channel_and_row(tmp_path):
    y = np.zeros(5)
    y[3] = np.inf
    path = tmp_path / "run.npz"
    np.savez(path, **{"time [s]": np.arange(5.0), "in:u [V]": np.zeros(5), "out:gyro_bus_x [V]": y})
    message = _error(lambda: read_time_history(path))
    assert message == f"{path}: row 3: channel 'gyro_bus_x': value is NaN or inf (1 of 5 rows)"


def test_non_monotonic_time_names_the_line(tmp_path):
    path = _csv(tmp_path, HEADER + "0,1,2\n0.01,1,2\n0.02,1,2\n0.015,1,2\n")
    message = _error(lambda: read_time_history(path))
    assert message == f"{path}:5: channel 'time': time is not increasing (0.02 s, then 0.015 s)"


def test_uneven_time_names_the_line(tmp_path):
    path = _csv(tmp_path, HEADER + "0,1,2\n0.01,1,2\n0.02,1,2\n0.04,1,2\n")
    assert re.match(rf"{re.escape(str(path))}:5: channel 'time': samples are not uniformly spaced", _error(
        lambda: read_time_history(path)))


def test_sample_rate_mismatch_names_the_line(tmp_path):
    path = _csv(tmp_path, HEADER + "0,1,2\n0.002,1,2\n0.004,1,2\n")
    message = _error(lambda: read_time_history(path, sample_time_s=0.001))
    assert message == (f"{path}:3: channel 'time': time step 0.002 s (500 Hz), expected the sample time "
                       "0.001 s (1000 Hz)")


def test_not_a_number_names_line_and_channel(tmp_path):
    path = _csv(tmp_path, HEADER + "0,1,2\n0.01,1,--\n")
    assert _error(lambda: read_time_history(path)) == \
        f"{path}:3: channel 'out:gyro_bus_x [V]': '--' is not a number"


def test_missing_channel_names_file_channel_and_map_row(tmp_path):
    cmap = _write_map(tmp_path / "map.csv", "ai0,gimbal_primary_x,input,V\nai1,gyro_bus_x,output,V\n"
                                            "ai2,gyro_bus_y,output,V\n")
    path = _csv(tmp_path, "time [s],ai0 [V],ai1 [V]\n0,1,2\n0.01,1,2\n")
    assert _error(lambda: read_time_history(path, channel_map=cmap)) == (
        f"{path}:1: channel 'ai2' (output gyro_bus_y, channel map {tmp_path / 'map.csv'}:4) is missing from the file")


def test_unknown_channel_names_file_line_and_channel(tmp_path):
    cmap = _write_map(tmp_path / "map.csv", "ai0,gimbal_primary_x,input,V\n")
    path = _csv(tmp_path, "# logger v2\ntime [s],ai0 [V],ai9 [V]\n0,1,2\n0.01,1,2\n")
    assert _error(lambda: read_time_history(path, channel_map=cmap)) == (
        f"{path}:2: channel 'ai9' is not in the channel map {tmp_path / 'map.csv'} (did you mean 'ai0'? Else add "
        "it, with role 'ignore' to skip it)")


def test_wrong_unit_names_file_channel_and_map_row(tmp_path):
    cmap = _write_map(tmp_path / "map.csv", "ai0,gimbal_primary_x,input,V\nai1,gyro_bus_x,output,V\n")
    path = _csv(tmp_path, "time [s],ai0 [V],ai1 [mV]\n0,1,2\n0.01,1,2\n")
    assert _error(lambda: read_time_history(path, channel_map=cmap)) == (
        f"{path}:1: channel 'ai1': unit 'mV', expected 'V' (channel map {tmp_path / 'map.csv'}:3)")
    seconds = _csv(tmp_path, "time [ms],in:u [V],out:y [V]\n0,1,2\n")
    assert _error(lambda: read_time_history(seconds)) == f"{seconds}:1: channel 'time': unit 'ms', expected 's'"


def test_a_channel_without_role_or_map_is_refused(tmp_path):
    path = _csv(tmp_path, "time [s],gyro_bus_x [V]\n0,1\n0.01,1\n")
    assert _error(lambda: read_time_history(path)).startswith(
        f"{path}:1: channel 'gyro_bus_x': no role; prefix it 'in:' or 'out:'")


def test_bad_channel_maps_name_their_line(tmp_path):
    assert _error(lambda: _write_map(tmp_path / "map.csv", "ai0,u,actuator,V\n")) == \
        f"{tmp_path / 'map.csv'}:2: channel 'ai0': role 'actuator', expected one of input, output, ignore"
    assert _error(lambda: _write_map(tmp_path / "map.csv", "ai0,u,input,V\nai1,u,output,V\n")) == \
        f"{tmp_path / 'map.csv'}:3: signal 'u' is mapped twice (also on line 2)"
    assert _error(lambda: _write_map(tmp_path / "map.csv", "ai0,u,input,\n")) == \
        f"{tmp_path / 'map.csv'}:2: empty unit (every channel needs channel, signal, role, unit)"


def test_malformed_uff_names_the_file_and_dataset(tmp_path):
    path = tmp_path / "bad.uff"
    path.write_text("    -1\n    58\nnot a dataset 58 header\n    -1\n")
    message = _error(lambda: read_frequency_response(path))
    assert message.startswith(f"{path}: dataset 1 (type 58): malformed")
    lines = write_frequency_response(_frd(), tmp_path / "frf.uff").read_text().splitlines()
    (tmp_path / "cut.uff").write_text("\n".join(lines[:20] + lines[25:]) + "\n")  # 5 lines of dataset 1's data
    assert _error(lambda: read_frequency_response(tmp_path / "cut.uff")) == (
        f"{tmp_path / 'cut.uff'}: dataset 1 (type 58): 32 data points, its header (record 7) says 37: a truncated "
        "or malformed data block")
    empty = tmp_path / "none.uff"
    empty.write_text("nothing here\n")
    assert _error(lambda: read_frequency_response(empty)).startswith(f"{empty}: no frequency response")


def test_uff_nan_and_unit_errors_name_dataset_channel_and_row(tmp_path):
    _lab_uff(tmp_path / "lab.uff", nan=True)
    cmap = _write_map(tmp_path / "map.csv", "101+Z,gyro_bus_z,output,V\n1+Z,gimbal_primary_z,input,V\n"
                                            "2-X,gimbal_secondary_x,input,V\n")
    assert _error(lambda: read_frequency_response(tmp_path / "lab.uff", channel_map=cmap)) == (
        f"{tmp_path / 'lab.uff'}: dataset 2: channel '101+Z'/'2-X': the response is NaN or inf at "
        "row 4 (1 of 10 rows)")
    _lab_uff(tmp_path / "mv.uff", units="mV")
    assert _error(lambda: read_frequency_response(tmp_path / "mv.uff", channel_map=cmap)) == (
        f"{tmp_path / 'mv.uff'}: dataset 1: channel '101+Z': unit 'mV', expected 'V' (channel map "
        f"{tmp_path / 'map.csv'}:2)")
    _lab_uff(tmp_path / "none.uff", units="NONE")
    assert _error(lambda: read_frequency_response(tmp_path / "none.uff", channel_map=cmap)) == (
        f"{tmp_path / 'none.uff'}: dataset 1: channel '101+Z': no units label in record 9 (ordinate), "
        "expected e.g. 'V'")


def test_frequency_csv_errors_name_line_and_channel(tmp_path):
    head = "frequency [Hz],re:y/u [V/V],im:y/u [V/V]\n"
    nan = _csv(tmp_path, head + "1,1,0\n2,nan,0\n", "frf.csv")
    assert _error(lambda: read_frequency_response(nan)) == \
        f"{nan}:3: channel 'y'/'u': the response is NaN or inf (1 of 2 rows)"
    order = _csv(tmp_path, head + "1,1,0\n3,1,0\n2,1,0\n", "order.csv")
    assert _error(lambda: read_frequency_response(order)) == \
        f"{order}:4: channel 'frequency': frequencies must be >= 0 and increasing"
    half = _csv(tmp_path, "frequency [Hz],re:y/u [V/V]\n1,1\n", "half.csv")
    assert _error(lambda: read_frequency_response(half)).startswith(
        f"{half}:1: channel 'y'/'u': no column im:y/u")


def test_bad_coherence_names_line_and_channel(tmp_path):
    path = _csv(tmp_path, "frequency [Hz],re:y/u [V/V],im:y/u [V/V],coherence:y [1]\n1,1,0,0.5\n2,1,0,1.5\n")
    assert _error(lambda: read_frequency_response(path)) == \
        f"{path}:3: channel 'y': coherence 1.5, expected a number in [0, 1]"


def test_example_measured_data(tmp_path):
    """examples/measured_data.py: a logger CSV through a channel map, H1, UFF 58, as docs/reference/data_files.md shows."""
    import sys
    examples = str(EXAMPLES)
    sys.path.insert(0, examples)
    try:
        from measured_data import main
    finally:
        sys.path.remove(examples)
    result = main(tmp_path / "lab")
    assert sorted(p.name for p in (tmp_path / "lab").iterdir()) == ["channels.csv", "run.csv", "run_h1.uff"]
    # the random error of H1 where the coherence is lowest (0.995, near 60 Hz, 32 disjoint segments) is
    # eps_r = sqrt((1 - g2) / (2 n_d g2)) = 0.86 %; 4 eps_r bounds it (measured 1.76 %)
    assert result.max_error_away_from_mode < 4 * 0.0086
    assert result.uff_frequency_error <= 5e-6
    assert "1024-sample segments (5.12 s, 0.195312 Hz resolution), hann window, 50% overlap" in result.source


# --- mace-fmu data ------------------------------------------------------------------------------

def test_cli_data_check_and_h1(tmp_path, capsys):
    from mace_fmu.cli import main
    history = _history(2048)
    path = write_time_history(history, tmp_path / "run.npz")
    assert main(["data", "check", str(path), "--sample-time", "0.01"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out == [f"{path}: ok", "  time history: 2048 samples, 0 to 20.47 s, sample time 0.01 s (100 Hz)",
                   "  inputs: gimbal_primary_x [V]", "  outputs: gyro_bus_x [V], gyro_payload_z [V]"]
    frf = tmp_path / "h1.csv"
    assert main(["data", "h1", str(path), "--segment", "256", "--band", "1", "20", "-o", str(frf)]) == 0
    capsys.readouterr()
    expected = h1_estimate(history, segment_length=256, band_hz=(1.0, 20.0))
    back = read_frequency_response(frf)
    assert np.array_equal(back.response, expected.response) and np.array_equal(back.coherence, expected.coherence)


def test_cli_data_check_bad_file_is_one_line_and_status_2(tmp_path, capsys):
    from mace_fmu.cli import main
    path = _csv(tmp_path, HEADER + "0,1,2\n0.01,1,2\n0.02,1,nan\n")
    assert main(["data", "check", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == f"mace-fmu: error: {path}:4: channel 'gyro_bus_x': value is NaN or inf (1 of 3 rows)\n"


def _uff_pairs(path, pairs, *, frequencies=None) -> None:
    """Dataset-58 FRFs written by pyuff, one per (output, input, frequencies) with our ID lines."""
    import pyuff
    datasets = []
    for k, (out, inp) in enumerate(pairs):
        f = np.linspace(1.0, 5.0, 5) if frequencies is None else frequencies[k]
        datasets.append(pyuff.prepare_58(
            binary=0, func_type=4, id4=f"output: {out}", id5=f"input: {inp}", rsp_node=1, rsp_dir=0, ref_node=1,
            ref_dir=0, data=(1 + 1j) * f, x=f, abscissa_spacing=0, abscissa_spec_data_type=18,
            ordinate_spec_data_type=1, orddenom_spec_data_type=1, ordinate_axis_units_lab="V",
            orddenom_axis_units_lab="V"))
    pyuff.UFF(str(path)).write_sets(datasets, mode="overwrite")


def test_uff_incomplete_or_inconsistent_matrices_name_dataset_and_channels(tmp_path):
    path = tmp_path / "three.uff"
    _uff_pairs(path, [("y1", "u1"), ("y2", "u1"), ("y1", "u2")])
    assert _error(lambda: read_frequency_response(path)) == (
        f"{path}: channel 'y2'/'u2': no FRF dataset for this output/input pair (every output needs one per input)")
    path = tmp_path / "grid.uff"
    _uff_pairs(path, [("y1", "u1"), ("y1", "u2")], frequencies=[np.linspace(1.0, 5.0, 5), np.linspace(1.0, 6.0, 5)])
    assert _error(lambda: read_frequency_response(path)) == (
        f"{path}: dataset 2: channel 'y1'/'u2': frequency 2.25 Hz at row 1, dataset 1 has 2 Hz (every FRF needs the "
        "same frequencies)")
    path = tmp_path / "twice.uff"
    _uff_pairs(path, [("y1", "u1"), ("y1", "u1")])
    assert _error(lambda: read_frequency_response(path)) == f"{path}: dataset 2: channel 'y1'/'u1': same pair as dataset 1"


def test_unknown_formats_and_missing_files_are_named(tmp_path):
    assert _error(lambda: read_time_history(tmp_path / "run.mat")) == \
        f"{tmp_path / 'run.mat'}: unknown time-history format '.mat' (expected one of .csv, .npz, .lvm)"
    assert _error(lambda: read_measured_data(tmp_path / "run.tdms")).startswith(
        f"{tmp_path / 'run.tdms'}: unknown measured-data format '.tdms'")
    assert _error(lambda: read_time_history(tmp_path / "gone.csv")) == f"{tmp_path / 'gone.csv'}: no such file"
    assert _error(lambda: read_frequency_response(tmp_path / "gone.uff")) == f"{tmp_path / 'gone.uff'}: no such file"
    assert _error(lambda: read_channel_map(tmp_path / "gone.csv")) == \
        f"{tmp_path / 'gone.csv'}: no such channel-map file"


def test_measured_signals_are_checked_against_the_model(tmp_path):
    from mace_fmu.updating.files import check_model_signals
    # names of the 0-g volts-volts model (volts_model("0g").system.input_labels / output_labels), in part
    inputs = ["gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x", "gimbal_secondary_z"]
    outputs = ["gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z"]
    path = write_time_history(_history(), tmp_path / "run.npz")
    history = read_time_history(path)
    check_model_signals(history, model_inputs=inputs, model_outputs=outputs)
    typo = TimeHistory(np.arange(3.0), {"gimbal_primary_x": np.zeros(3)}, {"gyro_payload_y": np.zeros(3)},
                       source="run.csv")
    assert _error(lambda: check_model_signals(typo, model_inputs=inputs, model_outputs=outputs)) == \
        "run.csv: signal 'gyro_payload_y' is not a model output; did you mean gyro_payload_z, gyro_payload_x?"
    swapped = TimeHistory(np.arange(3.0), {"gyro_bus_x": np.zeros(3)}, {"gyro_bus_y": np.zeros(3)}, source="run.csv")
    assert _error(lambda: check_model_signals(swapped, model_inputs=inputs, model_outputs=outputs)) == \
        "run.csv: signal 'gyro_bus_x' is measured as an input but is a model output"
