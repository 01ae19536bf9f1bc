"""A simulator or scenario kind's behaviour is a method of its class: no module compares a string with a
kind's name but the module that defines that kind's class; and each kind class's Examples run."""
import ast
import doctest
import importlib
import inspect
from pathlib import Path

import pytest

from uqflight.simulators.kinds import REGISTRY as SIMULATORS
from uqflight.simulators.scenarios import REGISTRY as SCENARIOS

PACKAGE = Path(__file__).resolve().parents[1] / "uqflight"
KINDS = {**SIMULATORS, **SCENARIOS}
HOME = {name: Path(inspect.getfile(type(entry))).resolve() for name, entry in KINDS.items()}


def _strings(node) -> set[str]:
    """The string constants a comparison's operand is or lists (`x in ("a", "b")`)."""
    items = node.elts if isinstance(node, (ast.Tuple, ast.List, ast.Set)) else [node]
    return {item.value for item in items if isinstance(item, ast.Constant) and isinstance(item.value, str)}


def kind_name_comparisons(path: Path) -> list[str]:
    """'line: name' for every comparison in `path` with a kind's name outside that kind's own module."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Compare):
            for operand in (node.left, *node.comparators):
                found += [f"{node.lineno}: {name}" for name in _strings(operand) & set(KINDS) if HOME[name] != path]
    return found


@pytest.mark.parametrize("path", sorted(PACKAGE.rglob("*.py")), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_module_compares_a_string_with_a_kind_name_outside_its_class(path):
    assert not kind_name_comparisons(path.resolve())


def test_the_check_finds_a_comparison_with_a_kind_name(tmp_path):
    # the check itself can fail: a comparison written the way the switches were is found
    module = tmp_path / "switch.py"
    module.write_text('def f(sim, kind):\n    return sim["kind"] == "jsbsim" or kind in ("script", "x")\n')
    assert kind_name_comparisons(module) == ["2: jsbsim", "2: script"]


@pytest.mark.parametrize("module", ["uqflight.simulators.base", *sorted({type(e).__module__ for e in KINDS.values()})])
def test_the_kind_classes_examples_run(module):
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    assert result.attempted >= 1 and result.failed == 0
