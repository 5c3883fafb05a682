"""The project as a user installs it: a wheel built without warnings, installed (not editable) in a fresh venv.

The wheel is built from the source tree exactly as ``pip install .`` builds it (build isolation,
the pyproject's own setuptools), then installed with ``--no-deps`` into a new virtual environment
whose dependencies come from this environment's site-packages (a path entry, so none of its
``.pth`` files, and with them no editable install of mace-fmu, is active). ``mace-fmu build`` then
runs from an unrelated folder, with the bundled deck and data read from the installed package, as on a
fresh machine: zig's cache and the runtime cache empty. The wheel carries the native runtime's binaries
(compiled by setup.py when it was built), so that build compiles nothing.
"""

from __future__ import annotations

import os
import re
import site
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from support.paths import ROOT

pytestmark = pytest.mark.slow  # installs the package into fresh virtual environments

#: a Python warning class in a build log (setuptools' deprecations come as e.g. "SetuptoolsDeprecationWarning")
_PY_WARNING = re.compile(r"\b\w*Warning\b")


def test_non_editable_install_runs_the_main_job_from_another_folder(tmp_path: Path) -> None:
    wheels = tmp_path / "wheels"
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--wheel-dir", str(wheels), str(ROOT)],
                           capture_output=True, text=True, timeout=600)
    assert built.returncode == 0, built.stdout + built.stderr
    log = built.stdout + built.stderr
    assert not _PY_WARNING.search(log), log
    (wheel,) = wheels.glob("mace_fmu-*.whl")
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
        metadata = archive.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
    assert {"mace_fmu/data/mace_em.bdf", "mace_fmu/data/mace_em.toml", "mace_fmu/data/thesis.toml",
            "mace_fmu/fmu/slave.py", "mace_fmu/viewer/html.py", "modelica_like/system.py",
            "mace_fmu/fmu/native/c/controller/mace_discrete.c"} <= names
    assert not [n for n in names if n.startswith("viewer/")]  # the viewer is mace_fmu.viewer, not a top-level package
    assert "License-Expression: MIT" in metadata.splitlines()
    # the runtime's binaries, compiled by the build: four variants of five platforms, for these sources
    from mace_fmu.fmu.native import compile as runtime
    from mace_fmu.fmu.native.platforms import PLATFORMS

    prebuilt = {n.rsplit("/", 1)[1] for n in names if n.startswith("mace_fmu/fmu/native/prebuilt/")}
    assert len(prebuilt) == 20, sorted(prebuilt)
    assert prebuilt == {runtime._file_name(p, runtime._cache_key(p, c_files, runtime.sources_digest(
        runtime.source_files(c_files)))) for c_files in runtime.VARIANTS.values() for p in PLATFORMS}

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = venv / "bin" / "python"
    purelib = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             check=True, capture_output=True, text=True).stdout.strip()
    Path(purelib, "dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    installed = subprocess.run([str(python), "-m", "pip", "install", "--no-deps", "--no-index", str(wheel)],
                               capture_output=True, text=True, timeout=300)
    assert installed.returncode == 0, installed.stdout + installed.stderr
    assert not _PY_WARNING.search(installed.stdout + installed.stderr), installed.stdout + installed.stderr

    work = tmp_path / "elsewhere"
    work.mkdir()
    where = subprocess.run([str(python), "-c", "import mace_fmu; print(mace_fmu.__file__)"], cwd=work,
                           check=True, capture_output=True, text=True).stdout.strip()
    assert Path(where).is_relative_to(Path(purelib)), where
    fresh = {"ZIG_GLOBAL_CACHE_DIR": str(tmp_path / "zig-cache"), "MACE_FMU_CACHE_DIR": str(tmp_path / "mace-cache")}
    run = subprocess.run([str(venv / "bin" / "mace-fmu"), "build"], cwd=work, capture_output=True, text=True,
                         timeout=900, env={**os.environ, **fresh})
    assert run.returncode == 0, run.stderr
    # nothing compiled: no line of a compilation, nothing in zig's cache or the runtime cache
    assert "native FMU runtime" not in run.stderr, run.stderr
    assert not any(Path(folder).exists() and any(Path(folder).iterdir()) for folder in fresh.values())
    assert "Table 5.1, 0-g column" in run.stdout and "Table 3.15" in run.stdout
    assert sorted(p.name for p in (work / "fmus").iterdir()) == sorted(
        f"MACE_{s}_{k}.fmu" for s in ("1g", "0g") for k in ("native", "native_fmi3", "pythonfmu"))
    for fmu in (work / "fmus").iterdir():
        with zipfile.ZipFile(fmu) as archive:
            assert archive.testzip() is None and "modelDescription.xml" in archive.namelist()
