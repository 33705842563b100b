"""Input ground motion of the seismic box (seed 000 §6.1, SPEC §2.5). Pure NumPy, no YADE.

The bottom wall follows a horizontal acceleration a(t) [m/s^2]; its velocity and displacement come
from a(t) "by the constant-acceleration method" (等加速度法, §6.1), step by step:

    in step n (t_n = n dt -> t_n+1) the acceleration is held at a_bar = (a_n + a_n+1) / 2, so
    v_n+1 = v_n + a_bar dt,    u_n+1 = u_n + v_n dt + a_bar dt^2 / 2,

Newmark's constant-average-acceleration scheme (beta = 1/4, gamma = 1/2), the usual meaning of the
name; exact for an acceleration linear within each step and second order in dt otherwise. The
wall is given the velocity (u_n+1 - u_n)/dt during step n, so that a DEM update x += v dt puts it
exactly on u_n+1 (``BaseMotion.step``).

Inputs:
* ``cosine``: a = A cos(2 pi f t); the paper's A = 1500 gal = 15 m/s^2, f = 50 Hz (Fig. 33).
  From rest it gives v = A/w sin(w t), u = A/w^2 (1 - cos w t): the base oscillates about
  +A/w^2 (152 um for the paper's input) without drift.
* ``record_acceleration``: any two-column record (time [s], acceleration in g, gal or m/s^2),
  read by ``read_record`` with errors naming the file and line; time and amplitude rescaled as
  t -> time_scale t, a -> amplitude_scale a; linear between samples, zero before and after.
* The El Centro 1940 N-S record (yade_scripts/scenes/elcentro_ns_1940.txt, a copy of
  shared/data/elcentro_ns_1940.txt: 0.02 s samples, PGA 0.31882 g). The paper says only that it
  changed "the time interval and the acceleration scale" (時間間隔、加速度倍率をかえ) so as to give the
  wave of Fig. 34 (not in the OCR), because its 0.18-s runs could not hold even one cycle of a
  10 Hz wave. Our reading (liquefaction_case6.toml): time_scale = 1/50, so that the sampling
  interval becomes 0.4 ms, the record's dominant 1-3 Hz move to 50-150 Hz around the cosine's
  50 Hz, and 0.18 s of run covers the first 9 s of the record (the strong motion, PGA at 2.04 s
  -> 40.8 ms); amplitude_scale = 15 / (0.31882 g) = 4.7976, so that its peak equals the cosine's
  1500 gal. The paper finds its El Centro shaking "smaller" than the cosine and the base motion
  smooth after 0.14 s (7 s of the record): both hold for this reading.

Units: SI; records given in g use g = 9.80665 m/s^2.
"""
import math
import re

import numpy as np

from engines.files.inputs import MB, check_input_file

G0 = 9.80665  # standard gravity [m/s^2]
UNITS = {"g": G0, "gal": 0.01, "m/s2": 1.0}  # record acceleration unit -> m/s^2
RECORD_LIMIT = 200 * MB  # the largest record file read [bytes]


class Cosine:
    """a(t) = amplitude cos(2 pi frequency t) [m/s^2] for amplitude [m/s^2] and frequency [Hz]; a
    class rather than a closure, so that a checkpoint stores its fields (engines.model.state)."""

    CHECKPOINT_FIELDS = ("amplitude", "w")
    CHECKPOINT_DERIVED = {}

    def __init__(self, amplitude, frequency):
        self.amplitude, self.w = amplitude, 2 * np.pi * frequency

    def __call__(self, t):
        wt = self.w * t
        return self.amplitude * (math.cos(wt) if isinstance(wt, float) else np.cos(wt))  # a scalar: math is 10x faster


class Sampled:
    """a(t) linear between samples (t_s, a_s), ``left`` before and ``right`` after them (None: the
    end sample's value), as np.interp; stored by a checkpoint like Cosine (the record as it was read)."""

    CHECKPOINT_FIELDS = ("t_s", "a_s", "left", "right")
    CHECKPOINT_RESIZED = ("t_s", "a_s")
    CHECKPOINT_DERIVED = {}

    def __init__(self, t_s, a_s, left=0.0, right=0.0):
        self.t_s, self.a_s, self.left, self.right = t_s, a_s, left, right

    def checkpoint_restored(self):
        if self.t_s.ndim != 1 or self.t_s.shape != self.a_s.shape:
            raise ValueError("the record's times and accelerations must be two columns of one length")

    def __call__(self, t):
        return np.interp(t, self.t_s, self.a_s, left=self.left, right=self.right)


