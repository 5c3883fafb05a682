"""The structure data file that goes with a deck (default: the bundled mace_em.toml)."""

from __future__ import annotations

import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

from mace_fmu.errors import MaceError


def data_file_path(path: str | Path | None = None) -> Path:
    """``path``, or the bundled mace_em.toml when None."""
    return Path(path) if path is not None else Path(str(resources.files("mace_fmu") / "data" / "mace_em.toml"))


def read_data_file(path: Path, *, what: str) -> dict[str, Any]:
    """The parsed TOML file, or a MaceError naming the file and ``what`` was being read."""
    try:
        return tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise MaceError(f"{path}: cannot read the {what}: {exc}") from None
