"""Pages generated from the code at build time, so that they cannot drift from it.

- ``reference/api/*.rst``: one page per package, its public names read from the package's ``__all__``;
- ``reference/cli.rst``: every ``mace-fmu`` command's ``--help``, from the argparse parser;
- ``thesis/tables.md``: the thesis's tables beside ours, as the commands print them today;
- ``reference/fmu_variables.md``: the variables of the MACE FMUs, from the function that writes their
  model descriptions;
- ``_static/viewer/*.html``: the viewer's pages of the first flexible modes, embedded in the viewer guide,
  with a PNG still (``_static/viewer/modes_0g.png``, ``guide/_viewer_still.md``) where Chromium is installed.

The files are written under ``docs/`` before Sphinx lists the sources (``config-inited``) and are
not kept in git (``docs/.gitignore``).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import inspect
import io
import os
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]

#: the packages of the API reference, in the order of the data flow (tests/test_public_api.py's STAGES)
PACKAGES = ("mace_fmu", "mace_fmu.deck", "mace_fmu.deck.parsers", "mace_fmu.structure", "mace_fmu.parameters",
            "mace_fmu.fe", "mace_fmu.nastran_modes", "mace_fmu.iomodel", "mace_fmu.fmu", "mace_fmu.fmu.native",
            "mace_fmu.viewer",
            "mace_fmu.ssp",
            "mace_fmu.updating", "mace_fmu.updating.engine", "mace_fmu.updating.files", "mace_fmu.updating.mace",
            "mace_fmu.updating.fmu", "mace_fmu.updating.modal", "mace_fmu.updating.sample", "mace_fmu.control_studies", "mace_fmu.zero_g",
            "mace_fmu.zero_g.robust", "mace_fmu.sparse", "mace_fmu.util", "mace_fmu.cli")

#: the commands whose printed tables stand beside the thesis: (title, argv, what it shows)
THESIS_COMMANDS = (
    ("Tables 5.1 and 3.15: modes and mass properties", ["build", "--tables-only"],
     "The 0-g and 1-g (both preloads) flexible modes beside Table 5.1 and the free-free mass properties beside "
     "Table 3.15, as `mace-fmu build` prints them."),
    ("Table 4.7: the 1-g volts-volts model's closed-loop poles", ["model", "1g", "--poles"],
     "Closed-loop poles of the 1-g model beside Table 4.7's FE columns."),
    ("Table 5.2: the 0-g volts-volts model's closed-loop poles", ["model", "0g", "--poles"],
     "Closed-loop poles of the 0-g model beside Table 5.2."),
    ("Tables 4.2 and 4.3: the updating sample problem", ["update", "sample-problem"],
     "The two-mass sample problem of thesis section 4.3, every case beside Table 4.2 and 4.3."),
    ("Table 5.3: the updated nominal 0-g model and its frequency bounds", ["predict-0g"],
     "The updated nominal 0-g model and its bounds beside Table 5.3."),
)


def _write(path: Path, text: str) -> None:
    """Write only when the text changed, so that Sphinx does not rebuild pages that did not."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def _title(text: str, underline: str = "=") -> str:
    return f"{text}\n{underline * len(text)}\n"


def _is_data(obj) -> bool:
    return not (inspect.isclass(obj) or inspect.isfunction(obj) or inspect.ismodule(obj) or callable(obj))


