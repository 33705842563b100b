"""The model's settings, one dataclass per table of a scene file, made from the field lists declared
here (engines.model.fields: type, default, range or choices, meaning; ``settings_class``). No YADE.

The scene schema (engines.run.scene.SCHEMA) takes these lists as its tables ([walls], [material],
[contact], [water], [loading], [numerics], [output]; [scene] and [packing] are the run layer's), and a
validated scene hands the model its ``Settings``: the model reads these typed settings, never the
run layer's scene. Each value is checked once, when its table is made (``settings_class``); the
settings of the contact law and of the water (ContactSettings, WaterSettings) are taken from the
checked tables without a second check (``Settings.contact_settings``, ``Settings.water_settings``).
"""
import dataclasses
import math

from engines.model.contact import CONTACT_FIELDS, ContactSettings
from engines.model.fields import POS, POS_OR_AUTO, Field, checked, settings_class
from engines.model.pore_water import WATER_FIELDS, WaterSettings

# the default [numerics] dt_auto_factor: the trade study's fast setting (docs/TRADEOFFS.md; where it is
# validated: engines.studies.tradeoffs.VALIDATED_ON)
DT_AUTO_FACTOR = 0.36

WALLS_FIELDS = {
    "kind": Field(str, "discs", ("discs", "flat"), "discs: the packing's wall discs (groups bottom, left, right) bound the box; flat: they are replaced by YADE Box bodies at their inner faces (bottom: max z + r, left: max x + r, right: min x - r; moved back to a particle that reaches past one), the pores' flat walls: the bottom one lets in q_w (if > 0), the sides drain when [water] sides = drained; with [loading] they follow the base as [loading] moves says, not on springs; with [contact] law = paper the paper's law meets them itself)"),
}
MATERIAL_FIELDS = {
    "rho": Field(float, 2700.0, POS, "particle density [kg/m^3] (per unit thickness: mass = rho pi r^2)"),
    "rho_w": Field(float, 1000.0, (0.0, math.inf), "water density [kg/m^3]"),
    "g": Field(float, 9.81, (0.0, math.inf), "gravity [m/s^2], along -z"),
}
TIE_FIELDS = {  # side-wall springs of the seismic box (Fig. 27; used when loading.side_walls = springs)
    "ks_wall": Field(float, 1.5e5, (0.0, math.inf), "k'_s: tangential spring between vertical neighbours of a side-wall column, the lowest tied to the base [N/m]"),
    "eta_s_wall": Field(float, 0.6, (0.0, math.inf), "eta'_s: tangential dashpot of the same ties [N s/m]"),
}
CONTACT_TABLE = {  # the contact law's constants (CONTACT_FIELDS) and the engine's own choices
    **CONTACT_FIELDS,
    "law": Field(str, "paper", ("paper", "yade"), "paper: the paper's law as its own engine (engines.model.paper_law); yade: springs a/b mapped to YADE's ViscElMat law with its collider (no eq 18-24, docs/ENGINE.md)"),
    **TIE_FIELDS,
}
WATER_TABLE = {  # the water's constants (WATER_FIELDS) and the engine's own choices
    "enabled": Field(bool, True, None, "false: a dry scene, no water code runs"),
    **WATER_FIELDS,
    "l_m": Field(float, 1.3e-4, (0.0, math.inf), "link range beyond touching [m] (eq 28)"),
    "max_substeps": Field(int, 100, (1, math.inf), "with substep: refuse up front a water step that needs more sub-steps than this at the start"),
}
LOADING_FIELDS = {
    "type": Field(str, "none", ("none", "cosine", "record"), "horizontal acceleration of the moving walls"),
    "moves": Field(str, "bottom", ("bottom", "box"), "which walls follow the input"),
    "amplitude": Field(float, 15.0, (0.0, math.inf), "cosine amplitude [m/s^2] (1500 gal = 15)"),
    "frequency": Field(float, 50.0, POS, "cosine frequency [Hz]"),
    "record": Field(str, "", None, "two-column file time [s], acceleration [g]"),
    "time_scale": Field(float, 1.0, POS, "record time is multiplied by this"),
    "amplitude_scale": Field(float, 1.0, (0.0, math.inf), "record acceleration is multiplied by this"),
    "record_units": Field(str, "g", ("g", "gal", "m/s2"), "unit of the record's acceleration column"),
    "side_walls": Field(str, "fixed", ("fixed", "springs"), "side-wall columns: fixed, or moving in x tied by k'_s, eta'_s springs (Fig. 27; needs moves = bottom)"),
}
NUMERICS_FIELDS = {
    "dt": Field(float, 1e-6, POS_OR_AUTO, "time step [s], or \"auto\": dt_auto_factor x the smallest stability limit (engines.model.start)"),
    "duration": Field(float, 0.06, POS, "simulated time [s]"),
    "rebuild_interval": Field(int, 1000, (1, math.inf), "steps between pore rebuilds (§3.4(2)); with rebuild_distance > 0 an upper bound"),
    "rebuild_distance": Field(float, 0.0, (0.0, math.inf), "> 0: the pores are also rebuilt as soon as a disc has moved more than this [m] since the last build (WaterEngine's default in users' scripts: 0.25 l_m, docs/ENGINE.md); 0: off, every rebuild_interval steps as the paper does"),
    "water_interval": Field(int, 1, (1, math.inf), "DEM steps per water step; pressure forces persist in between"),
    "dt_safety": Field(float, 1.0, (0.0, 1.0), "dt must be <= dt_safety * 2 sqrt(m_min / kn) (eq 52)"),
    # the automatic time step (engines.model.start; dt = "auto") and its factor (where it is validated:
    # engines.studies.tradeoffs.VALIDATED_ON)
    "dt_auto_factor": Field(float, DT_AUTO_FACTOR, (0.0, 1.0), "dt = \"auto\": this fraction (> 0) of the smallest stability limit at the start (eq 52, side-wall ties, water stiffness, Darcy 2/lambda_max): the default is the study's fast setting (docs/TRADEOFFS.md)"),
}
OUTPUT_FIELDS = {
    "history_interval": Field(int, 100, (1, math.inf), "steps between history rows"),
    "snapshot_times": Field(list, [0.02, 0.04, 0.06], None, "times of the snapshot figures [s]"),
    "block_z": Field(list, [[0.0, 0.34], [0.66, 10.0]], None, "pressure blocks as [z0, z1] fractions of the initial bed height above the bottom wall (block1 bottom, block2 surface)"),
    "progress_seconds": Field(float, 10.0, POS, "wall seconds between progress lines"),
    "n_bands": Field(int, 8, (1, 64), "horizontal bands of equal height from the bottom wall to the bed's top for the effective stress and r_u (history.csv's *_band<k>, band 1 at the bottom; SPEC §2.8): each band at least a grain tall to hold both its contacts and its pores"),
    "porosity_window": Field(list, [0.0, 0.8], None, "[z0, z1] fractions of the initial bed height above the bottom wall; x between the side walls' inner faces: porosity = void fraction of this rectangle from exact disc-rectangle areas (engines.model.observe)"),
    # ParaView, checkpoints, headline results
    "vtk": Field(bool, False, None, "write a ParaView time series to DIR/vtk/ during the run (postproc.vtk: discs, contact forces, pores)"),
    "vtk_interval": Field(int, 0, (0, math.inf), "steps between VTK frames; 0: at the snapshot_times"),
    "checkpoint_seconds": Field(float, 600.0, POS, "wall seconds between checkpoints during a run (one is also written at the start, at the end and on an interrupt)"),
    "heave_rise": Field(float, 0.45e-3, POS, "rise of the bed top (highest particle top) above its initial height that marks the heave time in summary.json [m]"),
}


