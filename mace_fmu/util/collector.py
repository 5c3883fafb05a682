"""Python's cyclic garbage collector paused while a large deck becomes objects.

Reading a 100k-DOF deck makes about 400,000 objects (cards, their fields, their records), none of them in a
reference cycle. The collector's passes are triggered by the count of new objects and walk every object
still alive, so they grow with the deck: on the wide lattice (95,459 cards) they took a third of the
reading (2.7-3.1 s with them, 1.6-2.3 s without). While the deck stays alive, every later pass walks it
again: the 50 modes of the same lattice took 14.7 s with the collector and 13.8 s without (assembly 1.2 ->
0.8 s, constraints 0.6 -> 0.3 s). Memory is unaffected: objects without cycles are freed by their reference
counts, collector or not; the few cycles made in the block (thread pools, exceptions) wait until it ends.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def collector_paused() -> Iterator[None]:
    """Pause the cyclic garbage collector in the ``with`` block or the decorated function (as it was before
    afterwards, also on errors)."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()
