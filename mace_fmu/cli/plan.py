"""``mace-fmu plan-test``: before a test is run, how sure an FMU update on its data would be of each parameter."""

from __future__ import annotations

import argparse
from pathlib import Path

from mace_fmu.cli.common import non_negative_integer, positive_integer, progress, progress_bar
from mace_fmu.cli.preflight import output_option, scheduler_options
from mace_fmu.errors import MaceError
from mace_fmu.util.atomic import write_text_atomic

#: the epilog: printed as written (argparse expands %-formats in the options' help only, so "%" is one "%" here)
_EXAMPLE = """\
a test plan (TOML):
  [[test]]
  name = "gimbal"
  inputs = ["gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x", "gimbal_secondary_z"]
  outputs = ["gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z"]
  seconds = 20              # record length [s]          (default 8)
  sample_time_s = 0.002     # [s]                        (default 0.002)
  band_hz = [0.5, 60]       # white-noise excitation     (default [0.5, 60])
  noise_rms_percent = 2     # output noise, % of RMS      (default 2)
  gain_uncertainty_percent = { gyro_bus_x = 1 }   # sensor gains known to 1 % (default: exact)

  [[candidate]]             # optional: tests one update takes together (default: each test alone)
  name = "gimbal + strut"
  tests = ["gimbal", "strut"]
"""


def cmd_plan(args: argparse.Namespace) -> int:
    from mace_fmu.updating.engine.uncertainty import uncertainty_toml
    from mace_fmu.updating.fmu.planning import format_plan, plan_tests, read_test_plan
    from mace_fmu.util.runner import DaskRunner

    names = [n.strip() for part in args.update for n in part.split(",") if n.strip()]
    if not names:
        raise MaceError("name the parameters the update will estimate: --update NAME[,NAME...]")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise MaceError(f"parameter {twice[0]!r} named twice in --update (name each once)")
    candidates = read_test_plan(args.tests)
    from mace_fmu.updating.fmu.model import read_fmu_interface

    interface = read_fmu_interface(args.fmu)
    interface.check_parameters(names)
    values = None
    if args.at is not None:
        from mace_fmu.cli.update import _read_start

        values, _ = _read_start(args.at, args.fmu)  # a plan predicts at values; bounds do not apply
        interface.check_parameters(list(values))
    for c in candidates:  # every signal checked before the first simulation
        for t in c.tests:
            interface.check_signals(inputs=t.inputs, outputs=t.outputs, where=f"{args.tests}: test {t.name!r}")
    progress(f"planning {len(candidates)} candidate(s) for {len(names)} parameter(s) of {Path(args.fmu).name}")
    with progress_bar() as bar:
        with DaskRunner(scheduler=args.scheduler, workers=args.workers, progress=bar, task="FMU runs",
                        connect_timeout_s=args.scheduler_timeout) as runner:
            planned = plan_tests(fmu=args.fmu, parameters=names, candidates=candidates, seed=args.seed,
                                 values=values, runner=runner, progress=bar)
    print(format_plan(planned))
    if args.out is not None:
        path = write_text_atomic(args.out, uncertainty_toml(tuple(p.uncertainty for p in planned)))
        print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plan-test", help="before a test: the uncertainty an FMU update on its data would leave, "
                       "for each candidate experiment, ranked", formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="From the model alone (no data): each candidate's tests are simulated without "
                                   "noise, the update's sensitivities are taken, and the linearised standard "
                                   "deviation of every parameter an update on such data would report is printed, "
                                   "best candidate (smallest largest standard deviation) first.",
                       epilog=_EXAMPLE)
    p.add_argument("fmu", metavar="FILE", help="the FMU that will be updated")
    p.add_argument("--tests", metavar="PLAN.toml", required=True, help="the candidate tests (format below)")
    p.add_argument("--update", metavar="NAME[,NAME...]", action="append", default=[],
                   help="FMU parameters the update will estimate (repeatable)")
    p.add_argument("--at", metavar="FILE", help="parameter values to predict about (TOML [values], e.g. an earlier "
                   "update's parameters.toml; default: the FMU's start values). The predictions hold near these "
                   "values only: the cable moduli's predicted sd halved between the start values and a point 2-3 %% "
                   "away")
    p.add_argument("--seed", type=non_negative_integer, default=0,
                   help="seed of the excitation's white noise (default 0)")
    scheduler_options(p, scheduler_help="run the FMU simulations on this Dask cluster")
    p.add_argument("--workers", type=positive_integer, default=None, help="local worker processes (default: one per core)")
    output_option(p, "-o", "--out", kind="file", metavar="FILE",
                  help="also write each candidate's predicted uncertainty (TOML, as uncertainty.toml)")
    p.set_defaults(func=cmd_plan)
