"""ParaView output: a VTK time series of discs, contact forces and pores in DIR/vtk/.

The series, each a ``.pvd`` collection (``discs.pvd``, ``forces.pvd``, ``pores.pvd``, ``throats.pvd``) of
XML PolyData files (``discs_00000.vtp``, ...) with their times [s]. Coordinates are YADE's: the
discs lie in the x-z plane, y = 0, in metres.

* discs: one point per disc, point arrays ``radius`` [m], ``velocity`` [m/s] (3 components, y = 0),
  ``density_factor`` [-], ``group`` (0 particle, 1 bottom, 2 left, 3 right wall).
* forces: one line per touching pair between the disc centres, cell arrays ``normal_force`` and
  ``shear_force`` [N per m thickness] (each written when given).
* pores: one polygon per pore outline (vertices at the disc centres, and on flat walls the discs'
  feet and the corners), cell arrays ``pore`` (index), ``U`` [N/m], ``W``, ``A`` [m^2 per m] and
  ``rule``: 0 built from the packing, 1-4 inherited at a rebuild by rule (a)-(d) of §3.4(2) (the
  names are kept in the field array ``rule_names``); from snapshots holding the network
  (engines.model.network_view), its ``pore.*`` arrays too, under their names (booleans as 0/1).
* throats (snapshots holding the network): a line per throat between the pores' centroids, cell
  arrays ``throat.conductance`` and ``throat.flux``.

``convert_run(run_dir)`` turns the ``snapshot_*.npz`` files of a run into this series.
Written with VTK's own XML writers (Debian's python3-vtk9).
"""
import errno
import os
import re
from xml.sax.saxutils import quoteattr

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonCore import vtkPoints, vtkStringArray
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkCommonMisc import vtkErrorCode
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

from engines import files
from engines.model.effective_stress import invariants
from postproc.run_files import read_snapshot, run_dir, snapshot_files

RULES = ("build", "a", "b", "c", "d")  # rule codes 0..4 of the pores' 'rule' array
SERIES = ("discs", "forces", "pores")
THROATS = "throats"  # the series of the network's throats (runs whose snapshots hold the network)
# the arrays' names in the files, each with its unit (forces per metre of thickness, areas per metre too)
ARRAYS = {"radius": "radius [m]", "velocity": "velocity [m/s]", "normal_force": "normal_force [N/m]",
          "shear_force": "shear_force [N/m]", "U": "U [N/m]", "W": "W [m^2]", "A": "A [m^2]"}


STRESS_ARRAYS = ("stress_xx [Pa]", "stress_zz [Pa]", "stress_xz [Pa]", "p' [Pa]", "q [Pa]")  # a disc's effective stress


def _points(xz):
    """(N, 2) x-z positions -> vtkPoints at (x, 0, z)."""
    xz = np.asarray(xz, float)
    p3 = np.column_stack([xz[:, 0], np.zeros(len(xz)), xz[:, 1]])
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(p3, deep=True))
    return pts


def _cells(offsets, connectivity):
    cells = vtkCellArray()
    cells.SetData(numpy_to_vtkIdTypeArray(np.asarray(offsets, np.int64), deep=True),
                  numpy_to_vtkIdTypeArray(np.asarray(connectivity, np.int64), deep=True))
    return cells


def _add(data, name, values):
    """Attach ``values`` (n,) or (n, k) as a named array to point or cell data ``data``."""
    values = np.asarray(values)
    arr = numpy_to_vtk(np.ascontiguousarray(values), deep=True)
    arr.SetName(name)
    data.AddArray(arr)


def _in_plane(v):
    """(N, 2) x-z vectors -> (N, 3) with y = 0."""
    v = np.asarray(v, float)
    return np.column_stack([v[:, 0], np.zeros(len(v)), v[:, 1]])


def _write(poly, path):
    """``poly`` as an XML PolyData file at ``path``, whole or not at all (engines.files)."""
    w = vtkXMLPolyDataWriter()
    w.SetInputData(poly)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOff()  # raw binary: exact float64, small files
    with files.saved(path) as tmp:
        w.SetFileName(tmp)
        if not w.Write() or w.GetErrorCode():
            code = w.GetErrorCode()
            if code == vtkErrorCode.OutOfDiskSpaceError:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            raise OSError(f"VTK's writer failed ({vtkErrorCode.GetStringFromErrorCode(code)})")


