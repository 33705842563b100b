"""ParaView output: the files load with VTK's readers and hold the numbers given; the .pvd lists
every file with its time; pore outlines from triangles are the pores' polygons."""
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

from engines.model import pores as pg
from engines.run import scene as scenes
from engines.yade.deposition import scene_packing
from postproc import vtk as pv
from postproc.run_files import read_network, snapshot_files


def read(path):
    r = vtkXMLPolyDataReader()
    r.SetFileName(str(path))
    r.Update()
    out = r.GetOutput()
    assert out.GetNumberOfPoints() > 0, f"{path} did not load"
    return out


def points_xz(poly):
    p = vtk_to_numpy(poly.GetPoints().GetData())
    assert np.all(p[:, 1] == 0.0)
    return p[:, [0, 2]]


def cells(cell_array):
    off, con = vtk_to_numpy(cell_array.GetOffsetsArray()), vtk_to_numpy(cell_array.GetConnectivityArray())
    return [con[off[k]:off[k + 1]].tolist() for k in range(len(off) - 1)]


def array(data, name):
    a = data.GetArray(name)
    assert a is not None, f"no array {name}"
    return vtk_to_numpy(a)


def collection(path):
    """[(time, file)] of a .pvd."""
    return [(float(d.get("timestep")), d.get("file")) for d in ET.parse(path).getroot().iter("DataSet")]


def test_written_files_hold_the_numbers_given(tmp_path):
    rng = np.random.default_rng(4)
    n = 7
    xz, r, vel = rng.random((n, 2)), 0.1 + rng.random(n), rng.normal(size=(n, 2))
    dens, group = rng.choice([1.0, 5.0], n), np.array([0, 0, 0, 1, 1, 2, 3])
    pairs, f_n, f_s = np.array([[0, 1], [1, 2], [2, 5]]), rng.random(3), rng.normal(size=3)
    polygons = [[0, 1, 2], [2, 3, 4, 5]]
    U, W, A = np.array([12.5, -3.25]), np.array([1e-7, 2e-7]), np.array([0.9e-7, 2.1e-7])
    series = pv.VtkSeries(str(tmp_path))
    for t in (0.0, 0.015, 0.03):
        series.add(t, dict(xz=xz + t, r=r, vel=vel, density_factor=dens, group=group),
                   dict(pairs=pairs, f_n=f_n + t, f_s=f_s),
                   dict(polygons=polygons, pore=[4, 9], U=U + t, W=W, A=A, rule=["", "c"]))
    vdir = tmp_path / "vtk"
    for name in pv.SERIES:
        entries = collection(vdir / f"{name}.pvd")
        assert [t for t, _ in entries] == [0.0, 0.015, 0.03]
        assert all((vdir / f).exists() for _, f in entries)
    t, f = collection(vdir / "discs.pvd")[1]
    d = read(vdir / f)
    assert np.array_equal(points_xz(d), xz + t) and cells(d.GetVerts()) == [[k] for k in range(n)]
    pd = d.GetPointData()
    assert np.array_equal(array(pd, "radius [m]"), r) and np.array_equal(array(pd, "density_factor"), dens)
    assert np.array_equal(array(pd, "velocity [m/s]"), np.column_stack([vel[:, 0], np.zeros(n), vel[:, 1]]))
    assert np.array_equal(array(pd, "group"), group)
    fo = read(vdir / collection(vdir / "forces.pvd")[1][1])
    assert cells(fo.GetLines()) == pairs.tolist()
    assert np.array_equal(array(fo.GetCellData(), "normal_force [N/m]"), f_n + t)
    assert np.array_equal(array(fo.GetCellData(), "shear_force [N/m]"), f_s)
    po = read(vdir / collection(vdir / "pores.pvd")[1][1])
    assert cells(po.GetPolys()) == polygons and np.array_equal(points_xz(po), xz + t)
    cd = po.GetCellData()
    assert np.array_equal(array(cd, "U [N/m]"), U + t) and np.array_equal(array(cd, "W [m^2]"), W)
    assert np.array_equal(array(cd, "A [m^2]"), A) and array(cd, "pore").tolist() == [4, 9]
    assert array(cd, "rule").tolist() == [0, 3]  # build, rule (c)
    names = po.GetFieldData().GetAbstractArray("rule_names")
    assert [names.GetValue(k) for k in range(names.GetNumberOfValues())] == list(pv.RULES)


