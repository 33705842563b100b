"""engines.files: a write leaves the old file or the new one, never a part, and says why it failed."""
import errno
import json
import os

import numpy as np
import pytest

from engines import files


def test_write_json_replaces_whole_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "a.json"
    files.write_json(path, {"x": 1})
    files.write_json(path, {"x": 2})
    assert json.loads(path.read_text()) == {"x": 2}
    assert sorted(os.listdir(tmp_path)) == ["a.json"]


def test_a_failed_write_keeps_the_old_file_and_names_the_path(tmp_path, monkeypatch):
    path = tmp_path / "a.json"
    files.write_json(path, {"x": 1})

    def full(fd):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(files.WriteError, match=r"cannot write .*a\.json: no space left on the device"):
        files.write_json(path, {"x": 2})
    assert json.loads(path.read_text()) == {"x": 1}
    assert sorted(os.listdir(tmp_path)) == ["a.json"]


def test_an_exception_inside_the_block_removes_the_temporary(tmp_path):
    with pytest.raises(KeyError):
        with files.saved(tmp_path / "b.bin") as tmp:
            open(tmp, "wb").write(b"half")
            raise KeyError("stop")
    assert os.listdir(tmp_path) == []


def test_savez_refuses_objects_and_round_trips_numbers(tmp_path):
    files.savez(tmp_path / "s.npz", a=np.arange(3.0))
    with np.load(tmp_path / "s.npz", allow_pickle=False) as z:
        assert z["a"].tolist() == [0.0, 1.0, 2.0]
    with pytest.raises(TypeError, match="Python objects"):
        files.savez(tmp_path / "o.npz", a=np.array([{}], dtype=object))


def test_stale_temporaries_are_removed(tmp_path):
    (tmp_path / ".summary.json.tmp-abc").write_text("x")
    (tmp_path / "keep.txt").write_text("x")
    assert [os.path.basename(p) for p in files.remove_stale_temporaries(str(tmp_path))] == [".summary.json.tmp-abc"]
    assert os.listdir(tmp_path) == ["keep.txt"]


def test_new_files_have_ordinary_permissions(tmp_path):
    umask = os.umask(0o022)
    try:
        files.write_text(tmp_path / "t.txt", "x")
    finally:
        os.umask(umask)
    assert (os.stat(tmp_path / "t.txt").st_mode & 0o777) == 0o644


def test_save_figure_writes_the_format_of_the_extension(tmp_path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    files.save_figure(fig, str(tmp_path / "f.png"), dpi=50)
    files.save_figure(fig, str(tmp_path / "f.svg"))
    plt.close(fig)
    assert (tmp_path / "f.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert b"<svg" in (tmp_path / "f.svg").read_bytes()[:500]
    assert sorted(os.listdir(tmp_path)) == ["f.png", "f.svg"]


def test_the_temporary_keeps_the_extension_for_writers_that_go_by_it(tmp_path):
    """numpy.save appends .npy to a name without it (VTK's writers drop a trailing '_'): given the
    temporary, such a writer must write the temporary itself."""
    with files.saved(str(tmp_path / "a.npy")) as tmp:
        np.save(tmp, np.arange(3.0))
    assert np.load(tmp_path / "a.npy").tolist() == [0.0, 1.0, 2.0]
    assert os.listdir(tmp_path) == ["a.npy"]
