"""Scene files: presets load, extends merges, bad files are refused naming the field."""
import os

import numpy as np
import pytest

from engines.compiled.pore_dem import PoreDEM
from engines.run import scene as scenes
from packing.packing import Packing


def test_presets_load_and_case2_differs_only_in_permeability():
    c1, c2 = scenes.preset("quicksand_case1"), scenes.preset("quicksand_case2")
    assert (c1.water.k1, c1.water.k2) == (200.0, 2.0) and (c2.water.k1, c2.water.k2) == (2000.0, 200.0)
    d1, d2 = c1.as_dict(), c2.as_dict()
    diffs = {(t, k) for t in d1 for k in d1[t] if d1[t][k] != d2[t][k]}
    assert diffs == {("scene", "name"), ("water", "k1"), ("water", "k2")}
    assert c1.contact_settings().spring == "c" and c1.water_settings().E_w == 240.0


def _write(tmp_path, text):
    p = tmp_path / "s.toml"
    p.write_text(text)
    return str(p)


@pytest.mark.parametrize("text,field", [
    ('[scene]\nname = "x"\n[water]\nk1 = -1.0\n', r"\[water\] k1"),
    ('[scene]\nname = "x"\n[water]\nE_w = 0\n', r"\[water\] E_w"),
    ('[scene]\nname = "x"\n[contact]\nspring = "z"\n', r"\[contact\] spring"),
    ('[scene]\nname = "x"\n[contact]\nkn = "big"\n', r"\[contact\] kn"),
    ('[scene]\nname = "x"\n[water]\npermeability = 3.0\n', r"\[water\] unknown field"),
    ('[scene]\nname = "x"\n[wather]\n', "unknown table"),
    ('[packing]\nn_particles = 3\n', r"\[scene\] name"),
    ('[scene]\nname = "x"\n[output]\nblock_z = [[0.5, 0.1]]\n', "block_z"),
    ('[scene]\nname = x\n', "not valid TOML"),
    ('[scene]\nname = "x"\n[walls]\nkind = "boxes"\n', r"\[walls\] kind"),
])
def test_bad_scene_files_name_the_field(tmp_path, text, field):
    with pytest.raises(scenes.SceneError, match=field):
        scenes.load(_write(tmp_path, text))


def test_extends_and_overrides(tmp_path):
    base = tmp_path / "base.toml"
    base.write_text('[scene]\nname = "base"\n[water]\nk1 = 10.0\nk2 = 1.0\n')
    child = tmp_path / "child.toml"
    child.write_text('extends = "base.toml"\n[water]\nk2 = 0.5\n')
    sc = scenes.load(str(child), {"numerics": {"dt": 2e-7}})
    assert (sc.scene.name, sc.water.k1, sc.water.k2, sc.numerics.dt) == ("base", 10.0, 0.5, 2e-7)


def test_dt_above_the_stability_limit_is_refused():
    sc = scenes.preset("quicksand_case1", {"numerics": {"dt": 1e-4}})
    pk = Packing(np.array([[0.0, 1e-3], [0.0, 0.0]]), np.array([0.5e-3, 0.5e-3]), [0, 1], [1.0, 1.0])
    with pytest.raises(ValueError, match=r"\[numerics\] dt .* stability limit"):
        PoreDEM(sc.settings, pk)


def test_paths_resolve_against_the_file_that_names_them(tmp_path):
    """A scene elsewhere extending a preset inherits the preset's packing (beside the preset);
    its own relative paths resolve against its own folder."""
    preset = os.path.join(scenes.SCENE_DIR, "quicksand_case1.toml")
    mine = tmp_path / "sub" / "mine.toml"
    mine.parent.mkdir()
    mine.write_text(f'extends = "{os.path.relpath(preset, mine.parent)}"\n[scene]\nname = "mine"\n')
    sc = scenes.load(str(mine))
    assert sc.packing.file == os.path.join(scenes.SCENE_DIR, "quicksand_packing.csv")
    assert os.path.exists(sc.packing.file) and sc.water.k1 == 200.0
    child = tmp_path / "child.toml"
    child.write_text('extends = "sub/mine.toml"\n[loading]\ntype = "record"\nrecord = "rec.txt"\n')
    sc = scenes.load(str(child))
    assert sc.loading.record == str(tmp_path / "rec.txt")
    assert sc.packing.file == os.path.join(scenes.SCENE_DIR, "quicksand_packing.csv")


def test_a_preset_name_stands_for_its_file_in_load_and_extends(tmp_path):
    """--scene and extends take a preset's name (engines.run.scene.resolve) as well as a path."""
    assert scenes.load("quicksand_case2").as_dict() == scenes.preset("quicksand_case2").as_dict()
    mine = tmp_path / "mine.toml"
    mine.write_text('extends = "quicksand_case2"\n[water]\nk2 = 0.5\n')
    sc = scenes.load(str(mine))
    assert sc.water.k2 == 0.5 and sc.water.k1 == scenes.preset("quicksand_case2").water.k1
    assert sc.packing.file == os.path.join(scenes.SCENE_DIR, "quicksand_packing.csv")
    with pytest.raises(scenes.SceneError, match=r"scene 'quicksand_case9': no preset of that name \(presets: .*quicksand_case1"):
        scenes.load("quicksand_case9")
    mine.write_text('extends = "nosuch"\n')
    with pytest.raises(scenes.SceneError, match=r"mine.toml: extends: scene 'nosuch': no preset"):
        scenes.load(str(mine))


