"""Find, on a scratch scene, where YADE keeps what the bridge reads and writes, and verify it.

Nothing is assumed about YADE's object layout. Values that occur nowhere else (exact binary
fractions, different per body, field and round) are written through YADE's Python API, and the
process's memory is searched for them through /proc/self/mem (a read there fails cleanly on an
unmapped address, where a pointer dereference would crash). Each offset must be found exactly once
and be the same for every probe body and round. The offsets are then handed to the C library and
verified behaviourally, reads before writes: bridge reads equal the Python API's values, bridge
writes are read back identically by the Python API, bridge forces and torques equal O.forces'
values, and a NewtonIntegrator step driven by bridge forces equals, bit for bit, the same step
driven by O.forces.addF/addT/setPermF. Any mismatch raises ProbeError and leaves the bridge off.

The probe runs in its own scene (O.addScene + O.switchToScene) and switches back to the user's
scene afterwards, so the user's bodies, forces, O.iter, O.time and O.dt are not touched.
"""
import os
import struct

import numpy as np
from yade import O, Quaternion, Vector3, utils
from yade.wrapper import ForceResetter, NewtonIntegrator, PyRunner

N_PROBE = 6          # probe bodies; the Newton check uses as many twins
SCENE_SCAN = 4096    # bytes of Scene searched for the BodyContainer pointer and the ForceContainer,
FORCES_SCAN = 512    # of the ForceContainer for its summed forces' data pointer,
BODY_SCAN = 512      # of Body for the State pointer, of State for pos, vel, angVel: at most, and no
STATE_SCAN = 1024    # further than the object's heap block where that can be read (Memory.extent)
CONTAINER_SCAN = 256  # bytes of BodyContainer that must be readable (it holds the body vector)
USER_SPACE = 1 << 47


class ProbeError(RuntimeError):
    """The layout could not be found uniquely or failed a check: the bridge stays off."""


class Memory:
    """Reads of this process's memory that return None instead of crashing on a bad address."""

    def __init__(self):
        try:
            self.fd = os.open("/proc/self/mem", os.O_RDONLY)
        except OSError as e:
            raise ProbeError(f"cannot open /proc/self/mem for safe reads: {e}") from e

    def close(self):
        os.close(self.fd)

    def read(self, addr, n):
        if not 4096 <= addr < USER_SPACE - n:
            return None
        try:
            data = os.pread(self.fd, n, addr)
        except OSError:
            return None
        return data if len(data) == n else None

    def word(self, addr):
        data = self.read(addr, 8)
        return None if data is None else struct.unpack("<Q", data)[0]

    def extent(self, addr, limit):
        """Bytes to search from an object's address: its heap block's usable size if `addr` starts an
        in-use glibc malloc chunk (size word before it, the next chunk marking it in use), else
        `limit`. Searching past the object could find a neighbour holding the same pointer (a
        shared_ptr's control block does); any wrong bound still only fails the probe."""
        head = self.word(addr - 8)
        if head is None or head & 2:  # unreadable, or an mmapped chunk
            return limit
        size = head & ~7
        after = self.word(addr - 8 + size) if 32 <= size <= 1 << 16 else None
        return min(limit, size - 8) if after is not None and after & 1 else limit

    def words(self, addr, n_bytes):
        data = self.read(addr, n_bytes)
        return None if data is None else struct.unpack(f"<{n_bytes // 8}Q", data)


def probe_value(field, body, rnd, sign=1.0):
    """Three exact binary fractions unique to (field, body, round): 100 f + 10 b + c + 1/2 + k/2^20."""
    return tuple(sign * (100 * field + 10 * body + c + 0.5 + (1 + rnd + 7 * body + 3 * c) * 2.0 ** -20)
                 for c in range(3))


def _pack(v):
    return struct.pack("<3d", *v)


def _unique(found, what):
    if len(found) != 1:
        raise ProbeError(f"{what}: {len(found)} candidates {sorted(found)[:8]}, need exactly one")
    return next(iter(found))


def libyade_path():
    """Path of the libyade.so mapped into this process (the one `import yade` loaded)."""
    with open("/proc/self/maps") as f:
        paths = {line.split()[-1] for line in f if line.rstrip().endswith("/libyade.so")}
    if len(paths) != 1:
        raise ProbeError(f"expected one libyade.so mapped in this process, found {sorted(paths) or 'none'}")
    return paths.pop()


