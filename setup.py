"""The package build's one step beyond pyproject.toml: the native FMU runtime's binaries, compiled into the package.

The runtime does not depend on the model, so its binaries (four variants, five platforms) are compiled once,
here, when the package is built: a wheel carries them, and ``pip install -e .`` writes them into the source
tree (``mace_fmu/fmu/native/prebuilt/``, git-ignored). The first export on a fresh machine then compiles
nothing; without this step it waits minutes while zig builds its C libraries (issue 51, item 8).
The compilation runs the ``ziglang`` of the build environment (``[build-system] requires``) and reads and
fills the user's runtime cache (``~/.cache/mace-fmu``), so a rebuild on the same machine takes seconds.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
PREBUILT = Path("mace_fmu", "fmu", "native", "prebuilt")


class BuildPyWithRuntime(build_py):
    """``build_py``, then the runtime's binaries into the built package (the source tree when editable)."""

    def run(self) -> None:
        super().run()
        target = (HERE if self.editable_mode else Path(self.build_lib)) / PREBUILT
        sys.path.insert(0, str(HERE))  # the package's own compile module, from these sources
        try:
            from mace_fmu.errors import MaceError
            from mace_fmu.fmu.native.compile import prebuild
            from mace_fmu.util.progress import Step

            start = time.monotonic()

            def say(step: Step) -> None:  # pip shows these with -v; its spinner moves with each line
                print(f"mace-fmu: {step.task}: {step.detail}", flush=True)

            try:
                self._prebuilt = prebuild(target, progress=say)
            except MaceError as exc:  # the package works without them: an export compiles what it lacks
                print(f"mace-fmu: the runtime's binaries were not compiled ({exc}); an export compiles them at "
                      "first use", flush=True)
                return
            print(f"mace-fmu: {len(self._prebuilt)} runtime binaries in {target} "
                  f"({time.monotonic() - start:.0f} s)", flush=True)
        finally:
            sys.path.remove(str(HERE))

    def get_outputs(self, include_bytecode: bool = True) -> list[str]:
        """The package's files and, in a wheel, the runtime's binaries (an editable install keeps them in the tree)."""
        outputs = super().get_outputs(include_bytecode=include_bytecode)
        if self.editable_mode:
            return outputs
        return outputs + [str(p) for p in getattr(self, "_prebuilt", [])]


setup(cmdclass={"build_py": BuildPyWithRuntime})
