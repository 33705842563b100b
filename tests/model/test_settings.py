"""The model's typed settings (engines.model.settings): one declaration of each table's fields, which
the scene schema takes; each value of a scene checked once, as its table is made."""
import pytest

from engines.model import fields
from engines.model.settings import TABLES, Settings
from engines.run import scene as scenes


def test_the_schema_takes_the_settings_fields_and_defaults():
    for table, cls in TABLES.items():
        assert scenes.SCHEMA[table] is cls.FIELDS
    plain = scenes.validate({"scene": {"name": "plain"}})
    assert plain.settings == Settings.of()
    assert plain.settings.contact_settings() == Settings.of().contact_settings()
    assert plain.settings.output.snapshot_times is not Settings.of().output.snapshot_times  # a list per instance


def test_each_value_of_a_scene_is_checked_once(monkeypatch):
    seen = []
    check = fields.check
    counted = lambda where, *a, **k: seen.append(where) or check(where, *a, **k)  # noqa: E731
    monkeypatch.setattr(fields, "check", counted)
    monkeypatch.setattr(scenes, "check", counted)
    sc = scenes.preset("quicksand_case1", {"water": {"E_w": 300.0}})
    sc.settings.water_settings(), sc.settings.contact_settings()
    assert seen.count("[water] E_w") == 1 and seen.count("[numerics] dt") == 1
    assert sc.settings.water.E_w == sc.water_settings().E_w == 300.0


def test_a_bad_value_is_refused_naming_the_field():
    with pytest.raises(scenes.SceneError, match=r"\[water\] E_w: must be > 0"):
        scenes.preset("quicksand_case1", {"water": {"E_w": -1.0}})
    with pytest.raises(ValueError, match=r"\[numerics\] dt: must be > 0"):
        Settings.of().with_dt(0.0)
