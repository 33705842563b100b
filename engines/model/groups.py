"""The group codes of the discs, the one table: particles, and the wall discs by wall (Packing files
store the codes; the pores take the wall codes as their boundaries). No imports, so that readers of
run files (postproc) need nothing else."""

WALL_NONE, WALL_BOTTOM, WALL_LEFT, WALL_RIGHT = 0, 1, 2, 3
GROUP_NAMES = {WALL_NONE: "particle", WALL_BOTTOM: "bottom", WALL_LEFT: "left", WALL_RIGHT: "right"}
WALL_NAMES = {code: name for code, name in GROUP_NAMES.items() if code != WALL_NONE}  # by code
WALL_CODES = {name: code for code, name in WALL_NAMES.items()}                        # by name
