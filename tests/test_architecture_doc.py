"""docs/architecture.md names every module of the package, one row each, and nothing else: its table's
first column against `uqflight/**/*.py` on disk."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ROW = re.compile(r"^\| `(uqflight/[^`]+\.py)` \| (.+) \|$")


def documented() -> list[str]:
    """The modules the table of docs/architecture.md names, in its order."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    return [m.group(1) for line in text.splitlines() if (m := ROW.match(line)) and m.group(2).strip()]


def test_the_architecture_page_names_every_module_once_and_no_other():
    named = documented()
    on_disk = {path.relative_to(ROOT).as_posix() for path in (ROOT / "uqflight").rglob("*.py")}
    assert sorted(on_disk - set(named)) == [], "modules missing from docs/architecture.md"
    assert sorted(set(named) - on_disk) == [], "docs/architecture.md names modules that do not exist"
    assert len(named) == len(set(named)), "a module named twice in docs/architecture.md"

