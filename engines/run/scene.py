"""Scene files: a TOML document describing one run of the seed-000 model, validated into settings.

A scene is data, not code. The paper's cases are presets in ``yade_scripts/scenes/*.toml``; a
scene may ``extends = "other.toml"`` (a path) or ``extends = "quicksand_case1"`` (a preset's name,
``resolve``) and override any field. Every field, its unit and its
default is listed in SCHEMA below; ``/usr/bin/python3 -m engines.run.scene`` prints it as the table
in yade_scripts/scenes/README.md. Unknown tables or fields, wrong types and out-of-range values
raise SceneError naming the field: every number finite (list elements too), ``[scene] name`` one
plain name (engines.files.inputs.check_name: it names files), and a scene file (``--scene``,
``extends``) a regular file of at most SCENE_LIMIT bytes.
"""
import math
import os
import tomllib
from dataclasses import dataclass, field

from engines import ROOT
from engines.files.inputs import MB, check_input_file, check_name
from engines.model.fields import POS, REQUIRED, check, checked, describe_check
from engines.model.settings import TABLES, Settings

SCENE_DIR = os.path.join(ROOT, "yade_scripts", "scenes")
SCENE_LIMIT = 1 * MB  # the largest scene file read [bytes]


class SceneError(ValueError):
    """A scene file is invalid; the message names the field."""


# table -> field -> (type, default, check, unit/meaning) (engines.model.fields.Field). check: None,
# (min, max) inclusive bounds (POS: > 0), a tuple of allowed strings, or POS_OR_AUTO. [scene] and
# [packing] are the run layer's; the other tables are the model's settings (engines.model.settings).
SCHEMA = {
    "scene": {
        "name": (str, REQUIRED, None, "run name"),
        "description": (str, "", None, "free text"),
    },
    "packing": {
        "source": (str, "deposit", ("deposit", "file"), "deposit: drop discs into a wall-disc box; file: CSV x,z,r,group"),
        "file": (str, "", None, "CSV packing for source = file (relative to the scene file)"),
        "seed": (int, 1, (0, math.inf), "seed of the numpy Generator for sizes and placement"),
        "n_particles": (int, 45, (1, 100000), "particles to deposit"),
        "n_bottom": (int, 15, (2, 100000), "bottom wall discs (corners included)"),
        "n_side": (int, 9, (1, 100000), "discs of each side wall column, corner shared with the bottom"),
        "wall_radius": (float, 0.45e-3, POS, "wall disc radius [m]"),
        "mean_diameter": (float, 0.9e-3, POS, "mean of the log-normal diameters [m] (eq 53-54)"),
        "std_diameter": (float, 0.25e-3, POS, "standard deviation of the diameters [m]"),
        "d_min": (float, 0.4e-3, POS, "truncation of the diameters [m]"),
        "d_max": (float, 2.0e-3, POS, "truncation of the diameters [m]"),
        "settle_time": (float, 0.1, POS, "deposition time under gravity [s]"),
        "settle_dt": (float, 5e-6, POS, "time step of the deposition [s]"),
        "cut_extra": (float, 0.4, (0.0, 10.0), "deposit this fraction more particles, keep the lowest n_particles (a flat cut)"),
        "dense_top_depth": (float, 0.45e-3, (0.0, math.inf), "particles whose top lies within this depth of the top of their column are denser [m]"),
        "dense_top_factor": (float, 5.0, POS, "density factor of the top particles (5 quick sand, 10 seismic)"),
        # seismic box
        "dense_top_count": (int, 0, (0, 100000), "if > 0: the dense top particles are the n highest centres instead of the dense_top_depth layer (seismic: 54, the paper's discs 139-192)"),
        "wall_density_factor": (float, 1.0, POS, "density factor of the wall discs (seismic: 10; the side walls move)"),
        "settle_ks": (float, 0.0, (0.0, math.inf), "tangential stiffness during deposition [N/m] (§4.2: 0; §6: 3.5e4)"),
        "guard_walls": (bool, False, None, "deposition only: side walls raised above the highest particle (removed afterwards) so that no particle bounces out of the box"),
        "settle_loaded": (float, 0.0, (0.0, math.inf), "deposition only: after the dense top is marked, settle again this long [s] with its masses, so that the run starts at rest under its own weight (seismic: 0.15; 0 = not)"),
        "settle_submerged": (bool, False, None, "deposition only: the settle_loaded stage under the buoyant weight (rho f - rho_w) pi r^2 g, so that a saturated bed starts at rest in its water (quick sand); false: under the dry weight"),
    },
    **{table: cls.FIELDS for table, cls in TABLES.items()},  # the model's tables (engines.model.settings)
}


