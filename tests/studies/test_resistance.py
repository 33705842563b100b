"""The resistance curve's analysis (engines.studies.resistance) on synthetic histories: N_L at the
right cycle, the near-surface bands ignored, censoring, the CSR of a known sinusoid, the simplified
CSR, the median's order-statistic interval, the Wilson interval and the statements (no YADE)."""
import numpy as np
import pytest

from engines.studies import resistance as rs

F = 50.0          # Hz
DT = 1e-4         # s between rows
BOUNDS = [(0.001 * k, 0.001 * (k + 1)) for k in range(8)]  # 8 bands of 1 mm, bed top 8 mm
D = 1e-3          # mean diameter [m]: bands 7 and 8 (tops above 6 mm) lie within 2 D of the top


def summary():
    return {"band_bounds_m": BOUNDS, "band_overburden_Pa": [400.0 - 40 * k for k in range(8)],
            "parameters": {"packing": {"mean_diameter": D}, "material": {"g": 9.81, "rho_w": 1000.0}}}


def history(ru_of_band, cycles=rs.CYCLES, tau=100.0, sv0=400.0):
    """A history of ``cycles`` cycles: r_u per band from ru_of_band(k, t), sigma'_xz of amplitude
    ``tau`` [Pa] around an offset with a small drift, sigma'_v0 = sv0 [Pa] in every band."""
    t = np.arange(0.0, cycles / F + DT / 2, DT)
    h = {"t": t, "bed_top": np.full(len(t), 0.008)}
    for k in range(8):
        h[f"ru_band{k + 1}"] = ru_of_band(k, t)
        h[f"sv_band{k + 1}"] = np.full(len(t), sv0)
        h[f"sxz_band{k + 1}"] = 5.0 + 20.0 * t + tau * np.cos(2 * np.pi * F * t + 0.3 * k)
    return h


def test_n_l_is_the_cycle_where_a_bands_cycle_mean_ru_reaches_0p9_and_the_surface_bands_do_not_count():
    # band 3 rises linearly at 0.9 per 10 cycles under a swing of +-0.5 a cycle: its trailing
    # one-cycle mean is 0.09 (N - 1/2) per cycle, 0.9 at N = 10.5; band 2 gets there at N = 20.5;
    # band 8 (within 2 D of the top) is at 5 throughout and must not count
    def ru(k, t):
        swing = 0.5 * np.sin(2 * np.pi * F * t)
        return {2: 0.09 * F * t + swing, 1: 0.045 * F * t + swing, 7: np.full(len(t), 5.0)}.get(k, 0.1 + swing)

    r = rs.run_reading(history(ru), summary(), F, 15.0)
    assert r["n_l"] == pytest.approx(10.5, abs=F * DT + 1e-9) and r["band"] == 3 and not r["censored"]
    assert rs.counted_bands(BOUNDS, 0.008, D) == [0, 1, 2, 3, 4, 5]


def test_a_run_that_never_gets_there_is_censored_on_its_band_of_largest_ru_and_a_short_one_is_refused():
    def ru(k, t):
        return np.full(len(t), 0.2 + 0.1 * (k == 4) + 2.0 * (k == 6))  # band 7 (near the top) ignored

    r = rs.run_reading(history(ru), summary(), F, 15.0)
    assert r["censored"] and r["n_l"] is None and r["band"] == 5 and r["ru_cycle_mean_max"] == pytest.approx(0.3)
    with pytest.raises(ValueError, match="did not liquefy"):
        rs.run_reading(history(ru, cycles=12), summary(), F, 15.0)
    short = rs.run_reading(history(ru, cycles=12), summary(), F, 15.0, cycles=12)
    assert short["censored"]
    # a band that liquefies after the censoring cycles is censored too
    late = rs.run_reading(history(lambda k, t: 0.03 * F * t), summary(), F, 15.0, cycles=20)
    assert late["censored"]