def api_pages() -> None:
    """One page per package: its functions and classes (autosummary stubs), its constants with the
    comment that documents them where they are defined. The top-level names link to their package."""
    index = [_title("API reference"), "",
             "Every package lists its public names in ``__all__``; these pages are generated from those lists. "
             "The packages follow the data flow: deck, structure, parameters, finite elements, input-output "
             "models, FMUs and SSP packages, updating, Appendix A studies, the 0-g prediction; ``sparse`` is the "
             "sparse solver the finite elements use, ``util`` holds what they share.", "",
             ".. toctree::", "   :maxdepth: 1", ""]
    home = {}  # public name -> the package whose page documents it: the deepest that exports it
    stubs = set()  # the autosummary stubs the pages ask for: "package.Name"
    for name in sorted(PACKAGES, key=lambda package: package.count(".")):
        for public in importlib.import_module(name).__all__:
            home[public] = name
    for name in PACKAGES:
        package = importlib.import_module(name)
        lines = [_title(f"``{name}``"), f".. automodule:: {name}", "", f".. currentmodule:: {name}", ""]
        defined_in = getattr(getattr(package, "__getattr__", None), "modules", {})  # deck and ssp import eagerly
        objects = {public: getattr(package, public) for public in package.__all__}
        elsewhere = [public for public in package.__all__ if home[public] != name]
        if elsewhere:  # the names a package re-exports from a subpackage: documented on the subpackage's page
            lines += [f"- :py:obj:`{public} <{home[public]}.{public}>`" for public in elsewhere]
            lines.append("")
            objects = {public: obj for public, obj in objects.items() if public not in elsewhere}
        if objects:
            lines += [".. autosummary::", "   :toctree: generated", "   :nosignatures:", ""]
            lines += [f"   {public}" for public, obj in objects.items() if not _is_data(obj)]  # current module's
            lines.append("")
            for public, obj in objects.items():
                if _is_data(obj):
                    lines += [f".. autodata:: {defined_in.get(public, name)}.{public}", "   :no-index:", ""]
        _write(DOCS / "reference" / "api" / f"{name}.rst", "\n".join(lines) + "\n")
        index.append(f"   {name}")
        stubs |= {f"{name}.{public}" for public, obj in objects.items() if not _is_data(obj)}
    _write(DOCS / "reference" / "api" / "index.rst", "\n".join(index) + "\n")
    # autosummary writes a stub per name and never removes one: a name that left an __all__ would stay, unlisted
    for stub in (DOCS / "reference" / "api" / "generated").glob("*.rst"):
        if stub.stem not in stubs:
            stub.unlink()


def _commands(parser: argparse.ArgumentParser, prefix: str = "mace-fmu"):
    yield prefix, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _commands(sub, f"{prefix} {name}")


def cli_page() -> None:
    from mace_fmu.cli import build_parser

    os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal: a fixed width for the page
    lines = [_title("Command line"), "",
             "Every command's ``--help``, generated from the parser at build time. Errors in the input end with "
             "one line naming the file, line or option and exit status 2; an update that did not converge exits "
             "with status 3 (its results still written).", ""]
    for name, parser in _commands(build_parser()):
        lines += [_title(f"``{name}``", "-"), "", ".. code-block:: text", ""]
        lines += ["   " + line if line else "" for line in parser.format_help().splitlines()]
        lines.append("")
    _write(DOCS / "reference" / "cli.rst", "\n".join(lines) + "\n")


def _run(argv: list[str]) -> str:
    from mace_fmu.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    if status != 0:
        raise RuntimeError(f"mace-fmu {' '.join(argv)} exited {status}: {err.getvalue()[-2000:]}")
    return out.getvalue()


def thesis_page() -> None:
    from mace_fmu.cli.build import main_job_text

    lines = ["# The thesis reproduced", "",
             "Each table below is printed by the command above it, run when this page was built: the thesis value, "
             "ours and the difference come from the code of this version, never typed by hand. How each "
             "difference arises is explained on the pages of the user guide and in "
             "[What the main job reproduces](main_job.md).", ""]
    for title, argv, what in THESIS_COMMANDS:
        shown = [a for a in argv if a != "--tables-only"]
        text = main_job_text() if "--tables-only" in argv else _run(argv)
        lines += [f"## {title}", "", what, "", "```console", f"$ mace-fmu {' '.join(shown)}", "```", "", "```text",
                  text.rstrip(), "```", ""]
    _write(DOCS / "thesis" / "tables.md", "\n".join(lines))


def data_flow_page() -> None:
    """The packages in the order the data flows through them, each with the first line of its docstring."""
    lines = ["# The data flow", "",
             "A deck becomes modes, the modes a volts-volts model, the model an FMU; test data update the "
             "model's parameters. The packages follow that flow, and each imports only from those before it "
             "(a test checks every import). This page is generated from the package layout.", "", "```text"]
    for i, name in enumerate(PACKAGES[1:]):
        doc = (importlib.import_module(name).__doc__ or "").strip().split("\n\n")[0].replace("\n", " ")
        lines += [("    |\n    v\n" if i else "") + f"{name}", f"    {doc}"]
    lines += ["```", ""]
    _write(DOCS / "explanation" / "data_flow.md", "\n".join(lines))


def viewer_pages() -> None:
    """The viewer's standalone pages of the first 0-g and 1-g modes, embedded by the viewer guide."""
    from mace_fmu.viewer import animate_modes, write_animation_html

    from mace_fmu.fe.modes import compute_modes

    for configuration, max_hz in (("0g", 12.0), ("1g", 12.0)):
        modes = compute_modes(configuration=configuration, max_hz=max_hz)
        flexible = [k + 1 for k, hz in enumerate(modes.frequencies_hz) if hz > 1.5][:4]
        page = DOCS / "_static" / "viewer" / f"modes_{configuration}.html"
        write_animation_html(animate_modes(modes, flexible), page, title=f"MACE {configuration} modes")
    viewer_still()


