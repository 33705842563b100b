"""Seed 003 without YADE: Table 1 sizes, side loads, E50, the Mohr–Coulomb fit, eq 4–6, tiling."""
import math

import numpy as np
import pytest

from engines.seeds.biaxial.calibration import Calibration, eq4_e50, eq6_kn, fit_eq4
from engines.seeds.biaxial.cem_contact import (
    TABLE2_DT,
    CemContact,
    disc_mass,
    pair_constants,
    series,
    single_contact_dt_limit,
)
from engines.seeds.biaxial.periodic import PeriodicBlock, cell_for, random_placement, table1_radii, tile
from engines.seeds.biaxial.specimen import (
    BOTTOM,
    INTERIOR,
    LEFT,
    RIGHT,
    TOP,
    assign_groups,
    covered_height,
    e50,
    exposed_lengths,
    mohr_coulomb_fit,
    side_forces,
)
from packing.packing import Packing
from tests.oracles import love_stress, section_stress


def test_table1_counts_give_the_papers_volume_ratio():
    r = table1_radii(1000)
    counts = [int(np.sum(r == v)) for v in (1.4e-3, 2.8e-3, 3.2e-3)]
    assert counts == [663, 235, 102] and len(r) == 1000
    area = [c * v ** 2 for c, v in zip(counts, (1.4e-3, 2.8e-3, 3.2e-3))]
    # Table 1 states ΣV1 : ΣV2 : ΣV3 = 1.24 : 1.76 : 1 for N1 : N2 : N3 = 6.48 : 2.30 : 1
    np.testing.assert_allclose(np.array(area) / area[2], [1.24, 1.76, 1.0], atol=0.01)


def test_random_placement_has_no_overlap_across_the_periodic_edges():
    r = table1_radii(200)
    cell = cell_for(r, 0.5, 0.7)
    xz = random_placement(r, cell, np.random.default_rng(3))
    d = xz[:, None, :] - xz[None, :, :]
    d -= np.round(d / cell) * cell
    gap = np.hypot(d[..., 0], d[..., 1]) - r[:, None] - r[None, :]
    np.fill_diagonal(gap, 1.0)
    assert gap.min() > 0 and np.all((xz >= 0) & (xz < cell))


def test_contact_constants_are_the_papers_springs_per_unit_thickness():
    c = CemContact(kn=1e8, ks_ratio=0.25, phi_e_deg=15)
    kn, ks, cn, cs = pair_constants(2e-3, 2e-3, c)
    assert kn == pytest.approx(1e8 * 2e-3) and ks == pytest.approx(0.25 * kn)  # equal discs: width w = r
    m_star = 2500 * math.pi * 4e-6 / 2
    assert cn == pytest.approx(2 * math.sqrt(m_star * kn))  # critical
    for r1, r2 in [(1.4e-3, 3.2e-3), (1.4e-3, 2.8e-3), (2.8e-3, 3.2e-3)]:  # zeta_n = c_n / (2 sqrt(m* k_n))
        kn, _, cn, _ = pair_constants(r1, r2, c)
        assert abs(cn / (2 * np.sqrt(series(disc_mass(r1, c.rho), disc_mass(r2, c.rho)) * kn)) - 1) < 0.015
    # one contact of the lightest pair, leapfrog with a critical dashpot: ω dt <= 2(√2 − 1)
    omega = math.sqrt(1e8 * 1.4e-3 / (2500 * math.pi * 1.4e-3 ** 2 / 2))
    assert single_contact_dt_limit(table1_radii(100), c) == pytest.approx(2 * (math.sqrt(2) - 1) / omega)
    with pytest.raises(ValueError, match="phi_e_deg"):
        CemContact(phi_e_deg=90)


def test_groups_follow_fig2():
    xz = np.array([[0.5, 0.5], [0.05, 0.5], [0.95, 0.5], [0.5, 0.95], [0.5, 0.05], [0.05, 0.05], [0.95, 0.95]])
    assert assign_groups(xz, (1.0, 1.0), 0.1).tolist() == [INTERIOR, LEFT, RIGHT, TOP, BOTTOM, BOTTOM, TOP]
    with pytest.raises(ValueError, match="band"):
        assign_groups(xz, (1.0, 1.0), 0.5)


