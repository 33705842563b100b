"""A run's history.csv as its checkpoint knows it (no YADE: ``--resume`` checks it before YADE starts).

The recorder appends rows and keeps a SHA-256 of the file's bytes so far (header and rows); each
checkpoint records the number of rows, the last row's t and that checksum (``info``). On resume,
``kept(run_dir, info)`` returns the header and the rows the checkpoint recorded, after checking
that the file holds them: missing, short, another run's or edited rows are refused in one line
naming the file and what differs. Rows after the checkpoint (written before a stop or crash) are
dropped by the resume, which computes them again.
"""
import hashlib
import os

NAME = "history.csv"


class HistoryMismatch(ValueError):
    """history.csv does not hold the rows the checkpoint recorded; the message says what differs."""


def info(rows, last_t, digest):
    """The checkpoint's record of the history: ``rows`` written, the last one's t [s] (as written),
    the SHA-256 (hex) of the file's bytes."""
    return {"history_rows": int(rows), "history_last_t": last_t, "history_sha256": digest}


def kept(run_dir, info, rows=None):
    """(the bytes of history.csv to keep: header and the checkpoint's rows, whether that is the
    whole file). ``info``: the checkpoint's (``info`` above, and its "step"); a checkpoint without
    that record: only the count ``rows`` is checked (none if None)."""
    path = os.path.join(run_dir, NAME)
    n = info.get("history_rows", rows)
    if n is None:  # an older checkpoint, without the record, and no count given: nothing to check here
        return None, True
    step = f"the checkpoint at step {info['step']}" if "step" in info else "the checkpoint"
    try:
        with open(path, "rb") as f:
            data = f.read()
    except FileNotFoundError:
        raise HistoryMismatch(f"{path} is missing; {step} recorded {n} rows in it: the run cannot be resumed "
                              "(start it again with --overwrite)") from None
    except OSError as e:
        raise HistoryMismatch(f"{path}: cannot be read ({e.strerror or e})") from None
    lines = data.splitlines(keepends=True)
    complete = [x for x in lines if x.endswith(b"\n")]
    if not complete:
        raise HistoryMismatch(f"{path} is empty (not even its header line); {step} recorded {n} rows: the run cannot "
                              "be resumed (start it again with --overwrite)")
    if len(complete) - 1 < n:
        raise HistoryMismatch(f"{path} has {len(complete) - 1} rows, {step} recorded {n}: rows were lost, the run "
                              "cannot be resumed (start it again with --overwrite)")
    keep = b"".join(complete[:1 + n])
    if "history_sha256" in info:
        last = complete[n].split(b",", 1)[0].decode(errors="replace") if n else None
        if n and info["history_last_t"] is not None and _number(last) != info["history_last_t"]:
            raise HistoryMismatch(f"{path}: row {n} has t = {last} s, {step} recorded t = {info['history_last_t']:.9g} s "
                                  "for it: the history is another run's")
        if hashlib.sha256(keep).hexdigest() != info["history_sha256"]:
            raise HistoryMismatch(f"{path}: its header and first {n} rows are not those {step} recorded (SHA-256 "
                                  "differs): the history was changed, or is another run's")
    return keep, keep == data


def _number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None
