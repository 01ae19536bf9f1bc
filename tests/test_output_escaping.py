"""Text from files reaches terminals and reports defused: control characters are stripped from
everything the command line prints, report.md escapes Markdown, and the report's CSV tables quote
text cells a spreadsheet would evaluate (numbers stay numbers)."""
import csv

import pytest
from conftest import cli_in_process

from uqflight.text.console import clean, one_line
from uqflight.report.files import csv_safe
from uqflight.report.render import md

TITLE_AND_RETURN = "\x1b]0;pwned\x07"  # sets the terminal's title
REASON = "=HYPERLINK(1)|*bold* _em_ `code` [link](x) <b> #h" + TITLE_AND_RETURN + "\r\x9b2Jgone"
MODEL = f'''
from uqflight.simulators.base import FlightError

def hostile(p):
    if p["x"] > 0.0:
        raise FlightError({REASON!r})  # recorded as it is: the reason starts the CSV cell
    return {{"y": p["x"]}}
'''
CAMPAIGN = """name: hostile
seed: 3
simulator: {kind: python, function: "model.py:hostile"}
parameters:
  x: {distribution: uniform, lower: -1, upper: 1}
design: {kind: monte_carlo, samples: 8}
execution: {workers: 1, chunk: 4}
analysis: {band_samples: 200, bootstrap: 0}
"""


def test_clean_strips_every_control_character_but_tab_and_newline():
    text = "a\tb\n" + "".join(map(chr, range(32))) + "\x7f" + "".join(map(chr, range(0x80, 0xa0))) + "é→"
    assert clean(text) == "a\tb\n\t\né→"


def test_markdown_and_formula_escapes():
    assert md("a|b *c* _d_ `e` [f](g) <h> #i\nj") == r"a\|b \*c\* \_d\_ \`e\` \[f\](g) \<h\> \#i j"
    assert [csv_safe(v) for v in ("=1+1", "+cmd", "-2+3", "@SUM(A1)", "\tx", "\rx", "-0.5", "+1e-3", "x=1")] == \
           ["'=1+1", "'+cmd", "'-2+3", "'@SUM(A1)", "'\tx", "'\rx", "-0.5", "+1e-3", "x=1"]
    assert csv_safe(-1.5) == -1.5 and csv_safe(-3) == -3


@pytest.fixture(scope="module")
def hostile(tmp_path_factory):
    """A campaign whose failed runs give a reason holding terminal escapes, Markdown and a formula."""
    folder = tmp_path_factory.mktemp("hostile")
    (folder / "model.py").write_text(MODEL)
    (folder / "c.yaml").write_text(CAMPAIGN)
    ran = cli_in_process("run", folder / "c.yaml", "--out", folder / "r.h5", cwd=folder)
    assert ran.returncode == 0, ran.stderr
    return folder, ran


def test_run_and_info_print_failure_reasons_without_control_characters(hostile):
    folder, ran = hostile
    info = cli_in_process("info", folder / "r.h5")
    assert info.returncode == 0, info.stderr
    for printed in (ran.stdout, info.stdout):
        assert "failed (" in printed and "gone" in printed, printed
        assert not any(c in printed for c in "\x1b\x07\r\x9b"), repr(printed)
        assert "]0;pwned" + "2Jgone" in printed  # what is left of the sequences is plain text


def test_info_prints_a_failure_reason_holding_a_newline_on_one_line(tmp_path):
    """A reason with a newline was printed over two lines, the second one forged ("outputs: forged")."""
    (tmp_path / "model.py").write_text("def boom(p):\n    if p['x'] > 0.0:\n"
                                       "        raise RuntimeError('boom\\noutputs: forged')\n"
                                       "    return {'y': p['x']}\n")
    (tmp_path / "c.yaml").write_text(CAMPAIGN.replace("model.py:hostile", "model.py:boom"))
    ran = cli_in_process("run", tmp_path / "c.yaml", "--out", tmp_path / "r.h5", cwd=tmp_path)
    assert ran.returncode == 0 and "failed (" in ran.stdout  # run's summary lists the reasons too, one line each
    assert not any(line.startswith("outputs: forged") for line in ran.stdout.splitlines()), ran.stdout
    info = cli_in_process("info", tmp_path / "r.h5")
    assert info.returncode == 0, info.stderr
    failed = [line for line in info.stdout.splitlines() if "failed (" in line]
    assert len(failed) == 1 and failed[0].endswith(": 'RuntimeError: boom\\noutputs: forged'"), info.stdout
    assert not any(line.startswith("outputs: forged") for line in info.stdout.splitlines())
    assert [one_line(t) for t in ("a, b: c", "a\u2028b", "x\x1b[2J")] == ["a, b: c", "'a\\u2028b'", "x\x1b[2J"]


def test_report_escapes_markdown_and_quotes_formulas(hostile):
    folder, _ = hostile
    out = folder / "report"
    done = cli_in_process("report", folder / "r.h5", "--out", out)
    assert done.returncode == 0, done.stderr
    page = (out / "report.md").read_text()
    assert r"\|\*bold\* \_em\_ \`code\` \[link\](x) \<b\> \#h" in page
    assert "<b>" not in page and "|*bold*" not in page
    with open(out / "tables" / "failures.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert rows and all(row["reason"].startswith("'=HYPERLINK(1)|") for row in rows)
    with open(out / "tables" / "statistics_at_times.csv", newline="") as fh:
        statistics = list(csv.DictReader(fh))
    assert float(statistics[0]["band99 lower"]) < 0  # a negative number stays a number


def test_the_command_line_prints_only_through_echo():
    """One place strips control characters: a typer.echo or print in a command would bypass it."""
    from pathlib import Path

    import uqflight

    package = Path(uqflight.__file__).parent
    for module in (package / "cli" / "commands.py", package / "calibration" / "command.py"):
        text = module.read_text()
        assert "typer.echo(" not in text and "print(" not in text, module