def test_exposed_side_loads_add_up_to_sigma3_times_the_covered_height():
    # a disc further in and half hidden shows only what sticks out
    assert exposed_lengths([-1.0, -0.5], [1.0, 1.5], [2.0, 1.0]).tolist() == [2.0, 0.5]
    rng = np.random.default_rng(0)
    for _ in range(20):
        n = 30
        z = rng.random(n) * 0.1
        r = 2e-3 + 2e-3 * rng.random(n)
        x = rng.random(n) * 6e-3
        groups = np.where(rng.random(n) < 0.5, LEFT, RIGHT)
        f = side_forces(np.column_stack([x, z]), r, groups, 150.0, "exposed")
        for g, sign in ((LEFT, 1), (RIGHT, -1)):
            m = groups == g
            assert sign * f[m].sum() == pytest.approx(150.0 * covered_height(z[m], r[m]), rel=1e-12)
            assert np.all(sign * f[m] >= 0)
        lit = side_forces(np.column_stack([x, z]), r, groups, 150.0, "diameter")
        assert np.abs(lit).sum() == pytest.approx(150.0 * 2 * r.sum())


def test_e50_of_a_bilinear_curve_with_a_stick_slip_plateau():
    eps = np.linspace(0, 0.05, 501)
    q = np.minimum(2e4 * eps, 300.0)  # linear to 1.5 %, then a plateau
    assert e50(eps, q) == pytest.approx(2e4, rel=1e-9)
    q[300:310] = 100.0  # a slip on the plateau dips below half the peak: not the loading branch
    assert e50(eps, q) == pytest.approx(2e4, rel=1e-9)


def test_mohr_coulomb_fit_recovers_a_known_envelope():
    phi, c = math.radians(27.4), 0.4
    s3 = np.array([100.0, 200, 300, 400])
    N = math.tan(math.pi / 4 + phi / 2) ** 2
    s1 = s3 * N + 2 * c * math.sqrt(N)  # σ1 at failure on τ = c + σ tan φ
    p, cc = mohr_coulomb_fit(s3, s1)
    assert p == pytest.approx(27.4, abs=1e-9) and cc == pytest.approx(0.4, abs=1e-9)
    with pytest.raises(ValueError, match="two or more"):
        mohr_coulomb_fit([100.0], [300.0])


def test_eq4_fit_and_eq6_invert_each_other():
    A, m = 3.0e-3, -0.62
    s3 = np.array([100.0, 200, 300, 400])
    kn = np.array([1e8, 1e8, 5e7, 2e8])
    e = eq4_e50(s3, kn, A, m)
    assert fit_eq4(s3, kn, e) == pytest.approx((A, m), rel=1e-9)
    k = eq6_kn(e[1], s3[1], A, m)
    assert k == pytest.approx(1e8, rel=1e-12)
    assert eq4_e50(s3[1], k, A, m) == pytest.approx(e[1], rel=1e-12)


def test_calibration_inverts_its_curves_and_refuses_extrapolation():
    cal = Calibration([5.0, 10.0, 15.0], [16.0, 22.0, 27.0], [1e-3, 2e-3, 4e-3], [-0.5, -0.6, -0.7], 1e8, 0.25)
    phi_e, kn = cal.invert(24.0, 1e4, 200.0)
    assert phi_e == pytest.approx(12.0)
    A, m = cal.eq4_at(12.0)
    assert A == pytest.approx(math.exp(0.6 * math.log(2e-3) + 0.4 * math.log(4e-3)))
    assert eq4_e50(200.0, kn, A, m) == pytest.approx(1e4, rel=1e-12)
    with pytest.raises(ValueError, match="--phi-star"):
        cal.invert(30.0, 1e4, 200.0)
    with pytest.raises(ValueError, match="--e50"):
        cal.invert(24.0, -1.0, 200.0)


def test_love_and_section_stress_of_a_square_lattice():
    # nx x nz discs of radius r touching on a square lattice in a periodic cell, every contact
    # pressed with F: σxx = σzz = F / (2 r) both ways
    nx, nz, r, F = 5, 4, 1e-3, 0.3
    cell = (nx * 2 * r, nz * 2 * r)
    i, j = np.meshgrid(np.arange(nx), np.arange(nz), indexing="ij")
    xz = np.column_stack([i.ravel(), j.ravel()]) * 2 * r + r / 2
    branch = np.vstack([np.tile([2 * r, 0.0], (nx * nz, 1)), np.tile([0.0, 2 * r], (nx * nz, 1))])
    force = branch / (2 * r) * F
    first = np.vstack([xz, xz])
    sig = love_stress(force, branch, cell[0] * cell[1])
    np.testing.assert_allclose(sig, [[F / (2 * r), 0], [0, F / (2 * r)]], rtol=1e-12)
    for at in (0.0, 0.3 * cell[0], 0.99 * cell[0]):
        assert section_stress(first, branch, force, 0, at, cell) == pytest.approx(F / (2 * r), rel=1e-12)
    assert section_stress(first, branch, force, 1, 0.5 * cell[1], cell) == pytest.approx(F / (2 * r), rel=1e-12)


