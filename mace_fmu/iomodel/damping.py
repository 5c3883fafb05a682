"""Open-loop modal damping ratios from mode labels (Table 4.7's measurement model)."""

from __future__ import annotations

import re

import numpy as np

from mace_fmu.iomodel.instruments import DampingTable

_VIOLIN = re.compile(r"^(\d+)(?:st|nd|rd|th) .*violin, cables? ([\d and]+)$")


def _violin_key(label: str) -> tuple[int, frozenset[int]] | None:
    """(order, cables) of a violin label such as '1st in-plane violin, cables 1 and 3'."""
    match = _VIOLIN.match(label)
    if match is None:
        return None
    return int(match.group(1)), frozenset(int(c) for c in re.findall(r"\d+", match.group(2)))


def modal_damping(labels: tuple[str, ...], frequencies_hz: np.ndarray, table: DampingTable, *,
                  zero_hz: float = 0.01) -> np.ndarray:
    """Damping ratio of every mode: zero-frequency, by mode number (a parameter set's), by label, by violin family,
    else the default."""
    zeta = np.full(len(labels), table.default)
    family_members: dict[int, list[int]] = {}
    for i, (label, f) in enumerate(zip(labels, frequencies_hz)):
        if abs(f) < zero_hz:
            zeta[i] = table.zero_frequency
        elif i + 1 in table.by_mode:
            zeta[i] = table.by_mode[i + 1]
        elif label in table.by_label:
            zeta[i] = table.by_label[label]
        elif (key := _violin_key(label)) is not None:
            order, cables = key
            for k, fam in enumerate(table.violin_families):
                if fam.order == order and cables <= fam.cables:
                    family_members.setdefault(k, []).append(i)
                    break
    for k, members in family_members.items():
        fam = table.violin_families[k]
        for rank, i in enumerate(sorted(members, key=lambda i: frequencies_hz[i])):
            zeta[i] = fam.zeta[rank] if rank < len(fam.zeta) else float(np.mean(fam.zeta))
    return zeta