def test_csr_is_the_amplitude_of_a_known_sinusoid_over_sigma_v0_and_the_simplified_csr_its_formula():
    r = rs.run_reading(history(lambda k, t: np.zeros(len(t)), tau=123.0, sv0=410.0), summary(), F, 15.0)
    assert r["csr"] == pytest.approx(123.0 / 410.0, rel=1e-6) and r["tau_amplitude_Pa"] == pytest.approx(123.0, rel=1e-6)
    band = r["band"] - 1
    depth = 0.008 - 0.5 * sum(BOUNDS[band])
    ob = 400.0 - 40 * band
    assert r["csr_simplified"] == pytest.approx(0.65 * 15.0 / 9.81 * (ob + 1000 * 9.81 * depth) / ob, rel=1e-12)
    assert rs.sinusoid_amplitude(np.linspace(0, 0.06, 601), 3.0 * np.sin(2 * np.pi * F * np.linspace(0, 0.06, 601)), F) == \
        pytest.approx(3.0, rel=1e-9)


def test_cycle_mean_is_the_trailing_one_period_mean_and_skips_gaps():
    t = np.arange(0, 0.1 + 1e-12, 1e-3)  # 50 rows a period of 20 ms
    y = np.where(np.arange(len(t)) == 40, np.nan, t)
    m = rs.cycle_mean(t, y, F)
    assert np.all(np.isnan(m[t < 0.02 - 1e-12]))
    k = 60  # rows 41..60 (t in (0.04, 0.06]), row 40 not among them
    assert m[k] == pytest.approx(np.mean(t[41:61]))
    assert m[50] == pytest.approx(np.mean(t[31:51][t[31:51] != t[40]]))


def test_the_median_interval_of_order_statistics_with_censored_runs_and_its_coverage():
    m = rs.median_interval([3.0, None, 5.0, 7.0, None, 2.0, 4.0, 9.0])
    # 8 starts: [x(1), x(8)] covers 1 - 2/256; [x(2), x(7)] only 1 - 18/256 < 95 %
    assert m == {"median": 5.0, "low": 2.0, "high": None, "coverage": pytest.approx(1 - 2 / 256)}
    assert rs.median_interval([None, None, 1.0])["median"] is None  # most censored: the median is censored
    big = rs.median_interval(list(np.arange(1.0, 21.0)))  # 20 starts: j = 6, coverage 1 - 2 P(B <= 5) = 0.9586
    assert (big["low"], big["high"], big["median"]) == (6.0, 15.0, 10.0) and big["coverage"] == pytest.approx(0.9586, abs=1e-4)
    lo, hi = rs.wilson(4, 8)
    assert (lo, hi) == (pytest.approx(0.2152, abs=1e-4), pytest.approx(0.7848, abs=1e-4))


def _row(a, csr, n_l):
    vals = [n_l] * 4
    return {"amplitude_m_s2": a, **rs.group_reading([{"n_l": v, "band": 1, "ru_cycle_mean_max": 1.0, "csr": csr * (1 + 0.01 * i), "csr_simplified": 1.0}
                                                     for i, v in enumerate(vals)])}


def test_statements_decide_only_where_rows_separate_in_both():
    loose = {"rows": [_row(15.0, 0.2, None), _row(30.0, 0.4, 3.0)]}
    dense = {"rows": [_row(15.0, 0.2, None), _row(30.0, 0.4, 12.0)]}
    s = rs.statements({"loose": loose, "dense": dense})
    assert s["csr_falls_with_n_l"]["loose"].startswith("CSR falls")
    assert s["loose_below_dense"]["30 m/s^2"].endswith("loose lies below")
    assert s["loose_below_dense"]["15 m/s^2"] == "undecided with these intervals"
    one = {"rows": [_row(15.0, 0.2, 5.0), _row(30.0, 0.201, 3.0)]}  # CSR intervals overlap
    assert rs.statements({"loose": one})["csr_falls_with_n_l"]["loose"].startswith("undecided")


def test_each_rows_peak_ru_is_summed_up_over_the_starts_that_ran_a_cycle():
    """ru_peak: the mean, Student's interval and largest of the starts' largest cycle-mean r_u,
    a start shorter than a cycle (None) left out; none at all: no largest."""
    runs = [{"n_l": None, "band": 1, "ru_cycle_mean_max": v, "csr": 0.3, "csr_simplified": 1.0} for v in (0.4, 0.6, None)]
    peak = rs.group_reading(runs)["ru_peak"]
    assert peak["mean"] == pytest.approx(0.5) and peak["max"] == 0.6 and peak["values"] == [0.4, 0.6, None]
    assert peak["ci95_low"] < 0.4 and peak["ci95_high"] > 0.6
    assert rs.group_reading(runs[2:])["ru_peak"]["max"] is None