def _find_bodies_offset(lib, mem, scene, slots):
    """Offset in Scene of the BodyContainer pointer: a word pointing to a readable block that holds
    the address of body 0's shared_ptr slot (as Body::byId returns it), and for which YADE's
    exported BodyContainer::size and operator[] agree with the body count and every slot. (Those two
    only read the container's first 0x28 bytes, which the readable block covers; the second test
    tells the container from a neighbouring heap object whose block reaches into it.)"""
    scene_words = mem.words(scene, mem.extent(scene, SCENE_SCAN) & ~7)
    if scene_words is None:
        raise ProbeError("the current Scene is not readable")
    found = set()
    for k, w in enumerate(scene_words):
        block = mem.words(w, CONTAINER_SCAN)
        if block is not None and slots[0] in block and _is_body_container(lib, w, slots):
            found.add(8 * k)
    return _unique(found, "BodyContainer pointer in Scene")


def _is_body_container(lib, bodies, slots):
    return lib.yb_bodies_size(bodies) == len(slots) and all(
        lib.yb_bodies_at(bodies, i) == s for i, s in enumerate(slots))


def _find_state_offsets(mem, bodies, values):
    """(State pointer in Body, pos, vel, angVel in State): each probe value found exactly once,
    at the same offsets for every body."""
    common = None
    for body, (pos, vel, angvel) in zip(bodies, values):
        words = mem.words(body, mem.extent(body, BODY_SCAN) & ~7)
        if words is None:
            raise ProbeError("a probe Body is not readable")
        found = set()
        for k, w in enumerate(words):
            block = mem.read(w, mem.extent(w, STATE_SCAN))
            if block is None:
                continue
            hits = [[j for j in range(0, len(block) - 23, 8) if block[j:j + 24] == _pack(v)]
                    for v in (pos, vel, angvel)]
            if all(len(h) == 1 for h in hits):
                found.add((8 * k, hits[0][0], hits[1][0], hits[2][0]))
        common = found if common is None else common & found
    return _unique(common, "State pointer in Body and pos/vel/angVel in State")


def _find_forces_offset(mem, scene, forces):
    """Offset in Scene of the ForceContainer: the place whose first word points to the per-thread
    force buffers, the first of which (the calling thread's) holds exactly the forces added through
    O.forces.addF to bodies 0..n-1."""
    expected = b"".join(_pack(f) for f in forces)
    found = set()
    for k, w in enumerate(mem.words(scene, mem.extent(scene, SCENE_SCAN) & ~7)):
        data = mem.word(w)
        if data is not None and mem.read(data, len(expected)) == expected:
            found.add(8 * k)
    return _unique(found, "ForceContainer in Scene")


def _find_force_data_offset(mem, scene, forces_off, forces):
    """Offset in the ForceContainer of the data pointer of its summed forces (the vector that
    addForceUnsynced adds to and a sync fills): the one word there that points straight at the
    forces of bodies 0..n-1, after a sync (the per-thread buffers are one pointer further)."""
    expected = b"".join(_pack(f) for f in forces)
    words = mem.words(scene + forces_off, min(FORCES_SCAN, (mem.extent(scene, SCENE_SCAN) - forces_off) & ~7))
    if words is None:
        raise ProbeError("the ForceContainer is not readable")
    found = {8 * k for k, w in enumerate(words) if mem.read(w, len(expected)) == expected}
    return _unique(found, "summed forces' data pointer in ForceContainer")


def _expect(cond, what):
    if not cond:
        raise ProbeError(f"verification failed: {what}")


