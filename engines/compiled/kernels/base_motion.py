"""The base motion compiled (engines.model.ground_motion.BaseMotion.step): a Cosine or a Sampled
record (np.interp's arithmetic) integrated by the trapezoid rule, the wall velocity of the step.
Its numbers by name: MOTION. No YADE."""
import math

import numpy as np

from engines.compiled.kernels.common import jit
from engines.compiled.layout import Layout


# The base motion of the drive (engines.model.ground_motion.BaseMotion): its numbers, and for a
# sampled input (Sampled) its record (t_s, a_s) passed beside them; a cosine passes empty records.
MOTION = Layout("MOTION", ("amplitude", "w", "left", "right", "dt", "acc", "vel", "disp", "wall_velocity"))


@jit
def sampled_acceleration(t, t_s, a_s, left, right):
    """Twin of engines.model.ground_motion.Sampled at a time t [s]: np.interp(t, t_s, a_s, left,
    right) in NumPy's arithmetic (the interval's slope times the distance from its start, plus its
    start value; a sample's own value at a sample time) [m/s^2]."""
    last = len(t_s) - 1
    if t > t_s[last]:
        return right
    if t < t_s[0]:
        return left
    if t == t_s[last]:
        return a_s[last]
    j = np.searchsorted(t_s, t, side="right") - 1  # t_s[j] <= t < t_s[j + 1]
    if t == t_s[j]:
        return a_s[j]
    slope = (a_s[j + 1] - a_s[j]) / (t_s[j + 1] - t_s[j])
    return slope * (t - t_s[j]) + a_s[j]


@jit
def base_step(motion, t_s, a_s, k):
    """Twin of engines.model.ground_motion.BaseMotion.step: motion (MOTION: amplitude [m/s^2] and
    2 pi frequency [rad/s] of a Cosine, left and right [m/s^2] of a Sampled record (t_s, a_s) (s,
    m/s^2; empty for a Cosine), dt [s], acc, vel, disp, wall velocity) advanced in place from
    step k to k + 1; the wall velocity of that step is (u_k+1 - u_k) / dt [m/s]."""
    dt = motion[MOTION.dt]
    t = (k + 1) * dt
    if len(t_s):
        a_next = sampled_acceleration(t, t_s, a_s, motion[MOTION.left], motion[MOTION.right])
    else:
        a_next = motion[MOTION.amplitude] * math.cos(motion[MOTION.w] * t)
    a_bar = 0.5 * (motion[MOTION.acc] + a_next)
    du = motion[MOTION.vel] * dt + 0.5 * a_bar * dt * dt
    motion[MOTION.vel] += a_bar * dt
    motion[MOTION.disp] += du
    motion[MOTION.acc] = a_next
    motion[MOTION.wall_velocity] = du / dt
