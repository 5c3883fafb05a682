"""``mace-fmu build``: the main job: modes next to the thesis tables, and the FMUs of both models."""

from __future__ import annotations

import argparse

from mace_fmu.cli.common import (deck_option, model_variant, parameters, parameters_option, progress, progress_bar,
                                 step_lines)
from mace_fmu.cli.preflight import output_option
from mace_fmu.util.frequency import hz_text


def cmd_build(args: argparse.Namespace) -> int:
    # imported here, as in the other commands, so that `mace-fmu modes` starts without control/pythonfmu; each
    # stage's imports come after its progress line, as they take seconds together on a busy machine
    progress(f"deck {args.deck}")
    from mace_fmu.deck.reader import read_deck

    deck = read_deck(args.deck)
    params = parameters(args)
    if params is not None:
        progress(f"parameter set {args.parameters} ({len(params)} values)")
    progress("0-g modes (suspension removed, linear)")
    from mace_fmu.fe.modes import DEFAULT_MAX_HZ, compute_modes

    # the modes the FMUs are built from: up to 250 Hz, the thesis's cut-off, whatever a deck's EIGRL says
    m0 = compute_modes(deck, configuration="0g", max_hz=DEFAULT_MAX_HZ, parameters=params,
                       structure_file=args.structure_file)
    results = {}
    for preload in ("large", "linear"):
        progress(f"1-g modes ({preload} gravity preload)")
        with progress_bar() as bar:
            results[preload] = compute_modes(deck, configuration="1g", preload=preload, max_hz=DEFAULT_MAX_HZ,
                                             progress=bar, parameters=params, structure_file=args.structure_file)
    from mace_fmu.structure.file import is_bundled_deck

    # the thesis's tables pair and compare MACE's own modes; another deck gets its modes listed instead
    print(thesis_tables(m0, results) if is_bundled_deck(deck) else modes_text(m0, results))
    print()
    for configuration, modes in (("1g", results["large"]), ("0g", m0)):
        progress(f"{configuration} volts-volts model and its parametric arrays")
        from mace_fmu.fmu.export import export_fmu
        from mace_fmu.fmu.naming import model_fmu_name
        from mace_fmu.fmu.parametric import parametric_model
        from mace_fmu.iomodel.volts import volts_model

        model = volts_model(modes, parameters=params)
        parametric = parametric_model(model)  # what every runtime's FMU carries: computed once
        for runtime, fmi_version in (("native", 2), ("native", 3), ("pythonfmu", 2)):
            name = model_fmu_name(model, runtime=runtime, fmi_version=fmi_version, variant=model_variant(args))
            progress(f"{runtime} FMU (FMI {fmi_version}) {name}.fmu")
            path = export_fmu(model, runtime=runtime, fmi_version=fmi_version, out_dir=args.out, name=name,
                              parametric=parametric, progress=step_lines)
            print(f"wrote {path}", flush=True)  # beside the progress lines on stderr, in their order
    print()
    print(low_modes(results))
    return 0


def main_job_text() -> str:
    """The tables ``mace-fmu build`` prints for the bundled deck (the same functions; no FMUs written):
    what the documentation shows and its test compares."""
    from mace_fmu.fe.modes import DEFAULT_MAX_HZ, compute_modes

    m0 = compute_modes(configuration="0g", max_hz=DEFAULT_MAX_HZ)
    results = {preload: compute_modes(configuration="1g", preload=preload, max_hz=DEFAULT_MAX_HZ)
               for preload in ("large", "linear")}
    return thesis_tables(m0, results) + "\n\n" + low_modes(results)


def thesis_tables(m0, results) -> str:
    """Tables 5.1 (0-g, and 1-g for each preload) and 3.15 beside the thesis, as ``build`` prints them.

    ``m0``: the 0-g modes; ``results``: preload kind ("large", "linear") -> 1-g modes. The README shows
    this text; a test regenerates it from the code and compares.
    """
    from mace_fmu.thesis import (format_mass_rows, format_rows, format_side_by_side, table_3_15_comparison,
                                 table_5_1_0g, table_5_1_1g)

    return "\n\n".join([
        format_rows(table_5_1_0g(m0), title="Table 5.1, 0-g column (flexible modes)"),
        format_side_by_side({kind: table_5_1_1g(m1, m0) for kind, m1 in results.items()},
                            title="Table 5.1, 1-g column (structural modes paired with the 0-g ones by MAC)"),
        format_mass_rows(table_3_15_comparison(m0), title="Table 3.15, free-free mass properties about the centre node")])


def modes_text(m0, results, *, max_hz: float = 250.0) -> str:
    """The modes of a deck that is not MACE's, as ``build`` prints them in place of the thesis's tables: the 0-g
    and the large-preload 1-g modes up to ``max_hz`` [Hz], each with its label."""
    blocks = []
    for title, modes in (("0-g modes", m0.modes), ("1-g modes (large-displacement preload)", results["large"].modes)):
        lines = [f"{title} up to {max_hz:g} Hz"]
        lines += [f"{i + 1:3d} {hz_text(f, decimals=3):>9s}  {label}"
                  for i, (f, label) in enumerate(zip(modes.frequencies_hz, modes.labels)) if f <= max_hz]
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks)


def low_modes(results) -> str:
    """The 1-g modes below 25 Hz of both preloads side by side (by index: the preloads keep the mode order)."""
    large, linear = results["large"].modes, results["linear"].modes
    lines = ["1-g modes below 25 Hz (large-displacement preload | linear preload)"]
    for i in range(min(len(large), len(linear))):
        if large.frequencies_hz[i] > 25.0:
            break
        lines.append(f"{i + 1:3d} {hz_text(large.frequencies_hz[i], decimals=3):>9s}  {large.labels[i]:46s} | "
                     f"{hz_text(linear.frequencies_hz[i], decimals=3):>9s}  {linear.labels[i]}")
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("build", help="the main job: modes next to the thesis tables, and the FMUs of both models")
    deck_option(p)
    parameters_option(p)
    output_option(p, "-o", "--out", kind="folder", default="fmus",
                  help="where to write the FMUs: MACE_<1g|0g>_native.fmu (FMI 2.0), MACE_<1g|0g>_native_fmi3.fmu, "
                  "MACE_<1g|0g>_pythonfmu.fmu (default ./fmus); with --parameters P.toml "
                  "MACE_1g_native_P_<digest>.fmu and so on (6 hex digits of the set's values), never the plain "
                  "model's names nor another set's")
    p.set_defaults(func=cmd_build)
