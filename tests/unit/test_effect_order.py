"""effects/registry.py order_effects: an effect's declared place in its stage (``after``,
``before``) over the registry's order; stable otherwise; a cycle is refused by name."""
import pytest

from taichi_dem.effects.base import Effect
from taichi_dem.effects.registry import order_effects


def _effect(name, after=(), before=()):
    e = Effect(name, name)
    e.after, e.before = tuple(after), tuple(before)
    return e


def _names(effects):
    return [e.name for e in effects]


def test_the_given_order_stands_without_declarations():
    given = [_effect(n) for n in "abcd"]
    assert _names(order_effects(given)) == list("abcd")


def test_after_and_before_move_an_effect_and_keep_the_rest_in_order():
    given = [_effect("a", after=["c"]), _effect("b"), _effect("c"), _effect("d", before=["b"])]
    # (each time the earliest given effect whose predecessors are placed: c, then a, d, b)
    assert _names(order_effects(given)) == ["c", "a", "d", "b"]


def test_names_of_effects_not_enabled_are_ignored():
    given = [_effect("a", after=["absent"]), _effect("b", before=["absent"])]
    assert _names(order_effects(given)) == ["a", "b"]


def test_a_cycle_is_refused_naming_its_effects():
    given = [_effect("a", after=["b"]), _effect("b", after=["a"]), _effect("c")]
    with pytest.raises(ValueError, match="cycle among: a, b"):
        order_effects(given)
