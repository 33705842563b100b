"""YADE's own walls as flat walls of the pores (SPEC §2.6): a ``Wall`` body (utils.wall) or the face
of an axis-aligned ``Box`` (utils.box, utils.aabbWalls) that the discs lie against becomes an
engines.model.flat_walls.FlatWall. Refused in one line naming the body (ContractError): a body that
is not a Box or Wall (a Facet), a rotated box, a wall facing along y (out of the discs' x-z plane:
leave aabbWalls' front and back boxes out), a box or two-sided wall with discs on more than one
side, a wall that moves or spins.
"""
import numpy as np

from engines.model.flat_walls import BOUNDARIES, FlatWall
from engines.yade.contract import ContractError

PLANE_AXES = (0, 2)  # YADE's x and z: FlatWall axes 0 and 1


def flat_walls(bodies, boundaries, xz):
    """The FlatWalls of the YADE bodies {id: boundary} (boundary one of BOUNDARIES) of O.bodies
    ``bodies``, for discs with centres xz (N, 2) [m] (x, z); in the order of ``boundaries``."""
    return [flat_wall(bodies, int(i), boundary, np.asarray(xz, float)) for i, boundary in boundaries.items()]


def flat_wall(bodies, i, boundary, xz):
    """The FlatWall of body i (see flat_walls)."""
    b = bodies[i] if 0 <= i < len(bodies) else None
    if b is None:
        raise ContractError(f"body {i}: not in O.bodies (flat_walls must be existing Box or Wall bodies)")
    shape = type(b.shape).__name__
    if boundary not in BOUNDARIES:
        raise ContractError(f"body {i}: boundary {boundary!r} in flat_walls; one of {', '.join(BOUNDARIES)}")
    if b.state.vel.norm() > 0 or b.state.angVel.norm() > 0:
        raise ContractError(f"body {i}: a {shape} that moves (velocity {b.state.vel}, angular velocity "
                            f"{b.state.angVel}); flat walls are fixed for now")
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
