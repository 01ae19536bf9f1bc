"""A method kind's behaviour lives on its class (uqflight.methods): no module outside uqflight/methods/
compares a value with a method kind's name (`== "sparse"`, `in ("monte_carlo", ...)`, ...)."""
import ast
from pathlib import Path

from uqflight.methods import METHOD_KINDS

PACKAGE = Path(__file__).resolve().parents[1] / "uqflight"


def _names(node) -> set[str]:
    """The string constants a comparison operand is made of (a constant, or a tuple, list or set of them)."""
    items = node.elts if isinstance(node, (ast.Tuple, ast.List, ast.Set)) else [node]
    return {item.value for item in items if isinstance(item, ast.Constant) and isinstance(item.value, str)}


def comparisons_with_method_kinds(source: str) -> list[tuple[int, str]]:
    """(line, text) of each comparison of `source` with a method kind's name; one whose other side names a
    design (`design_kind != "monte_carlo"`: the design kind of that name) is the designs' concern."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Compare):
            continue
        operands = [node.left, *node.comparators]
        named = set().union(*(_names(operand) for operand in operands)) & set(METHOD_KINDS)
        if not named:  # get_source_segment reads the source anew: only for the comparisons that name a kind
            continue
        others = " ".join(ast.get_source_segment(source, o) or "" for o in operands if not _names(o))
        if not ("monte_carlo" in named and len(named) == 1 and "design" in others):
            found.append((node.lineno, ast.get_source_segment(source, node) or ""))
    return found


def test_no_module_outside_methods_compares_a_method_kind_name():
    found = [f"{path.relative_to(PACKAGE.parent)}:{line}: {text}"
             for path in sorted(PACKAGE.rglob("*.py")) if "methods" not in path.relative_to(PACKAGE).parts[:1]
             for line, text in comparisons_with_method_kinds(path.read_text())]
    assert found == []


def test_the_check_finds_the_comparisons_it_is_for():
    source = ('if method["kind"] == "auto": pass\nif kind in ("monte_carlo", "integration"): pass\n'
              'if "sparse" != kind: pass\nif design_kind != "monte_carlo": pass\nx = {"kind": "sparse"}\n')
    assert [line for line, _ in comparisons_with_method_kinds(source)] == [1, 2, 3]


def test_the_method_class_example_runs():
    import doctest

    import uqflight.methods.kind

    result = doctest.testmod(uqflight.methods.kind)
    assert result.attempted >= 4 and result.failed == 0


def test_every_method_kind_class_has_an_example_and_the_examples_run():
    import doctest
    import importlib

    from uqflight.methods import METHODS

    classes = {kind: type(method) for kind, method in METHODS.items()}  # METHODS holds one instance per kind
    results = {name: doctest.testmod(importlib.import_module(name))
               for name in sorted({cls.__module__ for cls in classes.values()})}
    assert {name: result for name, result in results.items() if result.failed or not result.attempted} == {}
    assert [kind for kind, cls in classes.items() if ">>>" not in (cls.__doc__ or "")] == []