def write_discs(path, xz, r, vel=None, density_factor=None, group=None, stress=None):
    """Discs as points with radius [m], velocity [m/s], density factor and group arrays and, given
    ``stress`` (N, 3): xx, zz, xz [Pa] (engines.model.effective_stress.disc_stress), each disc's
    effective stress, its p' and q [Pa] (STRESS_ARRAYS)."""
    n = len(xz)
    poly = vtkPolyData()
    poly.SetPoints(_points(xz))
    poly.SetVerts(_cells(np.arange(n + 1), np.arange(n)))
    pd = poly.GetPointData()
    _add(pd, ARRAYS["radius"], np.asarray(r, float))
    if vel is not None:
        _add(pd, ARRAYS["velocity"], _in_plane(vel))
    if density_factor is not None:
        _add(pd, "density_factor", np.asarray(density_factor, float))
    if group is not None:
        _add(pd, "group", np.asarray(group, np.int32))
    if stress is not None:
        stress = np.asarray(stress, float)
        _, _, p, q = invariants(stress)
        for name, values in zip(STRESS_ARRAYS, (stress[:, 0], stress[:, 1], stress[:, 2], p, q)):
            _add(pd, name, values)
    _write(poly, path)


def write_forces(path, xz, pairs, f_n, f_s=None):
    """The contact-force network: a line per pair (i, j) with normal (and shear) force [N/m: N per
    metre of thickness]."""
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    poly = vtkPolyData()
    poly.SetPoints(_points(xz))
    poly.SetLines(_cells(2 * np.arange(len(pairs) + 1), pairs.ravel()))
    cd = poly.GetCellData()
    _add(cd, ARRAYS["normal_force"], np.asarray(f_n, float))
    if f_s is not None:
        _add(cd, ARRAYS["shear_force"], np.asarray(f_s, float))
    _write(poly, path)


def rule_codes(rule):
    """Rules as codes 0..4 (see RULES); accepts the codes or the names."""
    rule = np.asarray(rule)
    if rule.dtype.kind in "iu":
        return rule.astype(np.int32)
    return np.array([RULES.index(str(x) or "build") for x in rule], np.int32)


def write_pores(path, xz, polygons, pore=None, U=None, W=None, A=None, rule=None, network=None):
    """Pore outlines: ``polygons`` a list of disc-index sequences; per polygon the pore index and
    its U [N/m], W, A [m^2] and rule (names or codes, see RULES); ``network``: more cell arrays
    {name: (n polygons,) values} (the network's pore.* arrays; booleans as 0/1)."""
    poly = vtkPolyData()
    poly.SetPoints(_points(xz))
    sizes = np.array([len(p) for p in polygons], np.int64)
    conn = np.concatenate([np.asarray(p, np.int64) for p in polygons]) if len(polygons) else np.zeros(0, np.int64)
    poly.SetPolys(_cells(np.concatenate([[0], np.cumsum(sizes)]), conn))
    cd = poly.GetCellData()
    for name, values in (("pore", pore), ("U", U), ("W", W), ("A", A)):
        if values is not None:
            _add(cd, ARRAYS.get(name, name), np.asarray(values, np.int32 if name == "pore" else float))
    for name, values in (network or {}).items():
        values = np.asarray(values)
        _add(cd, name, values.astype(np.int8) if values.dtype == bool else values)
    if rule is not None:
        _add(cd, "rule", rule_codes(rule))
        names = vtkStringArray()
        names.SetName("rule_names")
        for name in RULES:
            names.InsertNextValue(name)
        poly.GetFieldData().AddArray(names)
    _write(poly, path)


def write_throats(path, xz, conns, conductance=None, flux=None):
    """The throats of the pore network: a line per pore pair ``conns`` (Nt, 2) between the pores'
    centroids ``xz`` (Np, 2) [m], cell arrays throat.conductance [m^3/(N s)] and throat.flux [m^2/s]."""
    conns = np.asarray(conns, np.int64).reshape(-1, 2)
    poly = vtkPolyData()
    poly.SetPoints(_points(xz))
    poly.SetLines(_cells(2 * np.arange(len(conns) + 1), conns.ravel()))
    cd = poly.GetCellData()
    for name, values in (("throat.conductance", conductance), ("throat.flux", flux)):
        if values is not None:
            _add(cd, name, np.asarray(values, float))
    _write(poly, path)


