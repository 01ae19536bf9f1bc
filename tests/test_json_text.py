"""uqflight.text.json_text: the same JSON values as json.dumps, laid out for reading, strict."""
import json
import math

import numpy as np
import pytest

from uqflight.text.json_text import json_text

VALUE = {"name": "pg2", "empty": {}, "none": [], "flag": True, "missing": None, "count": 113,
         "floats": [0.1, 1e-300, -2.5e17, 1 / 3, 5e-324, 15000.000000000002],
         "nested": {"pdf": [[0.0, 0.5], [0.25, 1.0]], "runs": [{"run": 3, "reason": "trim failed: \"wdot\"\n"}]},
         "unicode": "σ₁ [ft²] − mean", 7: "key made a string"}


def test_json_text_holds_json_dumps_values_with_every_float_as_its_repr():
    text = json_text(VALUE)
    assert json.loads(text) == json.loads(json.dumps(VALUE))
    assert text.endswith("}\n")
    floats = json.loads(text)["floats"]
    assert [f.hex() for f in floats] == [f.hex() for f in VALUE["floats"]]  # to the bit


def test_json_text_puts_each_member_on_its_line_and_each_flat_list_on_one():
    lines = json_text({"a": [1.5, 2.5], "b": {"c": "x"}}).splitlines()
    assert lines == ["{", ' "a": [1.5, 2.5],', ' "b": {', '  "c": "x"', " }", "}"]


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_json_text_refuses_nan_and_infinity_as_json_does(bad):
    for value in ({"x": [1.0, bad]}, {"x": {"y": bad}}, [bad]):
        with pytest.raises(ValueError):
            json_text(value)


def test_json_text_refuses_what_json_cannot_write():
    with pytest.raises(TypeError):
        json_text({"x": np.float32(1.0)})
