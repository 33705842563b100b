"""Particle sizes (eq 53-54) and packing files."""
import numpy as np
import pytest
from scipy import stats

from packing.packing import Packing
from packing.psd import diameter_distribution, lognormal_parameters, sample_diameters


def test_eq54_parameters_give_the_mean_and_std():
    dist = diameter_distribution(0.9e-3, 0.25e-3)
    assert dist.mean() == pytest.approx(0.9e-3, rel=1e-12) and dist.std() == pytest.approx(0.25e-3, rel=1e-12)
    lam, zeta = lognormal_parameters(0.9e-3, 0.25e-3)
    assert zeta**2 == pytest.approx(np.log(1 + (0.25 / 0.9) ** 2))


def test_truncated_samples_match_the_truncated_distribution():
    rng = np.random.default_rng(0)
    d = sample_diameters(5000, 0.9e-3, 0.25e-3, 0.4e-3, 2e-3, rng)
    assert d.min() >= 0.4e-3 and d.max() <= 2e-3
    dist = diameter_distribution(0.9e-3, 0.25e-3)
    lo, hi = dist.cdf(0.4e-3), dist.cdf(2e-3)
    p = stats.kstest(d, lambda x: (dist.cdf(x) - lo) / (hi - lo)).pvalue
    assert p > 0.01
    assert np.array_equal(d, sample_diameters(5000, 0.9e-3, 0.25e-3, 0.4e-3, 2e-3, np.random.default_rng(0)))


def test_packing_roundtrip_and_validation(tmp_path):
    pk = Packing(np.array([[0.0, 1e-3], [1e-3, 0.0]]), [0.4e-3, 0.5e-3], [0, 1], [5.0, 1.0])
    pk.save(str(tmp_path / "p.csv"))
    back = Packing.load(str(tmp_path / "p.csv"))
    np.testing.assert_allclose(back.xz, pk.xz, rtol=1e-12)
    assert list(back.group) == [0, 1] and list(back.density_factor) == [5.0, 1.0]
    with pytest.raises(ValueError, match="group"):
        Packing(pk.xz, pk.r, [0, 7], [1.0, 1.0])
    with pytest.raises(ValueError, match="disc 0: r = 0.0 m: a radius must be > 0"):
        Packing(pk.xz, [0.0, 1e-3], [0, 1], [1.0, 1.0])


def _box_packing(particles):
    from engines.yade.deposition import wall_box
    walls, groups = wall_box(25, 12, 0.55e-3)
    p = np.asarray(particles, float)
    return Packing(np.vstack([p, walls]), np.full(len(p) + len(walls), 0.45e-3),
                   np.concatenate([np.zeros(len(p), int), groups]), np.ones(len(p) + len(walls)))


def test_a_packing_with_a_particle_outside_the_box_is_refused():
    from engines.yade.deposition import check_inside_box
    inside = [[5e-3, 2e-3], [20e-3, 12e-3]]  # the second is above the side walls, between them: inside
    check_inside_box(_box_packing(inside))
    for bad in ([-1e-3, 0.5e-3], [27e-3, 0.2e-3], [10e-3, -1e-3]):  # left of, right of, under the box
        pk = _box_packing(inside + [bad])
        assert pk.outside_box().tolist() == [2]
        with pytest.raises(ValueError, match="1 particle.*outside the box"):
            check_inside_box(pk, "test deposit")


def test_guard_columns_reach_above_the_given_height():
    from engines.yade.deposition import guard_columns, wall_box
    walls, _ = wall_box(25, 12, 0.55e-3)
    extra, groups = guard_columns(25, 12, 0.55e-3, 30e-3)
    assert extra[:, 1].min() > walls[:, 1].max() and extra[:, 1].max() >= 30e-3
    assert set(extra[:, 0]) == {0.0, walls[:, 0].max()} and len(groups) == len(extra)


def test_dense_top_by_count_and_wall_factor():
    from engines.yade.deposition import mark_dense_top
    rng = np.random.default_rng(0)
    pk = _box_packing(np.column_stack([1e-3 + 20e-3 * rng.random(30), 1e-3 + 10e-3 * rng.random(30)]))
    out = mark_dense_top(pk, 0.45e-3, 10.0, count=8, wall_factor=10.0)
    dense = np.flatnonzero(out.density_factor[:30] == 10.0)
    assert len(dense) == 8 and pk.xz[dense, 1].min() > np.delete(pk.xz[:30, 1], dense).max()
    assert np.all(out.density_factor[30:] == 10.0)


# -- refusals of packing rows: each names the file and the line (the header is line 1) ------------
R = 0.45e-3


