"""YADE's own walls as flat walls of the pores (SPEC §2.6): a ``Wall`` body (utils.wall) or the face
of an axis-aligned ``Box`` (utils.box, utils.aabbWalls) that the discs lie against becomes an
engines.model.flat_walls.FlatWall. Refused in one line naming the body (ContractError): a body that
is not a Box or Wall (a Facet), a rotated box, a wall facing along y (out of the discs' x-z plane:
leave aabbWalls' front and back boxes out), a box or two-sided wall with discs on more than one
side, a wall that spins or has turned. A wall may translate (a TranslationEngine, its velocity):
``WallMotion`` reads how far each has moved since the start, in the x-z plane.
"""
import numpy as np

from engines.model.flat_walls import FlatWall
from engines.model.groups import words
from engines.yade.contract import ContractError

PLANE_AXES = (0, 2)  # YADE's x and z: FlatWall axes 0 and 1


def flat_walls(bodies, boundaries, xz):
    """The FlatWalls of the YADE bodies {id: boundary} (boundary a word of engines.model.groups) of O.bodies
    ``bodies``, for discs with centres xz (N, 2) [m] (x, z); in the order of ``boundaries``."""
    return [flat_wall(bodies, int(i), boundary, np.asarray(xz, float)) for i, boundary in boundaries.items()]


def flat_wall(bodies, i, boundary, xz):
    """The FlatWall of body i (see flat_walls)."""
    b = bodies[i] if 0 <= i < len(bodies) else None
    if b is None:
        raise ContractError(f"body {i}: not in O.bodies (flat_walls must be existing Box or Wall bodies)")
    shape = type(b.shape).__name__
    if boundary not in words():
        raise ContractError(f"body {i}: boundary {boundary!r} in flat_walls; one of {', '.join(words())}")
    _check_not_turning(i, b)
    if shape == "Wall":
        return _wall(i, b, boundary, xz)
    if shape == "Box":
        return _box_face(i, b, boundary, xz)
    raise ContractError(f"body {i}: a {shape}; flat walls are YADE Box or Wall bodies (a facet is not taken)")


def _sides(i, shape, offsets):
    """+1 or -1: the side of a face all disc centres lie on (offsets: centre minus face [m])."""
    if np.all(offsets > 0):
        return 1
    if np.all(offsets < 0):
        return -1
    raise ContractError(f"body {i}: a {shape} with discs on both sides of its face; a flat wall bounds the discs "
                        f"from one side")


def _wall(i, b, boundary, xz):
    axis = int(b.shape.axis)
    if axis not in PLANE_AXES:
        raise ContractError(f"body {i}: a Wall facing along y, out of the discs' x-z plane (leave it out of flat_walls)")
    a = PLANE_AXES.index(axis)
    position = float(b.state.pos[axis])
    inward = _sides(i, "Wall", xz[:, a] - position)
    if b.shape.sense not in (0, inward):
        raise ContractError(f"body {i}: a Wall of sense {b.shape.sense} with the discs on its side {inward:+d}")
    return FlatWall(a, position, inward, boundary)


def _box_face(i, b, boundary, xz):
    """The face of box b the discs lie beyond, among its four faces in the x-z plane."""
    if np.max(np.abs(np.array(b.state.ori.toRotationMatrix()) - np.eye(3))) > 1e-12:
        raise ContractError(f"body {i}: a rotated Box (orientation {b.state.ori}); flat walls are axis-aligned")
    centre, half = np.array(b.state.pos), np.array(b.shape.extents)
    faces = []
    for a, axis in enumerate(PLANE_AXES):
        for inward in (1, -1):
            position = centre[axis] + inward * half[axis]
            if np.all(inward * (xz[:, a] - position) > 0):
                faces.append(FlatWall(a, float(position), inward, boundary))
    if len(faces) != 1:
        why = ("no face of it has every disc beyond it (a box facing along y, out of the x-z plane, or with discs "
               "around it)" if not faces else "the discs lie beyond two of its faces (at a corner of it)")
        raise ContractError(f"body {i}: a Box that bounds the discs from no single side: {why}; leave it out of "
                            f"flat_walls or make one box per side")
    return faces[0]


def _check_not_turning(i, b):
    """Refuse body i (b) when it spins."""
    if b.state.angVel.norm() > 0:
        raise ContractError(f"body {i}: a {type(b.shape).__name__} that turns (angular velocity {b.state.angVel}); "
                            f"flat walls may translate, not rotate")


class WallMotion:
    """The translations of the flat-wall bodies ``ids`` of O.bodies (in the order of flat_walls)
    since they were read: ``shift()`` (W, 2) [m] in (x, z), the WallVertices' shift
    (engines.model.flat_walls); refuses a body that spins. Holds no YADE object."""

    # a checkpoint stores nothing of it (engines.model.state)
    CHECKPOINT_FIELDS = ()
    CHECKPOINT_DERIVED = {"ids": "the flat walls' bodies, built from the scene",
                          "start": "their positions as built (the same in a run built again)"}

    def __init__(self, ids):
        from yade import O
        self.ids = [int(i) for i in ids]
        self.start = self._positions(O.bodies)

    def _positions(self, bodies):
        return np.array([[bodies[i].state.pos[a] for a in PLANE_AXES] for i in self.ids]).reshape(-1, 2)

    def shift(self):
        from yade import O
        for i in self.ids:
            _check_not_turning(i, O.bodies[i])
        return self._positions(O.bodies) - self.start