def cosine(amplitude, frequency):
    """a(t) = amplitude cos(2 pi frequency t) [m/s^2] for amplitude [m/s^2] and frequency [Hz]."""
    return Cosine(amplitude, frequency)


def read_record(path):
    """Time [s] and acceleration (the file's unit) of a two-column text record.

    Columns separated by spaces, tabs or a comma; '#' starts a comment; blank lines are skipped.
    Raises ValueError naming the file (and line) for: a missing, empty or not regular file, one
    above RECORD_LIMIT bytes, a line without exactly two
    numbers, a non-finite value, fewer than two samples, a time that does not increase.
    """
    check_input_file(path, "record file", RECORD_LIMIT)
    rows, lines = [], []
    with open(path) as f:
        for k, line in enumerate(f, 1):
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            parts = [p for p in re.split(r"[,\s]+", text) if p]
            if len(parts) != 2:
                raise ValueError(f"{path}, line {k}: expected 2 columns (time [s], acceleration), got {len(parts)}: {text!r}")
            try:
                t, a = float(parts[0]), float(parts[1])
            except ValueError:
                raise ValueError(f"{path}, line {k}: not a number: {text!r}") from None
            if not (np.isfinite(t) and np.isfinite(a)):
                raise ValueError(f"{path}, line {k}: non-finite value: {text!r}")
            rows.append((t, a))
            lines.append(k)
    if len(rows) < 2:
        raise ValueError(f"{path}: a record needs at least 2 samples, got {len(rows)}")
    data = np.array(rows)
    bad = np.flatnonzero(np.diff(data[:, 0]) <= 0)
    if len(bad):
        i = bad[0]
        raise ValueError(f"{path}, line {lines[i + 1]}: time must increase, got {data[i + 1, 0]} after {data[i, 0]}")
    return data[:, 0], data[:, 1]


def record_acceleration(path, time_scale=1.0, amplitude_scale=1.0, units="g"):
    """a(t) [m/s^2] of a record: samples at time_scale t_i with value amplitude_scale a_i (in m/s^2),
    linear between samples, zero before the first and after the last."""
    if units not in UNITS:
        raise ValueError(f"record units must be one of {', '.join(UNITS)}, got {units!r}")
    if not (np.isfinite(time_scale) and time_scale > 0):
        raise ValueError(f"time_scale must be > 0, got {time_scale}")
    if not (np.isfinite(amplitude_scale) and amplitude_scale >= 0):
        raise ValueError(f"amplitude_scale must be >= 0, got {amplitude_scale}")
    t, a = read_record(path)
    t_s, a_s = t * time_scale, a * UNITS[units] * amplitude_scale
    return Sampled(t_s, a_s)


def input_acceleration(settings):
    """a(t) [m/s^2] of the [loading] table of ``settings`` (engines.model.settings.Settings), or None
    for type = none: the one input of the YADE path (engines.model.pore_dem.PoreDEM,
    engines.yade.coupling) and of engines.run.preflight."""
    ld = settings.loading
    if ld.type == "none":
        return None
    if ld.type == "cosine":
        return cosine(ld.amplitude, ld.frequency)
    try:
        return record_acceleration(ld.record, ld.time_scale, ld.amplitude_scale, ld.record_units)
    except ValueError as e:
        raise ValueError(f"[loading] record: {e}") from None


class BaseMotion:
    """Acceleration, velocity and displacement of the driven bottom wall, advanced one DEM step at
    a time by the constant-(average-)acceleration method (module docstring). Starts from rest at
    u = 0 at t = 0."""

    CHECKPOINT_FIELDS = ("accel", "k", "acc", "vel", "disp")  # what a checkpoint stores (engines.model.state)
    CHECKPOINT_DERIVED = {"dt": "the scene's dt"}

    def __init__(self, accel, dt):
        if not dt > 0:
            raise ValueError(f"dt must be > 0, got {dt}")
        self.accel, self.dt = accel, float(dt)
        self.k = 0
        self.acc = float(accel(0.0))
        self.vel = 0.0
        self.disp = 0.0

    @property
    def t(self):
        return self.k * self.dt

    def step(self):
        """Advance from t_k to t_k+1; returns the wall velocity for that step, (u_k+1 - u_k)/dt [m/s]."""
        dt = self.dt
        a_next = float(self.accel((self.k + 1) * dt))
        a_bar = 0.5 * (self.acc + a_next)
        du = self.vel * dt + 0.5 * a_bar * dt * dt
        self.vel += a_bar * dt
        self.disp += du
        self.acc = a_next
        self.k += 1
        return du / dt
