"""A refusal of the user's input is one exception type, `uqflight.text.Refusal`, whose message is the whole
line the user sees; the command line turns it into "error: MESSAGE" and exit 2 in one place
(`uqflight.cli.arguments.RefusingGroup`), for every command and sub-command."""
import ast
from pathlib import Path

import pytest
from conftest import NORMAL_2D, cli, cli_in_process, closed_form_campaign

PACKAGE = Path(__file__).resolve().parents[1] / "uqflight"
COMMAND_MODULES = ("cli/commands.py", "calibration/command.py", "cli/arguments.py")
# the explicit translations at the commands' boundary, where a generic library error (h5py's OSError,
# JSBSim's RuntimeError, a worker's failure) becomes a Refusal with the command's own context:
# simulate, plan, run (2), info (2), report, design, surrogate export, aircraft; calibrate (2, a worker's
# failure and the --method/--order parse); and the option a --scale/--offset function came from (simulate,
# aircraft: one place, _prepared)
TRANSLATIONS = {"cli/commands.py": 11, "calibration/command.py": 2, "cli/arguments.py": 0}


def calls_of(name: str) -> list[tuple[str, str]]:
    """(module, enclosing function) of every call of `name` in the package."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for scope in ast.walk(tree):
            if isinstance(scope, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for node in ast.walk(scope):
                    if isinstance(node, ast.Call) and getattr(node.func, "id", None) == name:
                        found.append((str(path.relative_to(PACKAGE)), scope.name))
    return found


def translations(module: str) -> int:
    """The `raise Refusal(...)` statements inside an except clause of `module`."""
    tree = ast.parse((PACKAGE / module).read_text(encoding="utf-8"))
    return sum(isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call)
               and getattr(node.exc.func, "id", None) == "Refusal"
               for handler in ast.walk(tree) if isinstance(handler, ast.ExceptHandler)
               for node in ast.walk(handler))


def test_a_refusal_becomes_exit_2_in_one_place():
    assert calls_of("refuse") == [("cli/arguments.py", "invoke")]


@pytest.mark.parametrize("module", COMMAND_MODULES)
def test_the_commands_translate_only_generic_errors_into_refusals(module):
    assert translations(module) == TRANSLATIONS[module]


def bad_field_campaign(folder: Path) -> Path:
    path = folder / "c.yaml"
    path.write_text(closed_form_campaign("c", "sum_of_squares", NORMAL_2D, "{kind: tensor_grid, points: 4}",
                                         "method: {kind: pseudo_galerkin, order: -1}\n"), encoding="utf-8")
    return path


def one_line_refusal(done) -> str:
    assert done.returncode == 2, done.stderr[-2000:]
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in done.stderr, done.stderr
    return lines[0]


def test_a_campaign_refused_deep_in_the_library_exits_2_naming_file_and_field(tmp_path):
    path = bad_field_campaign(tmp_path)
    line = one_line_refusal(cli_in_process("plan", path))
    assert line.startswith(f"error: {path}: method.order: ")


def test_the_console_script_refuses_as_the_app_does(tmp_path):
    path = bad_field_campaign(tmp_path)
    assert one_line_refusal(cli("plan", path)) == one_line_refusal(cli_in_process("plan", path))


@pytest.mark.parametrize("command", [("report", "RESULTS"), ("surrogate", "export", "RESULTS", "--out", "pce.json"),
                                     ("calibrate", "RESULTS", "--data", "flight.csv", "--out", "cal")])
def test_a_file_that_is_not_hdf5_is_refused_by_every_command_reading_results(tmp_path, command):
    notes = tmp_path / "notes.txt"
    notes.write_text("not a results file\n", encoding="utf-8")
    args = [notes if arg == "RESULTS" else arg for arg in command]
    line = one_line_refusal(cli_in_process(*args, cwd=tmp_path))
    assert line == f"error: {notes} is not a results file (a results file is HDF5, written by `uqflight run`)"
