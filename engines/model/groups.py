"""The boundary kinds, the one table: what bounds the pores, how a scene or a packing gives it and
what it does to the water of a pore that has it as a vertex. Packing files store the disc group
codes; the pores take the wall codes as their boundaries; flat walls carry a word. The model (the
water step's masks, the pores' wall codes, the scene's flat walls), its compiled twins (they take
the model's masks), the YADE glue (WaterEngine's ``walls`` and ``flat_walls``) and the scenes'
choices read this table. No project imports, so that readers of run files (postproc) need nothing
else.

What a kind does to a pore's water (WATER), each a mask of the water step (PoreWater.boundary_masks):
  surface    U = 0 outside, exchange through k1 (eq 43a), booked as surface outflow
  drained    U = 0 outside, exchange through k3 (§6.1), booked as side outflow
  inflow     q_w into the pore (§5.1) or inflow_velocity x its inflow edges (SPEC §2.7), booked as inflow
  undrained  nothing crosses
  sides      (disc groups only) as the word [water] sides names ("undrained" or "drained")
"""
from typing import NamedTuple

WATER = ("surface", "drained", "inflow", "undrained")  # what a kind does to a pore's water (docstring)


class BoundaryKind(NamedTuple):
    """One row of BOUNDARY_KINDS."""

    name: str    # packing files' group name, WaterEngine(walls={name: ids}), a flat wall's word
    group: int   # disc group code stored in packing files (>= 1); 0: not a disc group
    word: bool   # a flat wall's boundary (FlatWall.boundary, WaterEngine(flat_walls={id: name}))
    water: str   # what it does to a pore's water: one of WATER, or "sides" (disc groups, docstring)
    face: tuple  # (axis, inward) of a disc group's inner face and of the flat wall that replaces it:
    #              axis 0 (x = const) or 1 (z = const), inward +1 when the discs lie above / right of it


BOUNDARY_KINDS = (
    #            name         group  word   water        face
    BoundaryKind("surface",   0,     False, "surface",   ()),       # the bed's open top (PoreNetwork.pore_surface)
    BoundaryKind("left",      2,     False, "sides",     (0, 1)),   # wall discs left of the bed
    BoundaryKind("right",     3,     False, "sides",     (0, -1)),  # wall discs right of the bed
    BoundaryKind("bottom",    1,     False, "inflow",    (1, 1)),   # wall discs under the bed
    BoundaryKind("undrained", 0,     True,  "undrained", ()),
    BoundaryKind("drained",   0,     True,  "drained",   ()),
    BoundaryKind("inflow",    0,     True,  "inflow",    ()),
)


def disc_groups():
    """The kinds given as disc groups (packing files' wall codes), in the table's order."""
    return tuple(k for k in BOUNDARY_KINDS if k.group)


def words():
    """The flat-wall words (FlatWall.boundary)."""
    return tuple(k.name for k in BOUNDARY_KINDS if k.word)


def kind(name):
    """The row of ``name``; KeyError naming the known ones."""
    for k in BOUNDARY_KINDS:
        if k.name == name:
            return k
    raise KeyError(f"boundary kind {name!r}; known: {[k.name for k in BOUNDARY_KINDS]}")


def water_of(name, sides):
    """What the kind ``name`` does to a pore's water (one of WATER), with [water] sides = ``sides``."""
    k = kind(name)
    return kind(sides).water if k.water == "sides" else k.water


def flat_word(name, sides, inflow):
    """The word of the flat wall that stands in for the disc group ``name`` in a scene ([walls]
    kind = flat): the word of what the group does to the water; an inflow group passes no water
    when the scene has no inflow (``inflow`` False)."""
    water = water_of(name, sides)
    water = "undrained" if water == "inflow" and not inflow else water
    return next(k.name for k in BOUNDARY_KINDS if k.word and k.water == water)


WALL_NONE = 0  # the particles' group code
WALL_BOTTOM, WALL_LEFT, WALL_RIGHT = (kind(name).group for name in ("bottom", "left", "right"))
GROUP_NAMES = {WALL_NONE: "particle", **{k.group: k.name for k in sorted(disc_groups(), key=lambda k: k.group)}}
WALL_NAMES = {code: name for code, name in GROUP_NAMES.items() if code != WALL_NONE}  # by code
WALL_CODES = {name: code for code, name in WALL_NAMES.items()}                        # by name
LAST_GROUP = max(GROUP_NAMES)  # the highest disc group code
SIDE_WORDS = tuple(name for name in words() if kind(name).water != "inflow")  # the choices of [water] sides