def _file_with(tmp_path, row):
    """A box packing file whose line 3 (the second particle) is ``row`` (x, z, r, group, density_factor)."""
    pk = _box_packing([[5e-3, 2e-3], [10e-3, 2e-3]])
    path = tmp_path / "p.csv"
    pk.save(str(path))
    lines = path.read_text().splitlines()
    lines[2] = row
    path.write_text("\n".join(lines) + "\n")
    return str(path)


@pytest.mark.parametrize("row,why", [
    (f"10e-3,2e-3,nan,0,1", "r = nan is not a number"),
    (f"nan,2e-3,{R},0,1", "x = nan is not a number"),
    (f"10e-3,inf,{R},0,1", "z = inf is not a number"),
    (f"10e-3,2e-3,0,0,1", "r = 0.0 m: a radius must be > 0"),
    (f"10e-3,2e-3,-1e-4,0,1", "r = -0.0001 m: a radius must be > 0"),
    (f"10e-3,2e-3,{R},7,1", "group = 7.0: not a group code (0 particle, 1 bottom, 2 left, 3 right)"),
    (f"10e-3,2e-3,{R},0.5,1", "group = 0.5: not a group code"),
    (f"10e-3,2e-3,{R},0,0", "density_factor = 0.0: must be > 0"),
    (f"5e-3,2e-3,{R},0,1", "the same centre as line 2: a duplicated disc"),
])
def test_a_bad_row_is_refused_naming_the_file_and_line(tmp_path, row, why):
    path = _file_with(tmp_path, row)
    with pytest.raises(ValueError) as e:
        Packing.load(path)
    assert str(e.value).startswith(f"packing file {path}, line 3: {why}"), str(e.value)


@pytest.mark.parametrize("x,z,face", [(0.4e-3, 2e-3, "left"), (26.1e-3, 2e-3, "right"), (10e-3, 0.4e-3, "bottom"),
                                      (10e-3, 0.5, None)])
def test_a_particle_outside_the_walls_inner_faces_is_refused(tmp_path, x, z, face):
    """Inner faces: left x = 0.45 mm, right x = 26.4 - 0.45 = 25.95 mm, bottom z = 0.45 mm; open at the top."""
    pk = Packing.load(_file_with(tmp_path, f"{x},{z},{R},0,1"))
    if face is None:  # 0.5 m above the bottom, between the side walls: inside the open box
        pk.check_fit(1e-6)
        return
    with pytest.raises(ValueError, match=r", line 3: particle centre \(x, z\) = .* outside the walls' box "
                                         r"\(inner faces left x = 0.00045, right x = 0.02595, bottom z = 0.00045 m\)"):
        pk.check_fit(1e-6)


def test_an_overlap_deeper_than_the_tolerance_is_refused_and_a_shallower_one_passes(tmp_path):
    tol = 1e-6
    ok = Packing.load(_file_with(tmp_path, f"{5e-3 + 2 * R - 0.9 * tol},2e-3,{R},0,1"))
    ok.check_fit(tol, "[contact] f_max / kn")
    deep = Packing.load(_file_with(tmp_path, f"{5e-3 + 2 * R - 1.1 * tol},2e-3,{R},0,1"))
    with pytest.raises(ValueError, match=r", line 2: overlaps line 3 by 1.1e-06 m \(0.2% of the smaller radius\), "
                                         r"deeper than \[contact\] f_max / kn = 1e-06 m"):
        deep.check_fit(tol, "[contact] f_max / kn")
    on_wall = Packing.load(_file_with(tmp_path, f"1.1e-3,{2 * R - 1.1 * tol},{R},0,1"))  # on line 5, a bottom wall disc
    with pytest.raises(ValueError, match=r", line 3: overlaps line 5 by 1.1e-06 m"):
        on_wall.check_fit(tol)
    on_wall.check_fit(tol, wall_discs=False)  # flat walls in the wall discs' place: particles only
    with pytest.raises(ValueError, match=r", line 2: overlaps line 3 by 1.1e-06 m"):
        deep.check_fit(tol, wall_discs=False)


def test_overlapping_wall_discs_are_not_refused():
    """Wall discs are fixed: their overlaps among themselves hold no contact force."""
    pk = _box_packing([[5e-3, 2e-3]])
    xz = pk.xz.copy()
    xz[2, 0] = xz[1, 0] + R  # two bottom wall discs (radius R, 1.1 mm apart) made to overlap by R
    Packing(xz, pk.r, pk.group, pk.density_factor).check_fit(1e-6)
