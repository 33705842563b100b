"""The verdict on the paper's statement by band (engines.studies.liquefaction.band_verdicts): zero
effective stress when the whole 95 % interval of min p'/p'_0 lies below P_RATIO_LIQUEFIED; bands near
the surface reported, not judged; the starts where r_u reached RU_LIQUEFIED counted."""
from engines.studies.liquefaction import P_RATIO_LIQUEFIED, band_verdicts


def interval(mean, low, high, values=(0.0,)):
    return {"n": len(values), "mean": mean, "ci95_low": low, "ci95_high": high, "values": list(values)}


def results(p_low_high, t_values=(None, None)):
    out = {}
    for k, (lo, hi) in enumerate(p_low_high, 1):
        out[f"bands.band{k}.p_ratio_min"] = interval((lo + hi) / 2, lo, hi)
        out[f"bands.band{k}.ru_max"] = interval(0.5, 0.4, 0.6)
        out[f"bands.band{k}.t_ru_0p9_s"] = interval(None, None, None, t_values)
    return out


def test_a_band_liquefies_only_when_its_whole_interval_lies_below_the_limit():
    eps = 1e-3
    r = results([(0.0, P_RATIO_LIQUEFIED - eps), (0.0, P_RATIO_LIQUEFIED + eps), (0.3, 0.4)], t_values=(0.01, None))
    v = band_verdicts(r, counted=[0, 1, 2])
    assert [v[b]["liquefied"] for b in ("band1", "band2", "band3")] == [True, False, False]
    assert v["band1"]["starts_ru_0p9"] == [1, 2]


def test_bands_near_the_surface_are_reported_not_judged_and_dry_bands_have_no_r_u():
    r = results([(0.3, 0.4), (-0.1, 0.0)])
    del r["bands.band1.ru_max"], r["bands.band1.t_ru_0p9_s"]
    v = band_verdicts(r, counted=[0])
    assert v["band2"]["judged"] is False and v["band2"]["liquefied"] is None  # its p' at zero is no verdict
    assert v["band1"]["ru_max"] is None and v["band1"]["starts_ru_0p9"] is None and v["band1"]["liquefied"] is False
    assert list(v) == ["band1", "band2"]