def _verify(bridge, ids, rnd):
    """Behavioural checks through the configured bridge, reads before writes."""
    xz = np.empty((len(ids), 2))
    y = np.empty(len(ids))
    for field, getter in ((0, bridge.get_pos_xz), (1, bridge.get_vel_xz)):
        for i in ids:
            v = probe_value(field, int(i), rnd, -1.0)
            setattr(O.bodies[int(i)].state, ("pos", "vel")[field], Vector3(*v))
        getter(ids, xz)
        _expect(all(tuple(xz[k]) == probe_value(field, int(i), rnd, -1.0)[::2] for k, i in enumerate(ids)),
                f"{getter.__name__} reads what the Python API wrote")
    for i in ids:
        O.bodies[int(i)].state.angVel = Vector3(*probe_value(2, int(i), rnd, -1.0))
    bridge.get_angvel_y(ids, y)
    _expect(all(y[k] == probe_value(2, int(i), rnd, -1.0)[1] for k, i in enumerate(ids)),
            "get_angvel_y reads what the Python API wrote")

    V = np.array([probe_value(3, int(i), rnd)[::2] for i in ids])
    bridge.set_vel_xz(ids, V)
    _expect(all(tuple(O.bodies[int(i)].state.vel) == (V[k, 0], 0.0, V[k, 1]) for k, i in enumerate(ids)),
            "the Python API reads what set_vel_xz wrote")

    F = np.array([probe_value(4, int(i), rnd)[::2] for i in ids])
    T = np.array([probe_value(5, int(i), rnd)[1] for i in ids])
    f0 = [tuple(O.forces.f(int(i), True)) for i in ids]  # synced: this step's forces + permanent ones
    t0 = [tuple(O.forces.t(int(i), True)) for i in ids]
    bridge.add_force_xz(ids, F)
    bridge.add_force_xz(ids, F)
    bridge.add_torque_y(ids, T)
    # probe values have few significant bits: these sums are exact in any order
    _expect(all(tuple(O.forces.f(int(i), True)) == (f[0] + 2 * F[k, 0], f[1], f[2] + 2 * F[k, 1])
                for k, (i, f) in enumerate(zip(ids, f0))), "O.forces.f adds what add_force_xz added")
    _expect(all(tuple(O.forces.t(int(i), True)) == (t[0], t[1] + T[k], t[2])
                for k, (i, t) in enumerate(zip(ids, t0))), "O.forces.t adds what add_torque_y added")
    bridge.set_perm_force_xz(ids, F)
    _expect(all(tuple(O.forces.permF(int(i))) == (F[k, 0], 0.0, F[k, 1]) for k, i in enumerate(ids)),
            "O.forces.permF reads set_perm_force_xz")
    f0 = [tuple(O.forces.f(int(i), True)) for i in ids]  # synced: add_force_unsynced_xz adds to these
    bridge.add_force_unsynced_xz(ids, F)
    _expect(all(tuple(O.forces.f(int(i), True)) == (f[0] + F[k, 0], f[1], f[2] + F[k, 1])
                for k, (i, f) in enumerate(zip(ids, f0))), "O.forces.f adds what add_force_unsynced_xz added")


_step_forces = None  # what the Newton check's PyRunner applies each step


def _apply_step_forces():
    _step_forces()


def _verify_newton_step(bridge, n):
    """Bodies n..2n-1 are twins of 0..n-1; each step (after ForceResetter) the twins get their forces
    through the bridge (add_force_xz, add_force_unsynced_xz, add_torque_y, set_perm_force_xz), the
    originals through O.forces; after two steps (O.step(), then the bridge's steps(1)) each pair
    must be identical."""
    global _step_forces
    hook = f"__import__('sys').modules[{__name__!r}]._apply_step_forces()"
    # updateGlobals=False: by default PyRunner copies the locals of O.step()'s caller into __main__
    O.engines = [ForceResetter(), PyRunner(command=hook, iterPeriod=1, updateGlobals=False),
                 NewtonIntegrator(damping=0.0, gravity=(0, 0, -9.75))]
    O.dt = 2.0 ** -10
    _step_forces = lambda: None  # noqa: E731  (a first step leaves YADE's force buffers in step)
    O.step()
    for i in range(n):
        a, b = O.bodies[i].state, O.bodies[n + i].state
        b.pos, b.vel, b.angVel, b.ori = Vector3(a.pos), Vector3(a.vel), Vector3(a.angVel), Quaternion(a.ori)
    start = [tuple(O.bodies[i].state.pos) for i in range(n)]
    twins = np.arange(n, 2 * n, dtype=np.int64)
    F = np.array([probe_value(4, i, 0)[::2] for i in range(n)])
    P = np.array([probe_value(3, i, 0)[::2] for i in range(n)])
    T = np.array([probe_value(5, i, 0)[1] for i in range(n)])
    G = np.array([probe_value(3, i, 1)[::2] for i in range(n)])
    for i in range(n):
        O.forces.setPermF(i, Vector3(P[i, 0], 0.0, P[i, 1]))
    bridge.set_perm_force_xz(twins, P)

    def forces():
        for i in range(n):  # probe values have few significant bits: F + G is exact
            O.forces.addF(i, Vector3(F[i, 0] + G[i, 0], 0.0, F[i, 1] + G[i, 1]))
            O.forces.addT(i, Vector3(0.0, T[i], 0.0))
        bridge.add_force_unsynced_xz(twins, G)
        bridge.add_force_xz(twins, F)
        bridge.add_torque_y(twins, T)
    _step_forces = forces
    iter0 = O.iter
    try:
        O.step()
        bridge.steps(1)  # the bridge's O.step()
    finally:
        _step_forces = None
    _expect(O.iter == iter0 + 2, "the bridge's step advanced O.iter by one")
    for i in range(n):
        a, b = O.bodies[i].state, O.bodies[n + i].state
        _expect(all(tuple(getattr(a, f)) == tuple(getattr(b, f)) for f in ("pos", "vel", "angVel", "ori")),
                "two NewtonIntegrator steps with bridge forces equal those with O.forces")
        _expect(tuple(a.pos) != start[i], "the Newton check moved the bodies")