@dataclass
class Scene:
    """A validated scene: ``tables`` holds every field (defaults filled in), by table;
    ``overrides`` the {table: {field: value}} applied on top of the file (recorded by runs);
    ``settings``: the model's typed settings (engines.model.settings.Settings), what the model is given."""

    tables: dict
    path: str = ""
    overrides: dict = field(default_factory=dict)
    settings: Settings = None

    def __getattr__(self, table):
        try:
            return _Table(self.__dict__["tables"][table])
        except KeyError:
            raise AttributeError(table) from None

    def contact_settings(self):
        return self.settings.contact_settings()

    def water_settings(self):
        """The WaterSettings of [water], or None for a dry scene."""
        return self.settings.water_settings()

    def as_dict(self):
        return {t: dict(v) for t, v in self.tables.items()}

    def with_overrides(self, overrides):
        """A new validated scene with {table: {field: value}} replaced."""
        sc = validate(_merge(self.as_dict(), overrides), self.path)
        sc.overrides = _merge(self.overrides, overrides)
        return sc


class _Table(dict):
    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


def validate(raw, path=""):
    """Fill defaults and check every field of a parsed scene document; returns a Scene."""
    unknown = set(raw) - set(SCHEMA) - {"extends"}
    if unknown:
        raise SceneError(f"unknown table(s) {sorted(unknown)}; known: {sorted(SCHEMA)}")
    tables = {}
    for table, fields in SCHEMA.items():
        given = raw.get(table, {})
        if not isinstance(given, dict):
            raise SceneError(f"[{table}] must be a table")
        extra = set(given) - set(fields)
        if extra:
            raise SceneError(f"[{table}] unknown field(s) {sorted(extra)}; known: {sorted(fields)}")
        if table in TABLES:  # the model's settings check their fields as they are made
            try:
                made = TABLES[table](**given)
            except ValueError as e:
                raise SceneError(str(e)) from None
            tables[table] = {name: getattr(made, name) for name in fields}
            continue
        values = {}
        for name, spec in fields.items():
            if name in given:
                values[name] = check(f"[{table}] {name}", given[name], spec, SceneError)
            elif spec[1] is REQUIRED:
                raise SceneError(f"[{table}] {name}: required field is missing")
            else:
                values[name] = spec[1]
        tables[table] = values
    _cross_checks(tables, path)  # (the paths it resolves are the settings' too)
    return Scene(tables, path, settings=Settings(**{t: checked(cls, tables[t]) for t, cls in TABLES.items()}))


def _cross_checks(t, path):
    p = t["packing"]
    c = t["contact"]
    if c["law"] == "yade" and c["spring"] not in ("a", "b"):
        raise SceneError(f"[contact] spring = {c['spring']!r}: law = 'yade' has springs a and b only "
                         f"(no YADE law has the f_max plateau of c and d); use law = 'paper'")
    if t["numerics"]["dt_auto_factor"] <= 0:
        raise SceneError(f"[numerics] dt_auto_factor: must be in (0, 1], got {t['numerics']['dt_auto_factor']}")
    if p["d_min"] >= p["d_max"]:
        raise SceneError(f"[packing] d_min = {p['d_min']} must be < d_max = {p['d_max']}")
    if p["source"] == "file" and not p["file"]:
        raise SceneError("[packing] file: required when source = 'file'")
    if t["loading"]["type"] == "record" and not t["loading"]["record"]:
        raise SceneError("[loading] record: required when type = 'record'")
    _check_lists(t["output"])
    if t["water"]["q_w"] > 0 and t["water"]["inflow_velocity"] > 0:
        raise SceneError(f"[water] q_w = {t['water']['q_w']:g} m^2/s per inflow pore and inflow_velocity = "
                         f"{t['water']['inflow_velocity']:g} m/s are two ways of one inflow; set one of them to 0")
    if t["loading"]["side_walls"] == "springs" and c["law"] == "yade":
        raise SceneError("[loading] side_walls = 'springs': the side-wall ties run in the paper's law engine; "
                         "use [contact] law = 'paper'")
    if t["loading"]["side_walls"] == "springs" and t["loading"]["moves"] != "bottom":
        raise SceneError("[loading] side_walls = 'springs' needs moves = 'bottom' (the box moving as one has no springs)")
    if t["walls"]["kind"] == "flat" and t["loading"]["side_walls"] == "springs":
        raise SceneError("[walls] kind = 'flat': [loading] side_walls = 'springs' ties side-wall discs; flat side "
                         "walls are fixed or follow the base (use [walls] kind = 'discs')")
    try:
        check_name(t["scene"]["name"], "[scene] name")
    except ValueError as e:
        raise SceneError(str(e)) from None
    _resolve_paths(t, os.path.dirname(path) if path else SCENE_DIR)


