"""engines.model.state: the named state of an object, stored and set again with its checks."""
from dataclasses import dataclass

import numpy as np
import pytest

from engines.model.state import StateError, restore, state_of


@dataclass
class Books:
    inflow: float = 0.0
    count: int = 0


class Inner:
    CHECKPOINT_FIELDS = ("shift",)
    CHECKPOINT_DERIVED = {}

    def __init__(self):
        self.shift = np.zeros((2, 2))


class Thing:
    CHECKPOINT_FIELDS = ("k", "x", "pairs", "walls", "prev", "books", "masks", "inner", "notes", "later")
    CHECKPOINT_RESIZED = ("pairs", "walls", "masks")
    CHECKPOINT_DERIVED = {"view": "a view of x"}

    def __init__(self):
        self.k, self.x, self.pairs = 0, np.zeros(3), np.zeros((0, 2), np.int64)
        self.walls = np.zeros((2, 4), bool)  # (W, pores): resized along its second axis
        self.view = self.x[1:]
        self.prev, self.books = None, Books()
        self.masks = {"bottom": np.zeros(4, bool), "left": np.zeros(4, bool)}
        self.inner, self.notes = Inner(), {"a": 1}

    def checkpoint_restored(self):
        if self.pairs.shape[1:] != (2,):
            raise ValueError("pairs must be (m, 2)")


def stepped():
    t = Thing()
    t.k, t.x[:] = 7, [1.0, 2.0, 3.0]
    t.pairs, t.walls = np.array([[0, 1], [1, 2]]), np.ones((2, 5), bool)
    t.prev, t.books, t.notes = np.ones((3, 2)), Books(0.5, 2), {"a": 2}
    t.masks = {"bottom": np.ones(5, bool), "left": np.zeros(5, bool)}
    t.inner.shift[:] = 0.25
    return t


def test_the_state_set_on_a_fresh_object_is_the_state_stored():
    values = state_of(stepped())
    assert "later" not in values and values["inner.shift"].shape == (2, 2)  # an absent field: left out
    fresh = Thing()
    view = fresh.view
    restore(fresh, dict(values))
    again = state_of(fresh)
    assert sorted(again) == sorted(values)
    for k, v in values.items():
        assert np.array_equal(again[k], v) if isinstance(v, np.ndarray) else again[k] == v, k
    assert np.array_equal(view, [2.0, 3.0])  # copied in place: a view of a fixed-shape array follows it
    assert fresh.walls.shape == (2, 5) and isinstance(fresh.books, Books) and fresh.books.count == 2


@pytest.mark.parametrize("edit,match", [
    (lambda v: v.pop("k"), "field k is missing"),
    (lambda v: v.update(k=1.5), "field k: expected a int, got a float"),
    (lambda v: v.update(k=None), "field k: expected a int, got null"),
    (lambda v: v.update(x=np.zeros(4)), r"field x: expected shape \(3,\), got \(4,\)"),
    (lambda v: v.update(x=np.zeros(3, np.float32)), "field x: expected an array of float64, got float32"),
    (lambda v: v.update(x=[0.0, 0.0, 0.0]), "field x: expected an array, got a list"),
    (lambda v: v.update(pairs=np.zeros(4, np.int64)), r"pairs: expected shape \(0, 2\) \(any lengths\)"),
    (lambda v: v.update(pairs=np.zeros((1, 3), np.int64)), "pairs must be"),  # the class's own check
    (lambda v: v.update(prev="x"), "prev: expected an array"),
    (lambda v: v.update(books={"inflow": 1.0}), "books: expected the fields"),
    (lambda v: v.update({"masks{}": ["bottom"]}), "masks: expected the keys"),
    (lambda v: v.update(notes=[1]), "notes: expected a dict"),
])
def test_stored_values_that_do_not_fit_are_refused_by_name(edit, match):
    values = state_of(stepped())
    edit(values)
    with pytest.raises(StateError, match=match):
        restore(Thing(), values)


def test_what_is_not_data_is_refused_when_stored():
    t = stepped()
    t.notes = {"a": object()}
    with pytest.raises(TypeError, match="notes: a object is not data"):
        state_of(t)
    t.notes, t.x = {}, np.array([object()])
    with pytest.raises(TypeError, match="array of object is not numbers"):
        state_of(t)


def test_leftover_values_stay_for_the_caller():
    values = state_of(stepped()) | {"unknown": 1}
    restore(Thing(), values)
    assert values == {"unknown": 1}
