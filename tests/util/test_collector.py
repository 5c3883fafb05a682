"""The collector pause is scoped: the collector is as it was afterwards, also after an error, and a user's
own pause is kept."""

from __future__ import annotations

import gc

import pytest

from mace_fmu.util.collector import collector_paused


def test_the_collector_is_paused_inside_and_restored_after_an_error():
    assert gc.isenabled()
    with pytest.raises(RuntimeError):
        with collector_paused():
            assert not gc.isenabled()
            raise RuntimeError("inside")
    assert gc.isenabled()


def test_a_users_own_pause_is_kept_and_the_decorator_form_works():
    @collector_paused()
    def inside() -> bool:
        return gc.isenabled()

    assert inside() is False and gc.isenabled()
    gc.disable()
    try:
        assert inside() is False
        assert not gc.isenabled()  # the user's pause outlives ours
    finally:
        gc.enable()
