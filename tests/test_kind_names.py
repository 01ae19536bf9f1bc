"""No code outside a design kind's class compares a design kind's name: a kind's behaviour is a method or an
attribute of its class (uqflight/designs), so that a new kind is one class."""
import re

from conftest import ROOT
from uqflight.designs import DESIGN_KINDS
from uqflight.methods import METHODS

QUOTED = "|".join(DESIGN_KINDS)
# a quoted kind name on either side of ==, !=, `in` or `not in` (a tuple, list or set of names included)
COMPARED = re.compile(rf"""(?:==|!=|\bin)\s*[(\[{{]?[^#\n]*?["']({QUOTED})["']|["']({QUOTED})["']\s*(?:==|!=|\bin\b)""")


def comparisons(text: str) -> list[str]:
    """The lines of `text` that compare a design kind's name (one that is also a method kind's only where the
    line speaks of a design)."""
    found = []
    for line in text.splitlines():
        for match in COMPARED.finditer(line):
            name = match.group(1) or match.group(2)
            if name not in METHODS or "design" in line:
                found.append(line.strip())
    return found


def test_the_pattern_finds_a_comparison():
    assert comparisons('    if kind == "pick_freeze" and n:') == ['if kind == "pick_freeze" and n:']
    assert comparisons('qmc = reference.design_kind != "monte_carlo"')
    assert comparisons('if spec.get("kind") in ("subset_simulation", "active_learning"):')
    assert not comparisons('if out.method["kind"] in ("monte_carlo", "integration"):')  # a method kind
    assert not comparisons('example = {"kind": "morris", "trajectories": 4}')


def test_no_design_kind_name_is_compared_outside_the_designs():
    package = ROOT / "uqflight"
    found = {str(path.relative_to(ROOT)): hits for path in sorted(package.rglob("*.py"))
             if package / "designs" not in path.parents and (hits := comparisons(path.read_text()))}
    assert found == {}