def _discover_and_verify(lib, bridge, mem):
    n = N_PROBE
    O.bodies.append([utils.sphere((0, 0, 0), 0.5) for _ in range(n)])
    scene = lib.yb_scene()
    slots = [lib.yb_body_slot(i) for i in range(n)]
    bodies_off = _find_bodies_offset(lib, mem, scene, slots)

    body_ptrs = [mem.word(s) for s in slots]
    candidates = set()
    for rnd in range(2):
        values = [tuple(probe_value(f, i, rnd) for f in range(3)) for i in range(n)]
        for i, (pos, vel, angvel) in enumerate(values):
            st = O.bodies[i].state
            st.pos, st.vel, st.angVel = Vector3(*pos), Vector3(*vel), Vector3(*angvel)
        found = _find_state_offsets(mem, body_ptrs, values)
        candidates.add(found)
    state_offs = _unique(candidates, "State offsets across rounds")

    forces = [probe_value(4, i, 0) for i in range(n)]  # the scratch scene's first forces
    for i, f in enumerate(forces):
        O.forces.addF(i, Vector3(*f))
    forces_off = _find_forces_offset(mem, scene, forces)
    O.forces.f(0, True)  # a sync: the summed forces hold them too
    try:
        force_data_off = _find_force_data_offset(mem, scene, forces_off, forces)
    except ProbeError:  # not found uniquely: add_force_unsynced_xz calls addForceUnsynced, as before
        force_data_off = -1

    lib.yb_configure(forces_off, force_data_off, bodies_off, *state_offs, 1)
    ids = np.arange(n, dtype=np.int64)
    for rnd in range(2):
        _verify(bridge, ids, rnd)

    # a second body count (the body vector reallocates): the container checks must still hold
    O.bodies.append([utils.sphere((0, 0, 0), 0.5) for _ in range(n)])
    grown = [lib.yb_body_slot(i) for i in range(2 * n)]
    _expect(_is_body_container(lib, mem.word(lib.yb_scene() + bodies_off), grown),
            "BodyContainer::size and operator[] agree with Body::byId after the body vector grew")
    _verify(bridge, np.arange(2 * n, dtype=np.int64)[::-1].copy(), 2)
    _verify_newton_step(bridge, n)
    return {"forces": forces_off, "force_data": force_data_off, "bodies": bodies_off, "state": state_offs[0],
            "pos": state_offs[1], "vel": state_offs[2], "angvel": state_offs[3]}


def run(lib, bridge):
    """Discover and verify the layout on a scratch scene; return the offsets (bytes) or raise
    ProbeError. `lib` is the opened C library, `bridge` the module of numpy wrappers."""
    if O.running:
        raise ProbeError("the simulation is running: call engines.yade.yadebulk.available() before O.run()")
    home, home_scene = O.thisScene, lib.yb_scene()
    before = repr((O.iter, O.time, O.dt, len(O.bodies)))
    mem = Memory()
    scratch = O.addScene()
    O.switchToScene(scratch)
    try:
        return _discover_and_verify(lib, bridge, mem)
    except BaseException:
        lib.yb_configure(0, -1, 0, 0, 0, 0, 0, 0)
        raise
    finally:
        O.resetThisScene()
        O.switchToScene(home)
        mem.close()
        if lib.yb_scene() != home_scene or repr((O.iter, O.time, O.dt, len(O.bodies))) != before:
            lib.yb_configure(0, -1, 0, 0, 0, 0, 0, 0)
            raise ProbeError("switching back to the user's scene did not restore it")
