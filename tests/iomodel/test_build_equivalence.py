"""The faster model build gives the same models as the implementation before it.

Before: ``System.compile`` was ``control.interconnect``, which linearises the interconnected system
numerically. Now the wiring algebra (``modelica_like.algebra.interconnect``) gives the matrices
directly. Both are built here from the same diagrams, with the same single BLAS thread the build
now uses, and compared: state order and names, poles, frequency responses and DC gains.

Tolerances: 1e-10. The frequency response is compared relative to the largest response of the
same input (every output is in volts); per channel, a weak cross-coupling channel (tach_x from
rwa_z, 1-g) differs by 1.9e-9 of its own peak, and so do the previous implementation and a
third, block-by-block evaluation from each other (8e-10): that is the floor of double precision
for that channel, not a change of the model.
"""

from __future__ import annotations

import control as ct
import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import linear_sum_assignment
from threadpoolctl import threadpool_limits

from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.frf import frequency_response
from mace_fmu.iomodel.volts import volts_model
from modelica_like import System

FREQUENCIES_HZ = np.geomspace(0.05, 250.0, 60)


def interconnect_as_before(system: System) -> ct.StateSpace:
    """The previous ``System.compile``: control.interconnect of the blocks (numerical linearisation)."""
    ic = system.connection_matrices()
    blocks = list(ic.blocks)
    position = {b.name: k for k, b in enumerate(blocks)}

    def spec(e):
        b = system._blocks[e.block]
        return position[e.block], b.offset(e.port) + e.index

    connections = [[spec(dst), spec(src)] for dst, src in system._drivers.items() if hasattr(src, "block")]
    return ct.interconnect([b.lti() for b in blocks], connections=connections or False,
                           inplist=[[spec(e) for e in dests] for dests in system._inputs.values()],
                           outlist=[spec(e) for e in system._outputs.values()], inputs=list(system._inputs),
                           outputs=list(system._outputs), states=[f"{b.name}.{s}" for b in blocks for s in b.states],
                           name="before", dt=0, check_unused=False, warn_duplicate=False)


@pytest.fixture(scope="module", params=["1g", "0g"])
def both(request):
    model = volts_model(compute_modes(configuration=request.param))
    with threadpool_limits(limits=1, user_api="blas"):
        before = interconnect_as_before(model.diagram)
    return model, before


def test_same_signals_and_states(both) -> None:
    model, before = both
    assert list(model.system.state_labels) == list(before.state_labels)
    assert list(model.system.input_labels) == list(before.input_labels)
    assert list(model.system.output_labels) == list(before.output_labels)


def test_same_poles(both) -> None:
    model, before = both
    new, old = np.linalg.eigvals(model.system.A), np.linalg.eigvals(before.A)
    distance = np.abs(new[:, None] - old[None, :])
    rows, cols = linear_sum_assignment(distance)  # each new pole paired with one old pole
    assert np.max(distance[rows, cols] / np.maximum(np.abs(old[cols]), 1.0)) <= 1e-10


def test_same_frequency_responses_and_dc_gains(both) -> None:
    model, before = both
    old = frequency_response(before, FREQUENCIES_HZ)
    column_peak = np.abs(old).max(axis=(0, 1), keepdims=True)
    for new in (frequency_response(model.system, FREQUENCIES_HZ), model.frequency_response(FREQUENCIES_HZ)):
        assert np.max(np.abs(new - old) / column_peak) <= 1e-10
    dc_new = model.system.C @ np.linalg.solve(-model.system.A, model.system.B) + model.system.D
    dc_old = before.C @ np.linalg.solve(-before.A, before.B) + before.D
    assert np.max(np.abs(dc_new - dc_old)) <= 1e-10 * np.abs(dc_old).max()


def test_compiled_matrices_against_a_block_by_block_evaluation(both) -> None:
    """An independent route: each block's response at s, then the wiring solved at s, no A, B, C, D.

    H(s) = F G(s) (I - L G(s))^-1 E with G(s) the blocks' responses side by side; against
    C (sI - A)^-1 B + D of the compiled system (control's direct solves), per channel."""
    model, _ = both
    ic = model.diagram.connection_matrices()
    frequencies = FREQUENCIES_HZ[::4]
    blockwise = []
    for f in frequencies:
        s = 2j * np.pi * f
        g = sla.block_diag(*[b.D + (b.C @ np.linalg.solve(s * np.eye(len(b.A)) - b.A, b.B) if len(b.A) else 0.0)
                             for b in ic.blocks])
        blockwise.append(ic.exit @ g @ np.linalg.solve(np.eye(g.shape[1]) - ic.wiring @ g, ic.entry))
    blockwise = np.array(blockwise)
    compiled = model.diagram.compile()
    ours = np.moveaxis(np.asarray(ct.frequency_response(compiled, 2 * np.pi * frequencies).frdata), -1, 0)
    assert np.max(np.abs(ours - blockwise) / np.abs(blockwise).max(axis=0, keepdims=True).clip(1e-300)) <= 1e-10
