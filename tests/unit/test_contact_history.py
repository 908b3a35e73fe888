"""Contact history owned by the effects that keep it (contacts/history.py, issue 30 item 3):
the History record is made of the values the enabled contact effects declare, and one load /
store / clear / take serves every storage (neighbour entries, (particle, wall) slots, mesh
contacts). The physics through it is checked by the contact tests (Chung-Ooi, rolling
friction on planes and meshes, mesh edges, resume bit for bit)."""
import numpy as np
import pytest
import taichi as ti

from taichi_dem.contacts.history import history_members, make_history_io, make_history_type
from taichi_dem.effects.base import Effect
from taichi_dem.effects.hertz_mindlin import HertzMindlin
from taichi_dem.effects.rolling import RollingConstantTorque, RollingEPSD
from taichi_dem.engine import backend


class _Bond(Effect):
    """A contact effect keeping a history value of its own (as a bonded-particle model would)."""
    name, stage, kinds, mechanical = "bond", "contact", ("pair",), True
    contact_fields = {"bond_history": (True, "real")}


def test_the_record_holds_what_the_enabled_effects_keep():
    hm = HertzMindlin("")
    assert history_members([hm]) == ("tangential",)
    assert history_members([hm, RollingConstantTorque("")]) == ("tangential",)
    assert history_members([hm, RollingEPSD("")]) == ("tangential", "rolling")
    assert history_members([hm, RollingEPSD(""), _Bond("")]) == ("tangential", "rolling", "bond")


class _Owner:
    """Stands for a simulation living on the runtime while this test's fields exist."""
    def _mark_stale(self, why):
        pass


@pytest.fixture
def runtime():
    owner = _Owner()
    backend.acquire(owner, "cpu", "f64")
    yield
    backend.release(owner)


def test_load_store_clear_and_take_on_one_and_two_index_storage(runtime):
    members = ("tangential", "rolling")
    History = make_history_type(ti.f64, members)
    entry = {m: ti.Vector.field(3, ti.f64, 4) for m in members}          # per neighbour entry
    slot = {m: ti.Vector.field(3, ti.f64, (3, 2)) for m in members}      # per (particle, wall)
    pairs = make_history_io(History, members, entry)
    walls = make_history_io(History, members, slot)

    @ti.kernel
    def exercise():
        entry["tangential"][1] = ti.Vector([1.0, 2.0, 3.0])
        entry["rolling"][1] = ti.Vector([4.0, 5.0, 6.0])
        h = pairs.load(1)
        h.tangential *= 2.0
        pairs.store(2, h)                       # a copy, doubled
        pairs.clear(1)                          # the contact opened
        walls.store(ti.Vector([2, 1]), pairs.take(3, 2))    # moved on: 2 is emptied
        e = pairs.empty()
        pairs.store(0, e)

    for f in list(entry.values()) + list(slot.values()):
        f.fill(9.0)
    exercise()
    t, r = entry["tangential"].to_numpy(), entry["rolling"].to_numpy()
    np.testing.assert_array_equal(t[[0, 1, 2]], 0.0)
    np.testing.assert_array_equal(r[[0, 1, 2]], 0.0)
    np.testing.assert_array_equal(t[3], 9.0)                     # untouched
    np.testing.assert_array_equal(slot["tangential"].to_numpy()[2, 1], [2.0, 4.0, 6.0])
    np.testing.assert_array_equal(slot["rolling"].to_numpy()[2, 1], [4.0, 5.0, 6.0])
    np.testing.assert_array_equal(slot["rolling"].to_numpy()[0, 0], 9.0)


def test_a_storage_must_hold_every_value():
    with pytest.raises(AssertionError, match="rolling"):
        make_history_io(None, ("tangential", "rolling"), {"tangential": object(), "rolling": None})