def test_extends_loops_and_bad_extends_are_refused(tmp_path):
    (tmp_path / "a.toml").write_text('extends = "b.toml"\n[scene]\nname = "a"\n')
    (tmp_path / "b.toml").write_text('extends = "a.toml"\n')
    with pytest.raises(scenes.SceneError, match="extends: a loop"):
        scenes.load(str(tmp_path / "a.toml"))
    (tmp_path / "c.toml").write_text('extends = 3\n')
    with pytest.raises(scenes.SceneError, match="extends: expected a scene file name"):
        scenes.load(str(tmp_path / "c.toml"))


def test_overrides_are_recorded():
    sc = scenes.preset("quicksand_case1", {"numerics": {"duration": 0.02}})
    assert sc.overrides == {"numerics": {"duration": 0.02}} and sc.numerics.duration == 0.02
    sc2 = sc.with_overrides({"water": {"k1": 20.0}})
    assert sc2.overrides == {"numerics": {"duration": 0.02}, "water": {"k1": 20.0}}
    assert scenes.preset("quicksand_case1").overrides == {}


def test_a_script_and_a_scene_file_get_the_same_settings_and_refusals():
    """WaterSettings and ContactSettings built in a YADE script equal those of a scene file with the
    same fields, and refuse a bad value with the scene file's message ("[water] k1: ...")."""
    from engines.model.contact import ContactSettings
    from engines.model.pore_water import WaterSettings
    plain = scenes.validate({"scene": {"name": "x"}})
    assert plain.water_settings() == WaterSettings() and plain.contact_settings() == ContactSettings()
    for table, cls, name, bad in (("water", WaterSettings, "k1", -1.0), ("water", WaterSettings, "sides", "open"),
                                  ("contact", ContactSettings, "restitution", 1.5), ("contact", ContactSettings, "kn", 0)):
        with pytest.raises(scenes.SceneError) as from_file:
            scenes.validate({"scene": {"name": "x"}, table: {name: bad}})
        with pytest.raises(ValueError) as from_script:
            cls(**{name: bad})
        assert str(from_script.value) == str(from_file.value) and str(from_file.value).startswith(f"[{table}] {name}:")
    assert WaterSettings(k1=np.float32(3.0)).k1 == 3.0 and type(WaterSettings(k1=3).k1) is float


def test_the_scene_readme_table_is_the_schema():
    """yade_scripts/scenes/README.md shows the schema as engines.run.scene prints it (regenerate it with
    `PYTHONPATH=. /usr/bin/python3 -m engines.run.scene` after a change of the schema)."""
    with open(os.path.join(scenes.SCENE_DIR, "README.md"), encoding="utf-8") as f:
        rows = [line.rstrip("\n") for line in f if line.startswith("|")]
    assert rows == scenes.schema_markdown().splitlines()


def test_walls_are_discs_unless_flat_is_asked_for():
    assert scenes.preset("quicksand_case1").walls.kind == "discs"
    flat = scenes.preset("quicksand_case1", {"walls": {"kind": "flat"}, "contact": {"law": "yade", "spring": "b"}})
    assert flat.walls.kind == "flat"


def test_flat_walls_follow_a_loading_but_are_not_on_springs():
    shaken = scenes.preset("quicksand_case1", {"walls": {"kind": "flat"}, "loading": {"type": "cosine"}})
    assert shaken.walls.kind == "flat" and shaken.loading.type == "cosine"
    with pytest.raises(scenes.SceneError, match=r"^\[walls\] kind = 'flat': \[loading\] side_walls = 'springs' ties "
                                                r"side-wall discs") as e:
        scenes.preset("liquefaction_case1", {"walls": {"kind": "flat"}})
    assert "\n" not in str(e.value)
    assert scenes.preset("quicksand_case1", {"walls": {"kind": "flat"}}).walls.kind == "flat"  # the paper's law too


def test_every_preset_states_the_papers_transfer():
    """The presets keep the paper's re-meshing (the cross-check's reference), whatever the field's
    default: each base preset states transfer = "paper", the others extend one."""
    names = sorted(f[:-5] for f in os.listdir(scenes.SCENE_DIR) if f.endswith(".toml"))
    assert len(names) >= 10
    for name in names:
        assert scenes.preset(name).water.transfer == "paper", name
        raw = open(os.path.join(scenes.SCENE_DIR, name + ".toml")).read()
        assert "extends = " in raw or 'transfer = "paper"' in raw, name