def _finite(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _check_lists(out):
    """The list fields of [output] (every list field of SCHEMA), element by element: finite numbers
    (no NaN, no infinity, no strings), the shapes and orders their meanings need."""
    times = out["snapshot_times"]
    for k, v in enumerate(times):
        if not (_finite(v) and v >= 0):
            raise SceneError(f"[output] snapshot_times[{k}]: expected a finite time >= 0 [s], got {v!r}")
    if not out["block_z"]:
        raise SceneError("[output] block_z: expected at least one block [z0, z1], got []")
    for k, blk in enumerate(out["block_z"]):
        if not (isinstance(blk, list) and len(blk) == 2 and all(map(_finite, blk)) and blk[0] < blk[1]):
            raise SceneError(f"[output] block_z[{k}]: expected [z0, z1] of finite numbers with z0 < z1, got {blk!r}")
    win = out["porosity_window"]
    if not (len(win) == 2 and all(map(_finite, win)) and 0 <= win[0] < win[1]):
        raise SceneError(f"[output] porosity_window: expected [z0, z1] of finite numbers with 0 <= z0 < z1, got {win!r}")


LIST_FIELDS = tuple((table, name) for table, fields in SCHEMA.items() for name, spec in fields.items() if spec[0] is list)
PATH_FIELDS = (("packing", "file"), ("loading", "record"))  # relative to the file that names them


def _resolve_paths(tables, base):
    """Make the relative PATH_FIELDS of ``tables`` absolute against the folder ``base`` (in place)."""
    for table, name in PATH_FIELDS:
        sub = tables.get(table)
        value = sub.get(name) if isinstance(sub, dict) else None
        if isinstance(value, str) and value and not os.path.isabs(value):
            tables[table][name] = os.path.normpath(os.path.join(base, value))


def _merge(base, over):
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in base.items()}
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k].update(v)
        else:
            out[k] = v
    return out


def resolve(name, base=None):
    """The scene file ``name`` stands for (``--scene`` and ``extends``): a preset's name (no folder
    separator, no ``.toml``: yade_scripts/scenes/<name>.toml) or a path, relative to the folder
    ``base`` (default: the working folder)."""
    if "/" not in name and os.sep not in name and not name.endswith(".toml"):
        path = os.path.join(SCENE_DIR, name + ".toml")
        if not os.path.isfile(path):
            names = sorted(f[:-5] for f in os.listdir(SCENE_DIR) if f.endswith(".toml"))
            raise SceneError(f"scene {name!r}: no preset of that name (presets: {', '.join(names)}); "
                             f"a scene file's path ends in .toml")
        return path
    return os.path.normpath(os.path.join(base, name)) if base else name


def read_raw(path, _chain=None):
    """Parse a scene file, following ``extends`` chains; returns the merged TOML dict.

    Relative paths (``extends``, PATH_FIELDS) are resolved against the folder of the file that
    names them, so a scene anywhere may extend a preset and inherit its packing file."""
    try:
        check_input_file(path, "scene file", SCENE_LIMIT)
        with open(path, "rb") as f:
            raw = tomllib.load(f)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{path}: not valid TOML: {e}") from None
    except UnicodeDecodeError as e:
        raise SceneError(f"{path}: not a text file (byte {e.start} is not UTF-8); a scene is TOML text") from None
    except ValueError as e:
        raise SceneError(str(e)) from None
    path = os.path.abspath(path)
    _chain = (path,) if _chain is None else _chain
    _resolve_paths(raw, os.path.dirname(path))
    parent = raw.pop("extends", None)
    if parent is not None:
        if not isinstance(parent, str) or not parent:
            raise SceneError(f"{path}: extends: expected a scene file name, got {parent!r}")
        try:
            parent = resolve(parent, os.path.dirname(path))
        except SceneError as e:
            raise SceneError(f"{path}: extends: {e}") from None
        if parent in _chain:
            raise SceneError(f"{path}: extends: a loop back to {parent}")
        try:
            raw = _merge(read_raw(parent, _chain + (parent,)), raw)
        except SceneError as e:
            raise SceneError(f"{path}: extends: {e}" if str(e).startswith("scene file ") else str(e)) from None
    return raw


def load(path, overrides=None):
    """Read and validate a scene file or preset (``resolve``); ``overrides`` {table: {field: value}}
    are applied last."""
    path = resolve(path)
    raw = read_raw(path)
    if overrides:
        raw = _merge(raw, overrides)
    sc = validate(raw, path)
    sc.overrides = _merge({}, overrides or {})
    return sc


def preset(name, overrides=None):
    """Load ``yade_scripts/scenes/<name>.toml``."""
    return load(os.path.join(SCENE_DIR, name + ".toml"), overrides)


def schema_markdown():
    """The schema as a Markdown table (yade_scripts/scenes/README.md)."""
    lines = ["| table | field | type | default | range or choices | meaning |", "|---|---|---|---|---|---|"]
    for table, fields in SCHEMA.items():
        for name, (typ, default, bounds, doc) in fields.items():
            shown = "required" if default is REQUIRED else repr(default)
            lines.append(f"| {table} | {name} | {typ.__name__} | {shown} | {describe_check(bounds)} | {doc} |")
    return "\n".join(lines)


if __name__ == "__main__":
    print(schema_markdown())
