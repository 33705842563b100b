"""Writing a file so that it is either whole or absent: every write of the project goes through here.

``write_bytes``, ``write_text``, ``write_json``, ``savez``, ``save_figure`` and ``saved`` (a context for writers that
want a path, e.g. matplotlib's savefig) write to a temporary file in the target's folder (named
``.NAME.tmp-*`` and ending in NAME's extension, so that a writer going by the name it is given, as
numpy.save and VTK's XML writers do, writes there what it would write to NAME), flush and fsync it,
then rename it over the target, so a reader never sees a half file and a kill at any moment leaves
the old file or the new one. A failed write (a full disk, a missing folder, no permission) removes
the temporary file and raises ``WriteError``, one line naming the path and the cause.
``remove_stale_temporaries(folder)`` removes what a killed process left (the next start of a run
calls it).
"""
import contextlib
import errno
import glob
import io
import json
import os
import tempfile

TEMP_PREFIX = "."
TEMP_MARK = ".tmp-"


class WriteError(OSError):
    """A file that could not be written; the message names the path and the cause, in one line."""


def reason(e):
    """The cause of an OSError in words ("no space left on the device"), for a one-line message."""
    if getattr(e, "errno", None) == errno.ENOSPC:
        return "no space left on the device"
    if getattr(e, "errno", None) == errno.EDQUOT:
        return "disk quota exceeded"
    return e.strerror or str(e)


@contextlib.contextmanager
def saved(path, mode=0o666):
    """``with saved(path) as tmp: write(tmp)``: the file written to ``tmp`` replaces ``path`` when
    the block ends without an error (fsync'd first), and is removed otherwise. ``mode``: the new
    file's permissions before the umask (an ordinary file's by default, not mkstemp's 0600)."""
    folder = os.path.dirname(os.path.abspath(path))
    base = os.path.basename(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{base}{TEMP_MARK}", suffix=os.path.splitext(base)[1], dir=folder)
    except OSError as e:
        raise WriteError(f"cannot write {path}: {reason(e)}") from None
    os.close(fd)
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, mode & ~umask)
        os.replace(tmp, path)
    except OSError as e:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        if isinstance(e, WriteError):
            raise
        raise WriteError(f"cannot write {path}: {reason(e)}") from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        raise


def write_bytes(path, data):
    """Write ``data`` (bytes) to ``path`` atomically."""
    with saved(path) as tmp, open(tmp, "wb") as f:
        f.write(data)


def write_text(path, text):
    """Write ``text`` (str, UTF-8) to ``path`` atomically."""
    write_bytes(path, text.encode("utf-8"))


def write_json(path, data, **kw):
    """Write ``data`` as JSON (indent 1 unless given) to ``path`` atomically; non-finite floats are
    written as JSON's NaN/Infinity, as json.dump does."""
    kw.setdefault("indent", 1)
    write_text(path, json.dumps(data, **kw) + "\n")


def savez(path, compressed=True, **arrays):
    """``numpy.savez[_compressed]`` to ``path`` atomically (no pickled objects: object arrays are refused)."""
    import numpy as np
    for name, a in arrays.items():
        if np.asarray(a).dtype == object:
            raise TypeError(f"{path}: array {name!r} holds Python objects; only numbers and strings are written")
    buf = io.BytesIO()  # built in memory: a write that fails then leaves no half-written zip object behind
    (np.savez_compressed if compressed else np.savez)(buf, **arrays)
    write_bytes(path, buf.getvalue())


def save_figure(fig, path, **kw):
    """``fig.savefig`` (matplotlib) to ``path`` atomically, in the format of its extension."""
    fmt = os.path.splitext(path)[1][1:] or "png"
    with saved(path) as tmp:
        fig.savefig(tmp, format=fmt, **kw)


def remove_stale_temporaries(folder):
    """Remove the temporary files a killed writer left in ``folder`` (``.NAME.tmp-*``). Returns their paths."""
    gone = []
    for path in glob.glob(os.path.join(glob.escape(folder), f"{TEMP_PREFIX}*{TEMP_MARK}*")):
        with contextlib.suppress(OSError):
            os.remove(path)
            gone.append(path)
    return gone
