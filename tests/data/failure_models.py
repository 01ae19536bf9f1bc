"""Closed-form models that fail on a known share of their input box, for the failure-probability and
failed-run tests."""
import math

# x1, x2 ~ U(-1, 1): x1 + x2 > C is a corner triangle with legs 2 − C = √1.04, of area 0.52 of the
# box's 4: P(fail) = 0.13 exactly.
C = 2.0 - math.sqrt(1.04)
P_FAIL = 0.13


def corner_13(p):
    """y = 1 + x1 + x2 (mean 1 over the box), failing where x1 + x2 > C: on 13 % of the box."""
    x1, x2 = p["x1"], p["x2"]
    if x1 + x2 > C:
        raise ValueError("x1 + x2 above the corner's edge")
    return {"y": 1.0 + x1 + x2}


def corner_campaign(name: str, design: str, method: str = "least_squares", order: int = 1) -> str:
    """The campaign text that runs corner_13 on U(-1, 1)² with `design` (a YAML flow mapping)."""
    return (f"name: {name}\nseed: 5\nsimulator: {{kind: python, function: \"{__file__}:corner_13\"}}\n"
            "parameters:\n  x1: {distribution: uniform, lower: -1, upper: 1}\n"
            "  x2: {distribution: uniform, lower: -1, upper: 1}\n"
            f"design: {design}\nmethod: {{kind: {method}, order: {order}}}\n"
            "analysis: {band_samples: 2000, bootstrap: 0}\n")


def fails_at_centre(p):
    """y = a, failing only at a = 1.5: the nominal sample of a ~ U(1, 2)."""
    if p["a"] == 1.5:
        raise RuntimeError("centre node")
    return {"y": p["a"]}