def _table(name, fields, table, doc):
    return settings_class(name, fields, table, __name__, doc)


Walls = _table("Walls", WALLS_FIELDS, "walls", "[walls]: what bounds the box (wall discs or flat walls).")
Material = _table("Material", MATERIAL_FIELDS, "material", "[material]: densities [kg/m^3] and gravity [m/s^2].")
Contact = _table("Contact", CONTACT_TABLE, "contact",
                 "[contact]: the contact law's constants, the law, the side-wall ties.")
Water = _table("Water", WATER_TABLE, "water", "[water]: the water's constants, on or off, the link range, sub-steps.")
Loading = _table("Loading", LOADING_FIELDS, "loading", "[loading]: the ground motion and the side walls.")
Numerics = _table("Numerics", NUMERICS_FIELDS, "numerics",
                  "[numerics]: time step, duration, rebuild and water intervals.")
Output = _table("Output", OUTPUT_FIELDS, "output",
                "[output]: history, snapshots, blocks, porosity window, VTK, checkpoints.")
TABLES = {"walls": Walls, "material": Material, "contact": Contact, "water": Water, "loading": Loading,
          "numerics": Numerics, "output": Output}  # in the scene file's order


@dataclasses.dataclass(frozen=True)
class Settings:
    """The model's settings of one run, a typed dataclass per table (TABLES); made by the scene
    (engines.run.scene.Scene.settings) or by ``Settings.of``."""

    walls: Walls
    material: Material
    contact: Contact
    water: Water
    loading: Loading
    numerics: Numerics
    output: Output

    @classmethod
    def of(cls, **tables):
        """Settings from {table: {field: value}} (checked; missing tables and fields: the defaults)."""
        return cls(**{name: table(**tables.get(name, {})) for name, table in TABLES.items()})

    def contact_settings(self):
        """The ContactSettings of [contact] (checked with it)."""
        return checked(ContactSettings, {k: getattr(self.contact, k) for k in CONTACT_FIELDS})

    def water_settings(self):
        """The WaterSettings of [water] (checked with it), or None for a dry scene."""
        w = self.water
        return checked(WaterSettings, {k: getattr(w, k) for k in WATER_FIELDS}) if w.enabled else None

    def with_dt(self, dt):
        """These settings with [numerics] dt = dt [s] (a number > 0)."""
        return dataclasses.replace(self, numerics=dataclasses.replace(self.numerics, dt=dt))
