"""Input ground motion (seed 000 §6.1): cosine, records, constant-acceleration base motion."""
import os

import numpy as np
import pytest

from engines.model import ground_motion as gm
from engines.run import scene as scenes
from tests.oracles import base_history

A, F = 15.0, 50.0           # the paper's cosine: 1500 gal, 50 Hz
W = 2 * np.pi * F


def _errors(dt, t_end=0.06):
    t, a, v, u = base_history(gm.cosine(A, F), dt, int(round(t_end / dt)))
    return np.abs(v - A / W * np.sin(W * t)).max(), np.abs(u - A / W**2 * (1 - np.cos(W * t))).max()


def test_cosine_base_motion_matches_the_exact_velocity_and_displacement():
    ev, eu = _errors(1e-5)
    assert ev < 1e-5 * A / W and eu < 1e-5 * A / W**2


def test_constant_average_acceleration_is_second_order():
    e = np.array([_errors(dt) for dt in (4e-5, 2e-5, 1e-5)])
    ratios = e[:-1] / e[1:]
    np.testing.assert_allclose(ratios, 4.0, rtol=0.05)  # halving dt divides both errors by 4


def test_exact_cases():
    """A constant acceleration gives v = c t, u = c t^2/2 exactly; a linear one (a = c t) gives the
    exact velocity c t^2/2 (the step's mean acceleration is exact for it)."""
    c = 3.0e4
    t, a, v, u = base_history(lambda tt: c + 0 * tt, 1e-3, 50)
    np.testing.assert_allclose(v, c * t, rtol=1e-12)
    np.testing.assert_allclose(u, c * t**2 / 2, rtol=1e-12)
    t, a, v, u = base_history(lambda tt: c * tt, 1e-3, 50)
    np.testing.assert_allclose(v, c * t**2 / 2, rtol=1e-12, atol=1e-15)


def test_wall_velocity_lands_the_wall_on_the_integrated_displacement():
    """x += v dt with the velocity of each step reproduces u_n (what YADE's integrator will do)."""
    bm = gm.BaseMotion(gm.cosine(A, F), 1e-6)
    x = 0.0
    for _ in range(5000):
        x += bm.step() * bm.dt
    assert abs(x - bm.disp) < 1e-15
    assert abs(bm.disp - A / W**2 * (1 - np.cos(W * bm.t))) < 1e-7 * A / W**2  # (w dt)^2 = 1e-7


def _write(tmp_path, text, name="rec.txt"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def test_record_scaling_units_and_interpolation(tmp_path):
    path = _write(tmp_path, "# t, a\n0.0 0.0\n0.02, 0.5\n0.04\t-0.5\n")
    a = gm.record_acceleration(path, time_scale=0.5, amplitude_scale=2.0, units="g")
    np.testing.assert_allclose(a(0.01), 2.0 * 0.5 * gm.G0)      # t = 0.02 s of the record
    np.testing.assert_allclose(a(0.005), 0.5 * 2.0 * 0.5 * gm.G0)  # halfway, linear
    assert a(0.03) == 0.0 and a(-1.0) == 0.0                  # after the record, before it
    assert gm.record_acceleration(path, units="gal")(0.02) == pytest.approx(0.005)
    assert gm.record_acceleration(path, units="m/s2")(0.02) == pytest.approx(0.5)


@pytest.mark.parametrize("text,match", [
    ("0.0 1.0 2.0\n0.1 1.0 2.0\n", "expected 2 columns"),
    ("0.0 1.0\n0.1\n", "line 2: expected 2 columns"),
    ("0.0 1.0\n0.1 nan\n", "line 2: non-finite"),
    ("0.0 1.0\n0.1 x\n", "not a number"),
    ("0.0 1.0\n0.2 1.0\n0.1 1.0\n", "line 3: time must increase"),
    ("0.0 1.0\n0.0 1.0\n", "time must increase"),
    ("# only a comment\n0.0 1.0\n", "at least 2 samples"),
])
def test_bad_records_are_refused_naming_the_line(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        gm.read_record(_write(tmp_path, text))


def test_missing_record_and_bad_scales(tmp_path):
    with pytest.raises(ValueError, match="not found"):
        gm.read_record(str(tmp_path / "nope.txt"))
    path = _write(tmp_path, "0 0\n1 1\n")
    with pytest.raises(ValueError, match="units"):
        gm.record_acceleration(path, units="ft/s2")
    with pytest.raises(ValueError, match="time_scale"):
        gm.record_acceleration(path, time_scale=0.0)


def test_el_centro_preset_reading():
    """Case 6: the El Centro record compressed 50x in time, its peak scaled to 1500 gal."""
    sc = scenes.preset("liquefaction_case6")
    assert os.path.isfile(sc.loading.record)
    t, a_g = gm.read_record(sc.loading.record)
    assert len(t) == 1560 and np.allclose(np.diff(t), 0.02)
    a = gm.input_acceleration(sc.settings)
    t_peak = t[np.argmax(np.abs(a_g))] * sc.loading.time_scale
    assert t_peak == pytest.approx(0.0408)
    assert abs(a(t_peak)) == pytest.approx(15.0, rel=1e-4)
    ts = np.arange(0, 0.18, 1e-5)
    assert np.abs(a(ts)).max() == pytest.approx(15.0, rel=1e-4)
    # the first 9 s of the record fill the 0.18-s run
    assert sc.numerics.duration / sc.loading.time_scale == pytest.approx(9.0)


def test_scene_adapter_cosine_and_none():
    sc = scenes.preset("liquefaction_case1")
    a = gm.input_acceleration(sc.settings)
    assert a(0.0) == pytest.approx(15.0) and a(0.01) == pytest.approx(-15.0)
    assert gm.input_acceleration(scenes.preset("quicksand_case1").settings) is None