def viewer_still() -> None:
    """A PNG still of the 0-g page beside it where Chromium is installed; a sentence saying why not elsewhere.

    The viewer guide includes ``guide/_viewer_still.md``; the still is taken again only when the page is
    newer than it.
    """
    from mace_fmu.viewer.still import chromium_executable, write_still

    from mace_fmu.errors import MaceError

    page, png = DOCS / "_static" / "viewer" / "modes_0g.html", DOCS / "_static" / "viewer" / "modes_0g.png"
    reason = None
    if chromium_executable() is None:
        reason = "no Chromium was installed where this site was built"
    elif not png.exists() or png.stat().st_mtime < page.stat().st_mtime:
        try:
            write_still(page, png)
        except MaceError as error:  # a still is a picture of the page, not a reason to stop the build
            reason = f"Chromium could not render the page ({str(error)[:200]})"
    if reason is None:
        text = ("```{image} ../_static/viewer/modes_0g.png\n:alt: A still of the viewer page of the 0-g modes\n"
                ":width: 100%\n```\n\n*A still of the page above, taken by headless Chromium when this site was "
                "built (`mace-fmu view modes 0g --png FILE` takes one).*\n")
    else:
        png.unlink(missing_ok=True)
        text = f"*No still of the page above: {reason}.*\n"
    _write(DOCS / "guide" / "_viewer_still.md", text)


def _cell(value) -> str:
    return "" if value is None else str(value).replace("|", "\\|")


def fmu_variables_page() -> None:
    """The variables of the MACE FMUs (both kinds carry the same), from ``fmu_variables`` itself."""
    from dataclasses import replace

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.native.model_description import fmu_variables
    from mace_fmu.fmu.parametric import parametric_model
    from mace_fmu.iomodel.volts import volts_model

    lines = ["# FMU variables", "",
             "The variables of the bundled MACE FMUs (`mace-fmu export`, `mace-fmu build`), listed when this page was "
             "built by the same function that writes the FMUs' `modelDescription.xml` "
             "(`mace_fmu.fmu.native.model_description.fmu_variables`); the pythonfmu and native FMUs carry the "
             "same names, units, descriptions and start values. How the parameters act is in the "
             "[FMU guide](../guide/fmus.md).", ""]
    for kind in ("1g", "0g"):
        # the co-simulation variables: the model-exchange states are left out
        variables = fmu_variables(replace(parametric_model(volts_model(compute_modes(configuration=kind))),
                                          state_names=()))
        count = {c: sum(v.causality == c for v in variables) for c in
                 ("input", "output", "parameter", "calculatedParameter", "local")}
        lines += [f"## The {kind} FMU", "",
                  f"{count['input']} inputs, {count['output']} outputs, {count['parameter']} parameters, "
                  f"{count['calculatedParameter']} calculated parameters (`frequency_mode_k`, Hz: each mode's "
                  f"natural frequency after reanalysis)"
                  + (f", {count['local']} locals (the model-exchange states and their derivatives)" if count["local"]
                     else "") + ", then `time`.", ""]
        for causality, title in (("input", "Inputs"), ("output", "Outputs"), ("parameter", "Parameters")):
            lines += [f"### {title} ({kind})", "", "| name | unit | start | min | max | description |",
                      "|---|---|---|---|---|---|"]
            lines += [f"| `{v.name}` | {_cell(v.unit)} | {_cell(v.start)} | {_cell(v.minimum)} | {_cell(v.maximum)} "
                      f"| {_cell(v.description)} |" for v in variables if v.causality == causality]
            lines.append("")
    _write(DOCS / "reference" / "fmu_variables.md", "\n".join(lines))


def example_argv(gallery_conf, script_vars) -> list[str]:
    """The command-line arguments of an example run by sphinx-gallery (its ``reset_argv``): the examples that
    write files by default into the folder they run in write them under ``docs/_build/examples`` instead."""
    name = Path(script_vars["src_file"]).stem
    writes_files = ("own_structure", "nastran_plate", "modal_test_three_storey_frame", "update_shaker_beam")
    return [str(DOCS / "_build" / "examples" / name)] if name in writes_files else []


def generate(app, config) -> None:
    fmu_variables_page()
    viewer_pages()
    data_flow_page()
    api_pages()
    cli_page()
    thesis_page()


def setup(app):
    # config-inited: before Sphinx lists the source files, so that autosummary sees the generated pages
    app.connect("config-inited", generate)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