def test_outlines_of_a_square_and_a_ring():
    """Two triangles make a square; a ring of eight around a hole has an outer outline (kept) and
    a hole (negative area, left out by the converter)."""
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    polys, owner = pv.outlines_from_triangles([[0, 1, 2], [0, 2, 3]], [5, 5])
    assert owner.tolist() == [5] and sorted(polys[0]) == [0, 1, 2, 3]
    assert pv.signed_area(sq, polys[0]) == pytest.approx(1.0)
    outer = [[0, 0], [3, 0], [3, 3], [0, 3]]
    inner = [[1, 1], [2, 1], [2, 2], [1, 2]]
    xz = np.array(outer + inner, float)
    ring = [[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]]
    polys, owner = pv.outlines_from_triangles(ring, [0] * 8)
    areas = sorted(pv.signed_area(xz, p) for p in polys)
    assert areas == pytest.approx([-1.0, 9.0]) and owner.tolist() == [0, 0]


def test_outlines_are_the_pore_polygons_of_the_preset():
    """Outline areas equal the pores' polygon areas of engines.model.pores.measure."""
    pk = scene_packing(scenes.preset("quicksand_case1"))
    net = pg.build_pores(pk.xz, pk.r, eps_m=0.0, l_m=1.3e-4, walls=pk.group)
    m = pg.measure(net, pk.xz, pk.r)
    polys, owner = pv.outlines_from_triangles(net.tri, net.tri_pore)
    area = np.zeros(net.n_pores)
    np.add.at(area, owner, [pv.signed_area(pk.xz, p) for p in polys])
    assert net.n_pores > 40 and sorted(set(owner.tolist())) == list(range(net.n_pores))
    assert np.allclose(area, m.polygon_area, rtol=1e-12, atol=0)


def test_a_runs_snapshots_convert(tmp_path):
    """A short YADE run's snapshot_*.npz files become a series holding the same numbers."""
    from engines.run.runner import run_scene
    sc = scenes.preset("quicksand_case1", {"output": {"snapshot_times": [0.0, 1e-4, 2e-4], "history_interval": 50}})
    pk = scene_packing(sc)
    run = tmp_path / "run"
    run_scene(sc, pk, str(run), duration=2e-4)
    series = pv.convert_run(str(run))
    snaps = [dict(np.load(f)) for f in snapshot_files(str(run))]
    assert len(snaps) == 3 and series.dir == str(run / "vtk")
    for name in pv.SERIES:
        assert [t for t, _ in collection(run / "vtk" / f"{name}.pvd")] == [float(s["t"]) for s in snaps]
    for s, (_, f) in zip(snaps, collection(run / "vtk" / "discs.pvd")):
        d = read(run / "vtk" / f)
        assert np.array_equal(points_xz(d), s["xz"]) and np.array_equal(array(d.GetPointData(), "radius [m]"), s["r"])
        assert np.array_equal(array(d.GetPointData(), "velocity [m/s]")[:, [0, 2]], s["vel"])
    last, (_, f) = snaps[-1], collection(run / "vtk" / "pores.pvd")[-1]
    po = read(run / "vtk" / f)
    pore = array(po.GetCellData(), "pore")
    assert sorted(set(pore.tolist())) == sorted(set(last["tri_pore"].tolist()))
    assert np.array_equal(array(po.GetCellData(), "U [N/m]"), last["U"][pore])
    net = read_network(snapshot_files(str(run))[-1])  # the network under OpenPNM's names, beside the old keys
    assert net["pore.coords"].shape == (len(net["polygon.ptr"]) - 1, 3) == (len(last["W"]), 3)
    np.testing.assert_array_equal(net["pore.pressure"], last["U"])
    assert np.array_equal(array(po.GetCellData(), "pore.inflow"), net["pore.inflow"].astype(np.int8))
    th = read(run / "vtk" / collection(run / "vtk" / "throats.pvd")[-1][1])
    assert cells(th.GetLines()) == net["throat.conns"].tolist()
    assert np.array_equal(points_xz(th), net["pore.coords"][:, [0, 2]])
    assert np.array_equal(array(th.GetCellData(), "throat.flux"), net["throat.flux"])
    fo = read(run / "vtk" / collection(run / "vtk" / "forces.pvd")[-1][1])
    assert cells(fo.GetLines()) == last["pairs"].tolist()
    assert np.array_equal(array(fo.GetCellData(), "normal_force [N/m]"), last["f_n"])


