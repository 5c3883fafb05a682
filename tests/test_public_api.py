"""The package's front door: the names a user starts with, each documented, none costly to import."""

from __future__ import annotations

import subprocess
import sys


def test_every_public_name_resolves_and_is_documented():
    import mace_fmu

    for name in mace_fmu.__all__:
        obj = getattr(mace_fmu, name)
        assert obj.__doc__ and obj.__doc__.strip(), name


def test_importing_the_package_loads_no_heavy_dependency():
    code = "import sys, mace_fmu; print(sorted(m for m in ('control', 'fmpy', 'scipy') if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
