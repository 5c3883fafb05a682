"""Sphinx configuration of the mace-fmu documentation.

Built with ``python -m sphinx -W -b html docs docs/_build/html`` (warnings are errors). Pages that
come from the code are generated at build time by ``docs/_ext/generated.py``: the API reference
from each package's ``__all__``, the command-line reference from the argparse parser, and the
thesis tables beside our numbers.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

project = "mace-fmu"
author = "the mace-fmu developers"
copyright = "2026, the mace-fmu developers (MIT licence)"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "generated",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "guide/_viewer_still.md", "**.ipynb_checkpoints", "auto_examples/**/*.ipynb", "auto_examples/**/*.py",
                    "auto_examples/**/*.zip", "auto_examples/**/*.json", "auto_examples/**/*.md5"]
myst_enable_extensions = ["colon_fence", "dollarmath"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]  # the guide pages are the README's sections, some start at level 2 inside

autosummary_generate = True
autodoc_default_options = {"members": False}
autodoc_typehints = "description"
napoleon_numpy_docstring = True
napoleon_google_docstring = False

html_theme = "pydata_sphinx_theme"
html_title = "mace-fmu"
html_static_path = ["_static"]
html_theme_options = {
    "navigation_depth": 2,
    "show_toc_level": 2,
    "footer_start": ["copyright"],
}

# The examples: each is a gallery page. Only the quick ones run at build time (``MACE_DOCS_RUN``
# overrides the pattern); the others are shown with their code and the command that runs them, since
# they need minutes or FMUs built first (each says so in its docstring).
sphinx_gallery_conf = {
    "examples_dirs": [str(HERE.parent / "examples")],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": os.environ.get("MACE_DOCS_RUN",
                                       r"(measured_data|lqg_model_error|own_structure|nastran_plate|update_shaker_beam|"
                                       r"modal_test_three_storey_frame)\.py$"),
    "reset_argv": "generated.example_argv",  # own_structure.py writes its files under docs/_build/examples
    "ignore_pattern": r"__init__\.py",
    "download_all_examples": False,
    "remove_config_comments": True,
    "plot_gallery": "True",
    "abort_on_example_error": True,
    # the examples not run at build time show the project's own figure, not sphinx-gallery's placeholder
    "default_thumb_file": str(HERE / "_static" / "mode_and_bode.png"),
    "only_warn_on_example_error": False,
}