def test_tiling_repeats_the_block_with_seams_as_in_the_cell(tmp_path):
    rng = np.random.default_rng(1)
    r = table1_radii(60)
    cell = cell_for(r, 0.5, 0.75)
    block = PeriodicBlock(random_placement(r, cell, rng), r, cell, (100.0, 100.0), {})
    pk = tile(block, 3, 3)
    assert len(pk.r) == 9 * len(r) and np.all(pk.group == 0)
    # every disc of the middle copy has, inside the tiled model, the same neighbours (gaps) as its
    # periodic images gave it in the cell
    mid = np.arange(len(r)) + (1 * 3 + 1) * len(r)  # copy (i, j) = (1, 1): surrounded on every side
    d_tile = np.hypot(*(pk.xz[mid][:, None, :] - pk.xz[None, :, :]).transpose(2, 0, 1)) - pk.r[mid][:, None] - pk.r[None, :]
    d = block.xz[:, None, :] - block.xz[None, :, :]
    d -= np.round(d / cell) * cell
    d_cell = np.hypot(d[..., 0], d[..., 1]) - r[:, None] - r[None, :]
    for k in range(len(r)):
        near_cell = np.sort(d_cell[k][d_cell[k] < 2e-3])
        near_tile = np.sort(d_tile[k][d_tile[k] < 2e-3])
        np.testing.assert_allclose(near_tile, near_cell, atol=1e-15)
    with pytest.raises(ValueError, match="nx"):
        tile(block, 0, 1)
    pk.save(str(tmp_path / "ground.csv"))  # the pore-water scenes' packing file
    back = Packing.load(str(tmp_path / "ground.csv"))
    np.testing.assert_allclose(back.xz, pk.xz, rtol=1e-12)
    np.testing.assert_allclose(back.r, pk.r, rtol=1e-12)


def test_study_cost_estimate_follows_steps_and_discs(tmp_path):
    """--estimate: CPU ∝ discs; the compression's steps ∝ strain / rate / Δt; done jobs not counted."""
    import json

    from engines.run import biaxial_study as st

    ref = st.predicted_cpu_s(st.sensitivity(1))
    assert st.predicted_cpu_s(st.sensitivity(1, n_discs=500)) == pytest.approx(ref / 2)
    ms = st.MS_PER_STEP_1000 / 1000
    slow = st.predicted_cpu_s(st.sensitivity(1, strain_rate=25.0))
    dt = TABLE2_DT  # the default step
    assert (slow - ref) / ms == pytest.approx(0.04 / (25 / 6000) / dt - 0.04 / (100 / 6000) / dt)
    fine = st.predicted_cpu_s(st.sensitivity(1, dt=dt / 2, packing_dt=dt))
    pack = st.PACK_STEPS[0] * 5e-5 / dt * ms  # PACK_STEPS are counted at 0.5e-4 s
    assert fine - pack == pytest.approx(2 * (ref - pack))  # all but the packing at half the step
    assert st.predicted_cpu_s(st.main_jobs([1])[0]) > 3 * ref  # four σ3 to 5 % against one to 4 %
    jobs = [st.sensitivity(1), st.sensitivity(2)]
    done = tmp_path / jobs[0].name
    done.mkdir()
    (done / "job.json").write_text(json.dumps({"status": "ok", "command": jobs[0].command(str(done)), "env": {}}))
    assert st.estimate(jobs, str(tmp_path), log=None) == pytest.approx(ref)


def fake_run(runs, name, sigma3, q_f, e50_pa, solid_fraction):
    """A finished biaxial.py job as the sweep runner leaves it: at each σ3 (a number or a list,
    with q_f and e50_pa alike) a linear rise at the slope E50 to q_f, flat to 5 %."""
    import json
    import os

    d = os.path.join(runs, name)
    os.makedirs(d)
    strain = np.linspace(0, 0.05, 251)
    rows = []
    for s3, qf, e in zip(*(np.atleast_1d(np.asarray(v, float)) for v in (sigma3, q_f, e50_pa))):
        q = np.minimum(e * strain, qf)
        rows.append(np.column_stack([np.full_like(strain, s3), strain, q, s3 + q, s3 + q, np.full_like(strain, s3),
                                     strain]))
    np.savetxt(os.path.join(d, "curves.csv"), np.vstack(rows), delimiter=",", header="h", comments="")
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump({"per_sigma3": [{"sigma3_pa": float(s3), "peak_deviator_pa": float(qf)}
                                  for s3, qf in zip(np.atleast_1d(sigma3), np.atleast_1d(q_f))],
                   "packings": [{"solid_fraction": solid_fraction}] * len(np.atleast_1d(sigma3))}, f)
    with open(os.path.join(d, "job.json"), "w") as f:
        json.dump({"status": "ok", "wall_s": 60.0}, f)


