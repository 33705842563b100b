"""The one schedule of a step (engines.model.schedule.Schedule): water, rebuilds, output, the next event."""
import math
import os
import re

import numpy as np
import pytest

from engines.model.schedule import Schedule

ENGINES = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "engines")


def test_water_steps_are_counted_from_the_start():
    for k0, wi in ((0, 1), (0, 3), (2000, 10), (7, 4)):
        s = Schedule(water_interval=wi, k0=k0)
        due = [k for k in range(k0, k0 + 40) if s.water_due(k)]
        assert due == list(range(k0, k0 + 40, wi))
        for k in range(k0, k0 + 40):
            nxt = next(j for j in range(k, k + wi + 1) if s.water_due(j))
            assert s.steps_to_water(k) == nxt - k
            assert s.last_water(k) == max(j for j in range(k0, k + 1) if s.water_due(j))
            for end in range(k, k + 2 * wi):
                assert s.water_among(k, end) == any(s.water_due(j) for j in range(k, end))


def test_a_new_water_interval_starts_at_the_next_water_step():
    s = Schedule(water_interval=3, rebuild_interval=10, k0=2)
    assert s.set_water_interval(5, 6) == 8  # the old water steps 2, 5, 8: the next is 8
    assert [k for k in range(6, 30) if s.water_due(k)] == [8, 13, 18, 23, 28]
    assert s.steps_to_rebuild(9, water_steps_only=True) == 13 - 9  # due at 12, asked at 13
    assert s.set_water_interval(2, 13) == 13 and s.last_water(16) == 15
    with pytest.raises(ValueError, match="water_interval must be >= 1"):
        s.set_water_interval(0, 13)


def test_rebuilds_by_interval_displacement_and_areas():
    s = Schedule(water_interval=3, rebuild_interval=10, rebuild_distance=0.0)
    assert [k for k in range(35) if s.interval_due(k)] == list(range(10, 35))  # never built since 0
    s.built(12)
    assert not s.rebuild_due(19, max_sq_moved=1.0)  # no rebuild_distance: displacement ignored
    assert s.rebuild_due(20) and s.steps_to_rebuild(12) == 8 and s.steps_to_rebuild(12, water_steps_only=True) == 9
    assert not s.areas_due(np.array([-1.0]), np.array([1.0]))
    d = Schedule(rebuild_interval=10, rebuild_distance=0.5)
    assert d.moved2 == 0.25 and d.by_displacement
    assert not d.rebuild_due(3, 0.25) and d.rebuild_due(3, 0.25 + 1e-12)
    assert d.areas_due(np.array([0.5, -1e-30]), np.array([1.0, 1.0])) and not d.areas_due(np.ones(2), np.ones(2))
    dry = Schedule(rebuild_interval=None)
    assert not dry.rebuild_due(10**9) and dry.steps_to_rebuild(5) == math.inf


def test_output_steps_and_the_next_event():
    s = Schedule(water_interval=2, rebuild_interval=100)
    assert s.steps_to_event(0) == 100 and not s.output_due(0)
    s.set_output(30, [45, 7])
    assert [k for k in range(100) if s.output_due(k)] == [0, 7, 30, 45, 60, 90]
    assert [s.steps_to_output(k) for k in (0, 7, 44, 91)] == [7, 23, 1, 29]
    assert s.steps_to_event(95) == 5 and s.steps_to_event(85) == 5 and s.steps_to_event(61) == 29
    s.set_output(0)
    assert s.steps_to_output(3) == math.inf


@pytest.mark.parametrize("bad", [{"water_interval": 0}, {"rebuild_interval": 0}, {"rebuild_distance": -1.0}])
def test_bad_intervals_are_refused(bad):
    with pytest.raises(ValueError):
        Schedule(**bad)


def test_no_code_outside_the_schedule_and_the_reference_decides_a_water_step():
    pattern = re.compile(r"%\s*\(?\s*[\w.]*\b(water_interval|wi)\b")  # k % wi, (k - k0) % m.water_interval, ...
    found = []
    for folder, _, files in os.walk(ENGINES):
        for name in files:
            path = os.path.join(folder, name)
            rel = os.path.relpath(path, ENGINES)
            if not name.endswith(".py") or rel.startswith("reference") or rel == os.path.join("model", "schedule.py"):
                continue
            with open(path) as f:
                found += [f"{rel}:{n}" for n, line in enumerate(f, 1) if pattern.search(line)]
    assert found == []
