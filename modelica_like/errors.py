"""The one exception type of ``modelica_like``."""

from __future__ import annotations


class ModelError(ValueError):
    """A block diagram that cannot be built or compiled.

    The message names the blocks/connectors involved and says what was expected, e.g.
    ``size mismatch: plant.y has size 2 but k.u has size 1``.
    """