def write_collection(path, entries):
    """A ParaView .pvd collection: entries [(time [s], file relative to the .pvd)]."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">', "  <Collection>"]
    lines += [f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(f)}/>' for t, f in entries]
    lines += ["  </Collection>", "</VTKFile>", ""]
    files.write_text(path, "\n".join(lines))


class VtkSeries:
    """Frames of a run written to ``out_dir``/vtk; the .pvd files are rewritten after every
    frame, so an interrupted run leaves a readable series."""

    CHECKPOINT_FIELDS = ("entries",)  # what a checkpoint stores (engines.model.state)
    CHECKPOINT_DERIVED = {"dir": "the folder resumed in (Recorder.reopen)"}

    def __init__(self, out_dir):
        self.dir = os.path.join(out_dir, "vtk")  # made at the first frame
        self.entries = {s: [] for s in SERIES + (THROATS,)}

    def checkpoint_restored(self):
        """Refuse stored entries other than (t, "<series>_<frame>.vtp") of SERIES (and THROATS: a
        run of a checkpoint without them starts their series at its next frame), frames increasing;
        make them tuples again."""
        self.entries.setdefault(THROATS, [])
        if sorted(self.entries) != sorted(SERIES + (THROATS,)):
            raise ValueError(f"vtk entries: expected the series {list(SERIES + (THROATS,))}")
        for series, entries in self.entries.items():
            last = -1
            for k, e in enumerate(entries):
                m = re.fullmatch(rf"{series}_(\d{{5}})\.vtp", e[1]) if isinstance(e, list) and len(e) == 2 \
                    and isinstance(e[1], str) else None
                if not (m and type(e[0]) in (int, float) and int(m.group(1)) > last):
                    raise ValueError(f"vtk entry {series}[{k}]: expected [t, {series}_<frame>.vtp] of increasing "
                                     f"frames, got {e!r}")
                last = int(m.group(1))
            self.entries[series] = [(float(t), name) for t, name in entries]

    def add(self, t, discs, forces=None, pores=None, throats=None):
        """One frame at time t [s]: keyword dicts for write_discs, write_forces, write_pores and
        write_throats (without path; positions are taken from ``discs['xz']`` unless given)."""
        k = len(self.entries["discs"])
        xz = discs["xz"]
        os.makedirs(self.dir, exist_ok=True)
        for series, kwargs, write in (("discs", discs, write_discs), ("forces", forces, write_forces),
                                      ("pores", pores, write_pores), (THROATS, throats, write_throats)):
            if kwargs is None:
                continue
            name = f"{series}_{k:05d}.vtp"
            write(os.path.join(self.dir, name), **({"xz": xz} | kwargs))
            self.entries[series].append((float(t), name))
            write_collection(os.path.join(self.dir, f"{series}.pvd"), self.entries[series])


# -- pores from the triangles of a snapshot -----------------------------------------------------
def outlines_from_triangles(tri, tri_pore):
    """Outline polygons of pores stored as triangles (PoreNetwork.tri, tri_pore).

    A pore's boundary is the set of its triangle edges whose reverse is not in the pore; walked
    into cycles: the outline and, around an island of linked discs inside the pore, a cycle
    turning the other way (``snapshot_frame`` leaves those out). Returns (polygons, pore of each)."""
    tri, tri_pore = np.asarray(tri, np.int64), np.asarray(tri_pore, np.int64)
    polygons, owner = [], []
    for p in np.unique(tri_pore):
        t = tri[tri_pore == p]
        edges = {(int(a), int(b)) for a, b in np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])}
        nxt = {}
        for a, b in edges:
            if (b, a) not in edges:
                nxt.setdefault(a, []).append(b)
        while nxt:
            start = min(nxt)
            cycle, v = [start], _pop(nxt, start)
            while v != start:
                cycle.append(v)
                v = _pop(nxt, v)
            polygons.append(cycle)
            owner.append(int(p))
    return polygons, np.array(owner, np.int64)


def _pop(nxt, a):
    """Follow (and remove) one boundary edge out of vertex a."""
    b = nxt[a].pop()
    if not nxt[a]:
        del nxt[a]
    return b


def signed_area(xz, polygon):
    """Shoelace area of a polygon of disc centres [m^2] (positive counter-clockwise in x-z)."""
    x, z = np.asarray(xz)[polygon].T
    return 0.5 * float(np.sum(x * np.roll(z, -1) - np.roll(x, -1) * z))


def snapshot_frame(snap):
    """write keyword dicts (discs, forces, pores) of one snapshot .npz (engines.run.runner.Recorder)."""
    xz = snap["xz"]
    discs = dict(xz=xz, r=snap["r"], vel=snap["vel"], density_factor=snap["density_factor"], group=snap["group"],
                 stress=snap.get("stress"))
    forces = dict(pairs=snap["pairs"], f_n=snap["f_n"], f_s=snap["f_s"] if "f_s" in snap else None)
    pores = None
    if "polygon.ptr" in snap:  # the network's outlines (engines.model.network_view) and its pore.* arrays
        ptr = snap["polygon.ptr"]
        n = len(ptr) - 1
        vertices, ids = snap["vertices"] if "vertices" in snap else xz, snap["polygon.vertex"]
        pores = dict(xz=vertices, polygons=[ids[ptr[p]:ptr[p + 1]] for p in range(n)],
                     pore=np.arange(n), network={k: snap[k] for k in snap if k.startswith("pore.") and k != "pore.coords"})
        for name in ("U", "W", "A", "rule"):
            if name in snap:
                pores[name] = np.asarray(snap[name])
    elif "tri" in snap and len(snap["tri"]):
        polygons, owner = outlines_from_triangles(snap["tri"], snap["tri_pore"])
        vertices = snap["vertices"] if "vertices" in snap else xz  # with flat walls: discs, then wall vertices
        area = np.array([signed_area(vertices, poly) for poly in polygons])
        outer = {}  # per pore, the orientation of its largest cycle; cycles turning the other way are islands
        for k in np.argsort(-np.abs(area)):
            outer.setdefault(owner[k], np.sign(area[k]))
        keep = [k for k in range(len(polygons)) if np.sign(area[k]) == outer[owner[k]]]
        owner = owner[keep]
        pores = dict(xz=vertices, polygons=[polygons[k] for k in keep], pore=owner)
        for name in ("U", "W", "A", "rule"):
            if name in snap:
                pores[name] = np.asarray(snap[name])[owner]
    return discs, forces, pores


def snapshot_throats(snap):
    """write_throats' keyword dict of one snapshot .npz holding the network (None without)."""
    if "throat.conns" not in snap:
        return None
    return dict(xz=np.asarray(snap["pore.coords"])[:, [0, 2]], conns=snap["throat.conns"],
                conductance=snap["throat.conductance"], flux=snap["throat.flux"])


def convert_run(run_dir, out_dir=None):
    """Write the VTK series of a run's snapshots into (out_dir or run_dir)/vtk; returns the
    VtkSeries. Raises FileNotFoundError when the run has no snapshot."""
    files = snapshot_files(run_dir)
    if not files:
        raise FileNotFoundError(f"no snapshot_*.npz in {run_dir}")
    series = VtkSeries(out_dir or run_dir)
    for f in files:
        snap = read_snapshot(f)
        series.add(float(snap["t"]), *snapshot_frame(snap), throats=snapshot_throats(snap))
    return series


if __name__ == "__main__":
    from engines.files.inputs import ArgumentParser
    ap = ArgumentParser(prog="python3 -m postproc.vtk",
                                 description="Write a ParaView series of runs' snapshots into RUN_DIR/vtk/*.pvd.")
    ap.add_argument("runs", nargs="+", type=run_dir, metavar="RUN_DIR", help="a run's --out folder")
    for run in ap.parse_args().runs:
        if not snapshot_files(run):
            ap.error(f"{run}: the run wrote no snapshot_*.npz (give [output] snapshot_times, or run with --vtk)")
        print(f"{run}: {len(convert_run(run).entries['discs'])} frames -> {os.path.join(run, 'vtk')}")
