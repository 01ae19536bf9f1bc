"""The import graph runs one way, down the data flow: no module imports a layer above its own (lazy
imports inside functions included), and a worker imports only what flying needs."""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "uqflight"

# Lowest first; a module may import its own layer and those below. Longest prefix wins.
LAYERS = [
    ("uqflight.text", "uqflight.store.tsvd", "uqflight.simulators.base",
     "uqflight.parameters.germs", "uqflight.running.progress", "uqflight.running.forking", "uqflight.running.stopping",
     "uqflight.cli.fast_exit", "uqflight.cli.arguments"),
    ("uqflight.parameters", "uqflight.analysis", "uqflight.simulators", "uqflight.quantities"),
    ("uqflight.designs",),
    ("uqflight.methods",),
    ("uqflight.store", "uqflight.running.worker"),
    ("uqflight.campaign", "uqflight.analysis.statistics", "uqflight.analysis.rare_statistics"),
    ("uqflight.running", "uqflight.analysis.check", "uqflight.analysis.surrogate", "uqflight.calibration"),
    ("uqflight.report",),
    ("uqflight.cli",),
]


def layer(module: str) -> int:
    if module == "uqflight":  # the package's own __init__: the Python API beside the CLI (lazy imports)
        return len(LAYERS) - 1
    matches = [(len(prefix), i) for i, prefixes in enumerate(LAYERS) for prefix in prefixes
               if module == prefix or module.startswith(prefix + ".")]
    assert matches, f"{module} has no layer: add it to LAYERS"
    return max(matches)[1]


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, lazy: bool = True) -> set[str]:
    """The uqflight modules a file imports, anywhere in it (relative imports resolved; `from P import M`
    names P.M when M is a module, else P), or at module level alone when not `lazy`."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree) if lazy else _module_level(tree.body):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names if alias.name.startswith("uqflight")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("uqflight"):
                modules = {f"{target}.{alias.name}" for alias in node.names} & NAMES
                found |= modules if len(modules) == len(node.names) else modules | {target}
    return found


def _module_level(body):
    """The statements a module runs when imported: its body, into if/try blocks, not into functions or classes."""
    for node in body:
        yield node
        if isinstance(node, (ast.If, ast.Try)):
            yield from _module_level(node.body + node.orelse + getattr(node, "finalbody", [])
                                     + [s for handler in getattr(node, "handlers", []) for s in handler.body])


MODULES = sorted(PACKAGE.rglob("*.py"))
NAMES = {module_name(path) for path in MODULES}


@pytest.mark.parametrize("path", MODULES, ids=lambda p: module_name(p))
def test_no_module_imports_a_layer_above_its_own(path):
    own = layer(module_name(path))
    upward = sorted(target for target in imports(path) if layer(target) > own)
    assert not upward, f"{module_name(path)} (layer {own}) imports {upward}"


def test_a_worker_imports_only_what_flying_needs():
    code = ("import sys, uqflight.running.worker; print(' '.join(sorted(m for m in sys.modules "
            "if m.startswith(('uqflight', 'scipy', 'h5py', 'yaml', 'matplotlib', 'dask')))))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    # the quantities' recorder is part of flying: it sees every integration step; forking (the standard
    # library only) makes it die with its runner; labels (no imports) gives the unit a property's name ends
    # in, which tells the recorder an angle to unwrap; console (typer only when it prints) quotes a refused
    # file's names; bounded (the standard library only) reads a python model's file within its size; the
    # packages running and text are their docstrings alone
    assert all(m.startswith(("uqflight.simulators", "uqflight.running.worker", "uqflight.quantities"))
               or m in ("uqflight", "uqflight.running", "uqflight.running.forking", "uqflight.text", "uqflight.text.labels",
                        "uqflight.text.console", "uqflight.text.bounded")
               for m in loaded), loaded


# what the report may import beside its own modules: the analysis's result types and functions, text and labels,
# and the process plumbing its drawing children and progress use; no design, method, simulator, campaign or
# store module (what it needs of those comes with the analysis result: Statistics and its CampaignRecord)
REPORT_MAY_IMPORT = ("uqflight.analysis", "uqflight.text", "uqflight.running.forking", "uqflight.running.progress")


def test_the_report_imports_only_the_analysis_text_and_process_plumbing():
    report = [path for path in MODULES if module_name(path).startswith("uqflight.report")]
    assert len(report) > 10
    found = {module_name(path): sorted(target for target in imports(path) if not target.startswith("uqflight.report")
                                       and not any(target == allowed or target.startswith(allowed + ".")
                                                   for allowed in REPORT_MAY_IMPORT))
             for path in report}
    assert {name: targets for name, targets in found.items() if targets} == {}


def import_cycles(lazy: bool) -> list[set[str]]:
    """The strongly connected sets of two or more uqflight modules in the import graph (Tarjan)."""
    graph = {module_name(path): imports(path, lazy) & NAMES - {module_name(path)} for path in MODULES}
    index, low, stack, cycles = {}, {}, [], []

    def visit(module):
        index[module] = low[module] = len(index)
        stack.append(module)
        for target in sorted(graph[module]):
            if target not in index:
                visit(target)
                low[module] = min(low[module], low[target])
            elif target in stack:
                low[module] = min(low[module], index[target])
        if low[module] == index[module]:
            members = {stack.pop()}
            while module not in members:
                members.add(stack.pop())
            if len(members) > 1:
                cycles.append(members)

    for module in sorted(graph):
        if module not in index:
            visit(module)
    return cycles


# circles that other steps of the restructure (issue 43) take apart; no other may appear
KNOWN_CYCLES = [{"uqflight.methods", "uqflight.methods.validation", "uqflight.methods.validity"},
                {"uqflight.analysis.rare_statistics", "uqflight.analysis.statistics"}]


def test_no_import_cycles_among_module_level_imports():
    assert import_cycles(lazy=False) == []


def test_no_import_cycle_through_lazy_imports_either():
    # simulators/jsbsim.py ↔ scenarios/, simulators/bundle.py ↔ simulators/kinds/, report/sections.py ↔
    # report/trajectories.py were such circles
    assert [cycle for cycle in import_cycles(lazy=True) if cycle not in KNOWN_CYCLES] == []


def test_the_cycle_finder_finds_a_cycle(monkeypatch):
    # a lazy import of report.sections from report.trajectories (the circle that was) is found
    real = imports
    monkeypatch.setattr(sys.modules[__name__], "imports", lambda path, lazy=True: real(path, lazy) | (
        {"uqflight.report.sections"} if module_name(path) == "uqflight.report.trajectories" else set()))
    assert {"uqflight.report.sections", "uqflight.report.trajectories"} in import_cycles(lazy=True)