def test_hypotheses_table_from_synthetic_runs(tmp_path):
    """Cohesionless synthetic runs with a known φ per variant and packing (q_f = 2 σ3 sin φ /
    (1 − sin φ)): the table gives back φ*, c* = 0, the peak and E50 at 200 Pa, the porosity, the
    size ratio; a variant 4° stronger is a change with its share of the gap to 27.4°, one within
    the scatter is not; missing packings say so."""
    from engines.seeds.biaxial.study import HYPOTHESES, analyse_hypotheses, hypothesis_points, write_hypotheses

    phi = {"reference": 22.0, "rotation_locked": 26.0}
    jitter = {1: -0.5, 2: 0.0, 3: 0.5}
    for name, opts in hypothesis_points([1, 2, 3]):
        variant = next(v for v in HYPOTHESES if name.startswith(f"hyp_{v}_"))
        if variant == "periodic_cell" and opts["seed"] > 1:
            continue  # one packing only: too few for a verdict
        p = math.radians(phi.get(variant, 22.0) + jitter[opts["seed"]] + (0.3 if opts.get("n_discs") else 0.0))
        s3 = opts["sigma3"]
        fake_run(str(tmp_path), name, s3, 2 * s3 * math.sin(p) / (1 - math.sin(p)), 50 * s3, 0.83)
    res = analyse_hypotheses(str(tmp_path), [1, 2, 3])
    rows = {(r["variant"], r["phi_e_deg"]): r for r in res["rows"]}
    ref, locked = rows["reference", 15.0], rows["rotation_locked", 15.0]
    assert ref["phi_star_deg"]["mean"] == pytest.approx(22.0, abs=1e-6) and ref["phi_star_deg"]["n"] == 3
    assert abs(ref["c_star_pa"]["mean"]) < 1e-6
    assert ref["e50_200_pa"]["mean"] == pytest.approx(1e4, rel=1e-3)
    assert ref["porosity"]["mean"] == pytest.approx(0.17) and ref["sigma3_applied_ratio"]["mean"] == pytest.approx(1.0)
    q = lambda deg: 400 * math.sin(math.radians(deg)) / (1 - math.sin(math.radians(deg)))  # noqa: E731
    assert ref["size_ratio"]["mean"] == pytest.approx(np.mean([q(d + 0.3) / q(d) for d in (21.5, 22, 22.5)]))
    assert locked["verdict"].startswith(f"φ* +4.0 ± {1.96 * math.sqrt(2 * 0.25 / 3):.1f}°, "
                                        f"{100 * 4 / (27.4 - 22):.0f} % of the gap")
    assert "unchanged within the scatter" in rows["side_load_diameter", 15.0]["verdict"]
    assert "too few packings" in rows["periodic_cell", 15.0]["verdict"]
    assert rows["periodic_cell", 15.0]["phi_star_deg"]["n"] == 1
    assert res["jobs_total"] == len(hypothesis_points([1, 2, 3])) and res["jobs_failed"] == []
    table = write_hypotheses(res, str(tmp_path / "h.json"), str(tmp_path / "h.md"))
    assert "| rotation_locked | rotation = locked | 15° | 26.0 ± 0.5° (n = 3) |" in table


def test_the_default_reading_packs_with_friction_nearly_off_and_test_means_the_tests_phi():
    """The default reading (docs/BIAXIAL.md): packed at PACKING_PHI_E whatever --phi-e; "test"
    packs at --phi-e (None); the study's jobs name the protocol on their command line."""
    from engines.run import biaxial_study as st
    from engines.run.biaxial import parser
    from engines.seeds.biaxial.periodic import PACKING_PHI_E

    ap = parser()
    assert ap.parse_args(["--phi-e", "5", "--out", "x"]).packing_phi_e == PACKING_PHI_E == 0.5
    assert ap.parse_args(["--phi-e", "5", "--out", "x", "--packing-phi-e", "test"]).packing_phi_e is None
    argv = st.judged_jobs()[0].argv
    assert argv[argv.index("--packing-phi-e") + 1] == "0.5"
    hyp = dict(st.hypothesis_points([1]))["hyp_packing_at_test_phi_phi15_s3100_seed1"]
    assert hyp["packing_phi_e"] == "test"
