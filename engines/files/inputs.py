"""The files a user hands us and the names that become paths: one check of each.

``check_input_file(path, what, limit)`` accepts a regular file of at most ``limit`` bytes that is
not empty, and refuses (ValueError, one line naming ``what`` and the path) a missing file, a
directory, a device or pipe ("/dev/zero is not a regular file"), a file above the limit and an
empty one, before a byte of it is read. ``check_name(name, where)`` accepts a name that becomes one
file or folder inside a folder the user named (a sweep job, a scene's name, an ensemble's start)
and refuses one holding a path separator, ``..``, a leading dot or a control character, so that
no write leaves that folder. ``ArgumentParser`` is argparse with the one-line refusal the
command lines give (engines.run.preflight's scripts, postproc's).
"""
import argparse
import os
import stat

MB = 1 << 20


class ArgumentParser(argparse.ArgumentParser):
    """argparse with a one-line error (``prog: error: ...``, no usage block), exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message}\n")


def size_text(n):
    """Bytes as a person reads them: 1.5 MB, 12 kB, 10 GB."""
    for unit, scale in (("GB", 1 << 30), ("MB", MB), ("kB", 1 << 10)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n} bytes"


def check_input_file(path, what, limit):
    """Raise ValueError (one line: ``what``, the path, why) unless ``path`` is a regular file of
    1 to ``limit`` bytes; follows symbolic links (the file they name is checked). Returns its size."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ValueError(f"{what} {path} not found") from None
    except OSError as e:
        raise ValueError(f"{what} {path} cannot be read: {e.strerror}") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"{what} {path} is a directory, not a file")
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"{what} {path} is not a regular file (a device, pipe or socket)")
    if st.st_size == 0:
        raise ValueError(f"{what} {path} is empty")
    if st.st_size > limit:
        raise ValueError(f"{what} {path} is {size_text(st.st_size)}, above the limit of {size_text(limit)} "
                         f"for a {what}")
    if not os.access(path, os.R_OK):
        raise ValueError(f"{what} {path} cannot be read: permission denied")
    return st.st_size


def check_name(name, where):
    """Raise ValueError (one line naming ``where``, e.g. "[scene] name") unless ``name`` is a
    plain name for one file or folder: not empty, no path separator (/ or \\), no leading dot, no
    ``..``, no control characters. Returns ``name``."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"{where}: expected a name, got {name!r}")
    why = ("holds a path separator" if "/" in name or "\\" in name or (os.altsep and os.altsep in name) else
           "starts with a dot" if name.startswith(".") else
           "holds '..'" if ".." in name else
           "holds a control character" if any(ord(c) < 32 or ord(c) == 127 for c in name) else None)
    if why:
        raise ValueError(f"{where} = {name!r} {why}: it becomes a file or folder name, so it must be one plain "
                         f"name (letters, digits, - _ and inner dots)")
    return name
