"""``mace-fmu data``: check a measured data file (through a channel map), or estimate H1 from a time history."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

import numpy as np

from mace_fmu.cli.common import fraction, non_negative_hz, positive_integer, positive_number
from mace_fmu.cli.preflight import output_option

if TYPE_CHECKING:
    from mace_fmu.updating.engine.measured import FrequencyResponseData, TimeHistory


def _summary(data: TimeHistory | FrequencyResponseData) -> list[str]:
    from mace_fmu.updating.engine.measured import TimeHistory
    signals = lambda names: ", ".join(f"{n} [{data.unit(n)}]" for n in names) or "none"  # noqa: E731
    if isinstance(data, TimeHistory):
        t = data.times_s
        head = (f"time history: {t.size} samples, {t[0]:.9g} to {t[-1]:.9g} s, sample time "
                f"{data.sample_time_s:.9g} s ({1 / data.sample_time_s:.6g} Hz)")
    else:
        f = data.frequencies_hz
        head = f"frequency response: {f.size} frequencies, {f[0]:.6g} to {f[-1]:.6g} Hz"
        if data.coherence is not None:
            head += f", coherence {np.min(data.coherence):.3f} to {np.max(data.coherence):.3f}"
        if data.averages is not None:
            head += f", {data.averages} averages"
    return [head, f"inputs: {signals(data.inputs)}", f"outputs: {signals(data.outputs)}"]


def cmd_check(args: argparse.Namespace) -> int:
    from mace_fmu.updating.files import read_channel_map, read_measured_data

    channel_map = read_channel_map(args.map) if args.map else None
    data = read_measured_data(args.file, channel_map=channel_map, sample_time_s=args.sample_time)
    print(f"{args.file}: ok")
    for line in _summary(data):
        print(f"  {line}")
    return 0


def cmd_h1(args: argparse.Namespace) -> int:
    from mace_fmu.errors import MaceError
    from mace_fmu.updating.files import h1_estimate, read_channel_map, read_time_history, write_frequency_response

    channel_map = read_channel_map(args.map) if args.map else None
    history = read_time_history(args.file, channel_map=channel_map, sample_time_s=args.sample_time)
    if args.band is not None and not args.band[0] < args.band[1]:
        raise MaceError(f"--band {args.band[0]:g} {args.band[1]:g}: expected LOW < HIGH [Hz]")
    frd = h1_estimate(history, segment_length=args.segment, window=args.window, overlap=args.overlap,
                      band_hz=tuple(args.band) if args.band else None, inputs_held=args.inputs_held)
    write_frequency_response(frd, args.output)
    print(f"{args.output}: {frd.source}")
    for line in _summary(frd):
        print(f"  {line}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("data", help="measured data files: check one, or estimate H1 from a time history")
    commands = p.add_subparsers(dest="data_command", required=True)
    check = commands.add_parser("check", help="read a time history (.csv, .npz, LabVIEW .lvm) or frequency response "
                                "(.csv, .uff, .unv) and summarise it; bad data end with one line naming file, channel "
                                "and row")
    h1 = commands.add_parser("h1", help="H1 frequency response (Welch) of a time history, written as .csv or .uff")
    for q in (check, h1):
        q.add_argument("file", help="the measured data file")
        q.add_argument("--map", metavar="CSV", help="channel map: columns channel, signal, role (input|output|"
                       "ignore), unit")
        q.add_argument("--sample-time", type=positive_number, metavar="S",
                       help="expected sample time [s] of a time history")
    h1.add_argument("--segment", type=positive_integer, required=True, metavar="N", help="samples per Welch segment")
    h1.add_argument("--window", default="hann", help="scipy.signal window name (default hann)")
    h1.add_argument("--overlap", type=fraction, default=0.5, help="overlap of segments, a fraction (default 0.5)")
    h1.add_argument("--band", type=non_negative_hz, nargs=2, metavar=("LOW", "HIGH"),
                    help="keep frequencies in [LOW, HIGH] Hz")
    h1.add_argument("--inputs-held", action="store_true",
                    help="the record's inputs were held over each sample (a simulation's record, e.g. an FMU's; "
                    "DAC commands logged instead of the measured signal): divide the hold's half-sample delay and "
                    "droop out, so that the file is the continuous response an analyser measures")
    output_option(h1, "-o", "--output", kind="file", required=True, help="output file: .csv, .uff or .unv")
    check.set_defaults(func=cmd_check)
    h1.set_defaults(func=cmd_h1)
