"""A folder holding exactly some installed distributions and what they require, for a fresh venv.

A new virtual environment that sees only numpy, scipy and fmpy tests that an FMU carries everything
else it needs. Installing them from the index costs ~20 s a run; linking the copies this environment
already has gives the same set of packages in well under a second.
"""

from __future__ import annotations

from importlib import metadata
from pathlib import Path

from packaging.requirements import Requirement


def _closure(names: tuple[str, ...]) -> dict[str, metadata.Distribution]:
    """Distributions named, and every requirement they have without an extra, recursively."""
    found: dict[str, metadata.Distribution] = {}
    todo = list(names)
    while todo:
        name = todo.pop()
        dist = metadata.distribution(name)
        key = dist.metadata["Name"].lower().replace("_", "-")
        if key in found:
            continue
        found[key] = dist
        for text in dist.requires or ():
            requirement = Requirement(text)
            if requirement.marker is None or requirement.marker.evaluate({"extra": ""}):
                todo.append(requirement.name)
    return found


def curated_site(folder: Path, distributions: tuple[str, ...]) -> list[str]:
    """Link the top-level entries of ``distributions`` (and their requirements) into ``folder``.

    Returns the distribution names linked. Add ``folder`` to a venv with a ``.pth`` file.
    """
    folder.mkdir(parents=True, exist_ok=True)
    linked = _closure(distributions)
    for dist in linked.values():
        for top in {Path(str(f)).parts[0] for f in dist.files or ()} - {"..", "__pycache__"}:
            source = Path(dist.locate_file(top))
            target = folder / top
            if source.exists() and not target.exists():
                target.symlink_to(source, target_is_directory=source.is_dir())
    return sorted(linked)