def test_a_run_without_snapshots_is_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="no snapshot"):
        pv.convert_run(str(tmp_path))


def test_snapshot_pores_leave_islands_out_whatever_the_orientation():
    """The ring pore of test_outlines_...: the outline is kept and the hole left out, also when
    the whole picture is mirrored (all cycles turn the other way)."""
    xz = np.array([[0, 0], [3, 0], [3, 3], [0, 3], [1, 1], [2, 1], [2, 2], [1, 2]], float)
    ring = np.array([[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
    for pts in (xz, xz * [-1, 1]):
        snap = dict(xz=pts, r=np.full(8, 0.1), vel=np.zeros((8, 2)), density_factor=np.ones(8),
                    group=np.zeros(8, int), pairs=np.zeros((0, 2), int), f_n=np.zeros(0), tri=ring,
                    tri_pore=np.zeros(8, int), U=np.array([7.0]))
        _, _, pores = pv.snapshot_frame(snap)
        assert len(pores["polygons"]) == 1 and sorted(pores["polygons"][0]) == [0, 1, 2, 3]
        assert pores["U"].tolist() == [7.0] and pores["pore"].tolist() == [0]


def test_stored_entries_of_a_series_without_throats_are_taken_and_others_refused(tmp_path):
    """A checkpoint's entries written before the throats series: its throats start at the next
    frame; a name out of order is refused."""
    series = pv.VtkSeries(str(tmp_path))
    series.entries = {s: [[0.0, f"{s}_00000.vtp"], [0.5, f"{s}_00001.vtp"]] for s in pv.SERIES}
    series.checkpoint_restored()
    assert series.entries[pv.THROATS] == [] and series.entries["pores"][1] == (0.5, "pores_00001.vtp")
    series.entries = {s: [[0.0, f"{s}_00001.vtp"], [0.5, f"{s}_00001.vtp"]] for s in pv.SERIES}
    with pytest.raises(ValueError, match="increasing"):
        series.checkpoint_restored()


def test_every_float_array_is_named_with_its_unit(tmp_path):
    """The arrays ParaView lists carry their units (forces per metre of thickness)."""
    xz = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    pv.write_discs(str(tmp_path / "d.vtp"), xz, np.ones(3), vel=np.zeros((3, 2)))
    pv.write_forces(str(tmp_path / "f.vtp"), xz, [[0, 1]], [2.0], [1.0])
    pv.write_pores(str(tmp_path / "p.vtp"), xz, [[0, 1, 2]], pore=[0], U=[1.0], W=[0.5], A=[0.4])
    names = set()
    for name, kind in (("d.vtp", "GetPointData"), ("f.vtp", "GetCellData"), ("p.vtp", "GetCellData")):
        data = getattr(read(str(tmp_path / name)), kind)()
        names |= {data.GetArrayName(i) for i in range(data.GetNumberOfArrays())}
    assert names == {"radius [m]", "velocity [m/s]", "normal_force [N/m]", "shear_force [N/m]", "U [N/m]",
                     "W [m^2]", "A [m^2]", "pore"}


def test_each_discs_effective_stress_is_written_with_its_invariants(tmp_path):
    """A disc's stress (xx, zz, xz [Pa]) and its p' and q, each named with its unit."""
    xz = np.array([[0.0, 0.0], [1.0, 0.0]])
    stress = np.array([[30.0, 10.0, 0.0], [20.0, 20.0, 5.0]])
    pv.write_discs(str(tmp_path / "d.vtp"), xz, np.ones(2), stress=stress)
    pd = read(str(tmp_path / "d.vtp")).GetPointData()
    assert np.array_equal(array(pd, "stress_xx [Pa]"), stress[:, 0]) and np.array_equal(array(pd, "stress_xz [Pa]"),
                                                                                         stress[:, 2])
    assert array(pd, "p' [Pa]").tolist() == [20.0, 20.0] and array(pd, "q [Pa]").tolist() == [10.0, 5.0]
