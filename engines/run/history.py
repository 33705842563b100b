"""A run's history.csv as its checkpoint knows it (no YADE: ``--resume`` checks it before YADE starts).

The recorder appends rows and keeps a SHA-256 of the file's bytes so far (header and rows); each
checkpoint records the number of rows, the last row's t and that checksum (``info``). On resume,
``kept(run_dir, info)`` says how much of the file is the header and the rows the checkpoint
recorded, after checking that the file holds them: missing, short, another run's or edited rows are refused in one line
naming the file and what differs. Rows after the checkpoint (written before a stop or crash) are
dropped by the resume, which computes them again.
"""
import csv
import hashlib
import os

NAME = "history.csv"
CHUNK = 1 << 20  # bytes read at a time
LAST_LINE = 1 << 16  # bytes kept of the end of what was read (the last row: well under)


# the unit of each column [per metre of thickness for forces, energies and areas]; a column whose
# name starts with a key ending in "*" takes its unit (U_block1, wall_bottom_contact, ...)
UNITS = {"t": "s", "U_block*": "N/m", "porosity": "1", "kinetic_energy": "J/m", "water_balance_error": "1",
         "total_water": "m^2", "n_pores": "1", "fn_bottom_mean": "N/m", "bed_top": "m", "base_acc": "m/s^2",
         "base_vel": "m/s", "base_disp": "m", "side_left_dx": "m", "side_right_dx": "m", "remesh_change": "m^2",
         "wall_*": "N/m", "sv_band*": "Pa", "p_band*": "Pa", "q_band*": "Pa", "sxz_band*": "Pa", "ru_band*": "1"}


def units(columns):
    """{column: unit} of history.csv's ``columns`` (UNITS; KeyError names a column without one)."""
    def unit(name):
        for key, u in UNITS.items():
            if name == key or key.endswith("*") and name.startswith(key[:-1]):
                return u
        raise KeyError(f"history column {name!r} has no unit in engines.run.history.UNITS")
    return {c: unit(c) for c in columns}


class HistoryMismatch(ValueError):
    """history.csv does not hold the rows the checkpoint recorded; the message says what differs."""


def info(rows, last_t, digest):
    """The checkpoint's record of the history: ``rows`` written, the last one's t [s] (as written),
    the SHA-256 (hex) of the file's bytes."""
    return {"history_rows": int(rows), "history_last_t": last_t, "history_sha256": digest}


def kept(run_dir, info, rows=None):
    """(how many bytes of history.csv to keep: its header and the checkpoint's rows, whether that
    is the whole file, the SHA-256 object of those bytes), read in chunks (a long history is not
    held in memory). ``info``: the checkpoint's (``info`` above, and its "step"); a checkpoint
    without that record: only the count ``rows`` is checked (none if None)."""
    path = os.path.join(run_dir, NAME)
    n = info.get("history_rows", rows)
    step = f"the checkpoint at step {info['step']}" if "step" in info else "the checkpoint"
    sha, size, lines, tail, beyond = hashlib.sha256(), 0, 0, b"", False
    try:
        with open(path, "rb") as f:
            while n is None or lines < 1 + n:
                chunk = f.read(CHUNK)
                if not chunk:
                    break
                if n is not None and lines + chunk.count(b"\n") >= 1 + n:  # the kept part ends in this chunk
                    end = -1
                    for _ in range(1 + n - lines):
                        end = chunk.index(b"\n", end + 1)
                    beyond, chunk = end + 1 < len(chunk), chunk[:end + 1]
                lines += chunk.count(b"\n")
                tail = (tail + chunk)[-LAST_LINE:]
                sha.update(chunk)
                size += len(chunk)
            whole = not beyond and not f.read(1)
    except FileNotFoundError:
        raise HistoryMismatch(f"{path} is missing; {step} recorded {n} rows in it: the run cannot be resumed "
                              "(start it again with --overwrite)") from None
    except OSError as e:
        raise HistoryMismatch(f"{path}: cannot be read ({e.strerror or e})") from None
    if n is None:  # an older checkpoint, without the record, and no count given: nothing to check here
        return size, whole, sha
    if lines == 0:
        raise HistoryMismatch(f"{path} is empty (not even its header line); {step} recorded {n} rows: the run cannot "
                              "be resumed (start it again with --overwrite)")
    if lines - 1 < n:
        raise HistoryMismatch(f"{path} has {lines - 1} rows, {step} recorded {n}: rows were lost, the run "
                              "cannot be resumed (start it again with --overwrite)")
    if "history_sha256" in info:
        last = tail[:-1].rsplit(b"\n", 1)[-1].split(b",", 1)[0].decode(errors="replace")
        if n and info["history_last_t"] is not None and _number(last) != info["history_last_t"]:
            raise HistoryMismatch(f"{path}: row {n} has t = {last} s, {step} recorded t = "
                                  f"{info['history_last_t']:.9g} s for it: the history is another run's")
        if sha.hexdigest() != info["history_sha256"]:
            raise HistoryMismatch(f"{path}: its header and first {n} rows are not those {step} recorded (SHA-256 "
                                  "differs): the history was changed, or is another run's")
    return size, whole, sha


def _number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def first_loaded_row(run_dir, columns):
    """{column: value} of history.csv's first row in ``run_dir`` whose ``columns`` sum to more than 0
    (None when no row does)."""
    try:
        with open(os.path.join(run_dir, NAME), newline="") as f:
            for row in csv.DictReader(f):
                values = {name: _number(text) for name, text in row.items()}
                if all(values.get(c) is not None for c in columns) and sum(values[c] for c in columns) > 0:
                    return values
    except OSError:
        return None
    return None
