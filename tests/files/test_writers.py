"""The project's writers go through engines.files: a full disk while one writes leaves the previous
file whole and raises WriteError naming the path (one writer of each kind: a seed study's JSON, a
packing CSV, a VTK frame)."""
import errno
import os
import re

import numpy as np
import pytest

from engines import files


def calibration_json(path, k):
    from engines.seeds.biaxial.calibration import Calibration
    Calibration(phi_e=[5.0, 15.0], phi_star=[20.0, 27.0 + k], A=[1.0, 2.0], m=[0.5, 0.6], kn=1e6,
                ks_ratio=0.5).save(path)


def packing_csv(path, k):
    from packing.packing import Packing
    Packing(np.array([[0.0, 0.0], [1e-3 * (2 + k), 0.0]]), np.full(2, 0.5e-3), np.zeros(2, int), np.ones(2)).save(path)


def vtk_frame(path, k):
    from postproc.vtk import write_discs
    write_discs(path, np.array([[0.0, 0.0], [1e-3 * (2 + k), 0.0]]), np.full(2, 0.5e-3))


@pytest.mark.parametrize("write, name", [(calibration_json, "fit.json"), (packing_csv, "packing.csv"),
                                         (vtk_frame, "discs_00000.vtp")])
def test_a_full_disk_keeps_the_previous_file_and_names_it(tmp_path, monkeypatch, write, name):
    path = str(tmp_path / name)
    write(path, 0)
    before = open(path, "rb").read()
    write(path, 1)
    assert open(path, "rb").read() != before  # the second content differs: a write that went through would show
    write(path, 0)

    def full(fd):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(files.WriteError, match=rf"^cannot write {re.escape(path)}: no space left on the device$"):
        write(path, 1)
    assert open(path, "rb").read() == before
    assert os.listdir(tmp_path) == [name]
