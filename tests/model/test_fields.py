"""engines.model.fields: the one check of a settings value (types, bounds, choices, "auto"), and
check_each; the messages name the field as a scene file does."""
import math

import numpy as np
import pytest

from engines.model.fields import COUNT, NONNEG, POS, POS_OR_AUTO, POSITIVE, Field, check, check_each, describe_check


def test_numbers_are_converted_to_the_fields_type():
    f = Field(float, 1.0, NONNEG, "")
    assert check("x", 3, f) == 3.0 and type(check("x", 3, f)) is float
    assert type(check("x", np.float32(2.5), f)) is float and check("x", np.float32(2.5), f) == 2.5
    n = Field(int, 1, (1, math.inf), "")
    assert check("n", np.int64(4), n) == 4 and type(check("n", np.int64(4), n)) is int
    for bad, field in ((2.5, n), (True, n), (True, f), ("3", f), (3, Field(str, "", None, "")), (1, Field(bool, False, None, ""))):
        with pytest.raises(ValueError, match=r"^x: expected (float|int|str|bool), got "):
            check("x", bad, field)


def test_bounds_and_choices_are_named_in_the_message():
    with pytest.raises(ValueError, match=r"^\[water\] k1: must be in \[0\.0, inf\], got -1\.0$"):
        check("[water] k1", -1.0, Field(float, 0.0, NONNEG, ""))
    with pytest.raises(ValueError, match=r"^\[water\] E_w: must be > 0, got 0\.0$"):
        check("[water] E_w", 0.0, Field(float, 1.0, POS, ""))
    assert check("e", 1e-300, Field(float, 1.0, POS, "")) == 1e-300
    assert check("e", 0.0, Field(float, 1.0, NONNEG, "")) == 0.0   # >= 0 allows what > 0 refuses
    with pytest.raises(ValueError, match=r"^x: must be finite, got inf$"):
        check("x", math.inf, Field(float, 1.0, NONNEG, ""))
    with pytest.raises(ValueError, match=r"^\[water\] sides: must be one of undrained, drained, got 'open'$"):
        check("[water] sides", "open", Field(str, "undrained", ("undrained", "drained"), ""))
    assert check("s", "drained", Field(str, "undrained", ("undrained", "drained"), "")) == "drained"


def test_auto_or_a_positive_number():
    f = Field(float, 1e-6, POS_OR_AUTO, "")
    assert check("dt", "auto", f) == "auto"
    assert check("dt", 2e-6, f) == 2e-6
    with pytest.raises(ValueError, match=r'^dt: expected a number > 0 or "auto", got \'AUTO\'$'):
        check("dt", "AUTO", f)
    with pytest.raises(ValueError, match=r"^dt: must be > 0, got 0\.0$"):
        check("dt", 0.0, f)


def test_the_schema_shows_each_check():
    assert describe_check(None) == "" and describe_check(POS) == "> 0" and describe_check(NONNEG) == "[0.0, inf]"
    assert describe_check(POS_OR_AUTO) == "> 0 or 'auto'" and describe_check(("a", "b")) == "a, b"


def test_check_each_names_the_attribute():
    class Settings:
        gtol, maxiter = 1e-5, 0
    check_each(Settings, ("gtol",), POSITIVE)
    with pytest.raises(ValueError, match=r"^maxiter: must be in \[1, inf\], got 0$"):
        check_each(Settings, ("maxiter",), COUNT)
