"""A report replaces DIR with no moment when DIR is absent (issue 22, item 5): a SIGKILL at any point
of the replacement leaves the old or the new report in DIR; what a killed report leaves beside DIR is
cleaned by the next one; concurrent reports to one DIR end with one complete report, nothing else.

The kills are real SIGKILLs of a forked process, sent by itself at the k-th Python line it executes
inside `replace_dir`, counting the lines of replace.py and of shutil (whose rmtree deletes the old
report): every system call the replacement makes comes from one of them."""
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest
from conftest import UQFLIGHT, cli

from uqflight.report import replace
from uqflight.report import write_report as write_uqflight_report
from uqflight.report.replace import clean_leftovers, make_staging, replace_dir

FILES = ("report.html", "report.md", "summary.json", "plots/a.png", "plots/b.png", "tables/t.csv",
         "summaries/s.json")


TRACED = (replace.__file__, shutil.__file__)


def write_report(folder, label):
    for name in FILES:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(f"{label} {name}")
    return folder


def labelled(label):
    """The contents of `write_report(folder, label)`."""
    return {name: f"{label} {name}".encode() for name in FILES}


def contents(folder):
    if not folder.is_dir():
        return None
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def report_of(label, out):
    """A complete report `label` in a new staging folder for `out`."""
    return write_report(make_staging(out), label)


def in_child(action, kill_at=0, before=None):
    """Run `action()` in a forked process that SIGKILLs itself at its `kill_at`-th traced line (0: never);
    `before()` runs first, untraced. Returns (killed, lines executed)."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: nothing but the action, then _exit
        os.close(read)
        count = [0]

        def trace(frame, event, arg):
            if event == "line" and frame.f_code.co_filename in TRACED:
                count[0] += 1
                if count[0] == kill_at:
                    os.kill(os.getpid(), signal.SIGKILL)
            return trace

        code = 0
        try:
            prepared = before() if before else None
            sys.settrace(trace)
            action(prepared)
        except BaseException:  # noqa: BLE001 - reported by the exit code
            code = 1
        sys.settrace(None)
        os.write(write, str(count[0]).encode())
        os._exit(code)
    os.close(write)
    with os.fdopen(read) as fh:
        lines = fh.read()
    _, status = os.waitpid(pid, 0)
    killed = os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL
    assert killed or os.WEXITSTATUS(status) == 0, f"the child failed (exit {os.WEXITSTATUS(status)})"
    return killed, int(lines or 0)


def replacing(out, fallback=False):
    """In the child: its own staging folder holding the new report, then `replace_dir` traced."""
    def before():
        if fallback:  # as on a filesystem without RENAME_EXCHANGE
            def refuse(a, b):
                raise OSError(22, "Invalid argument")
            replace._exchange = refuse
        return report_of("new", out)

    return dict(action=lambda staging: replace_dir(staging, out), before=before)


def kill_everywhere(tmp_path, every=1, fallback=False, with_old=True):
    """Kill a replacement of an old report by a new one at every `every`-th line; after each kill DIR
    holds the old or the new report (the fallback: or is absent with the old one aside, which the next
    report puts back first), and the next replacement leaves DIR with its report and nothing beside it."""
    out = tmp_path / "DIR"
    old, new = labelled("old"), labelled("new")
    if with_old:
        write_report(out, "old")
    _, total = in_child(**replacing(out, fallback))
    assert total > 20 and contents(out) == new
    points = range(1, total + 1, every)
    kills = 0
    for k in points:
        shutil.rmtree(out)
        if with_old:
            write_report(out, "old")
        killed, _ = in_child(**replacing(out, fallback), kill_at=k)
        kills += killed
        found = contents(out)
        if found is None and fallback:  # the instant between the fallback's two renames
            clean_leftovers(out)
            found = contents(out)
        assert found in ((old, new) if with_old else (None, new)), f"kill at line {k} of {total}: {found}"
        replace_dir(report_of("next", out), out)
        assert contents(out) == labelled("next")
        assert sorted(p.name for p in tmp_path.iterdir()) == ["DIR"], f"kill at line {k}: leftovers"
    assert kills >= len(points) - 1  # every point but possibly the last (the lines leaving) was a kill
    return total


@pytest.mark.slow
def test_a_sigkill_anywhere_in_the_exchange_leaves_the_old_or_the_new_report(tmp_path):
    total = kill_everywhere(tmp_path, every=7)
    assert total < 1000  # a few hundred lines: every 7th reaches each step (every line: the slow test below)


def test_a_sigkill_anywhere_in_the_fallback_without_exchange_loses_no_report(tmp_path):
    kill_everywhere(tmp_path, every=17, fallback=True)


@pytest.mark.slow
def test_a_sigkill_at_every_line_of_every_way(tmp_path):
    for way, kwargs in {"exchange": {}, "first": {"with_old": False}, "fallback": {"fallback": True}}.items():
        (tmp_path / way).mkdir()
        kill_everywhere(tmp_path / way, **kwargs)


def test_the_exchange_is_used_here(tmp_path):
    """This machine's filesystem has RENAME_EXCHANGE, so the tests above test the exchange."""
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir(), b.mkdir()
    (a / "x").write_text("a")
    replace._exchange(a, b)
    assert (b / "x").read_text() == "a" and not (a / "x").exists()


def test_concurrent_replacements_end_with_one_report_and_nothing_else(tmp_path):
    out = tmp_path / "DIR"
    write_report(out, "old")
    for trial in range(6):
        stagings = [report_of(f"r{i}", out) for i in range(3)]
        go_read, go_write = os.pipe()
        pids = []
        for staging in stagings:
            pid = os.fork()
            if pid == 0:
                os.close(go_write)
                os.read(go_read, 1)  # all start together
                try:
                    replace_dir(staging, out)
                except BaseException:  # noqa: BLE001
                    os._exit(1)
                os._exit(0)
            pids.append(pid)
        os.close(go_read)
        os.close(go_write)  # EOF: go
        codes = [os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]) for pid in pids]
        assert codes == [0, 0, 0], f"trial {trial}"
        assert contents(out) in [labelled(f"r{i}") for i in range(3)]
        assert sorted(p.name for p in tmp_path.iterdir()) == ["DIR"], f"trial {trial}"


def test_what_a_killed_report_left_is_cleaned_and_nothing_else(tmp_path):
    out = tmp_path / "DIR"
    write_report(out, "old")
    # a report killed while writing its staging folder (partial: no report.html yet)
    in_child(lambda _: (write_report(make_staging(out), "half"), os.kill(os.getpid(), signal.SIGKILL)))
    # the state, from uqflight before this fix: killed between its two renames, DIR missing
    legacy = tmp_path / ".DIR.old-.DIR.k2j4x9.partial"
    out.rename(legacy)
    # not ours: a user's folder matching the pattern, a live writer's staging, another host's
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    foreign = tmp_path / f".DIR.{dead.pid}-1-{replace._host()}.0badcafe.partial"
    write_report(foreign, "theirs")
    (foreign / "thesis.txt").write_text("precious")
    live = report_of("live", out)
    other_host = write_report(tmp_path / ".DIR.1-1-ffffffff.0badcafe.partial", "elsewhere")
    replace_dir(report_of("new", out), out)
    assert contents(out) == labelled("new")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["DIR", foreign.name, live.name, other_host.name])
    assert (foreign / "thesis.txt").read_text() == "precious"


def test_a_file_at_the_report_lock_that_is_not_ours_is_refused_and_kept(tmp_path):
    out = tmp_path / "DIR"
    write_report(out, "old")
    lock = tmp_path / ".DIR.lock"
    lock.write_text("my notes")
    staging = report_of("new", out)
    with pytest.raises(FileExistsError, match=r"\.DIR\.lock is in the way of the report's lock"):
        replace_dir(staging, out)
    assert lock.read_text() == "my notes" and contents(out) == labelled("old")


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("results")
    campaign = folder / "c.yaml"
    campaign.write_text("""
name: replace
simulator: {kind: python, function: "uqflight.simulators.models:linear"}
parameters:
  x1: {distribution: uniform, lower: -1, upper: 1}
design: {kind: monte_carlo, samples: 8}
""")
    assert cli("run", campaign, "--out", folder / "r.h5").returncode == 0
    return folder / "r.h5"


@pytest.mark.slow
def test_two_uqflight_reports_to_one_folder_at_once(results, tmp_path):
    out = tmp_path / "DIR"
    runs = [subprocess.Popen([UQFLIGHT, "report", str(results), "--out", str(out)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outcomes = [run.communicate(timeout=300) for run in runs]
    assert [run.returncode for run in runs] == [0, 0], outcomes
    assert (out / "report.html").is_file() and sorted(p.name for p in tmp_path.iterdir()) == ["DIR"]


@pytest.mark.slow
def test_uqflight_report_killed_at_random_times_keeps_a_report(results, tmp_path):
    out = tmp_path / "DIR"
    assert cli("report", results, "--out", out).returncode == 0
    first = contents(out)
    for trial in range(8):
        run = subprocess.Popen([UQFLIGHT, "report", str(results), "--out", str(out)],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(0.5 + 0.4 * trial)
        run.send_signal(signal.SIGKILL)
        run.wait()
        assert (out / "report.html").is_file() and contents(out).keys() == first.keys(), f"trial {trial}"
    assert cli("report", results, "--out", out).returncode == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["DIR"]


@pytest.mark.slow
def test_a_report_that_fails_midway_leaves_nothing(decay_results, tmp_path, monkeypatch):
    import uqflight.report.render as render

    def broken(*args, **kwargs):
        raise RuntimeError("disk on fire")

    out = tmp_path / "nested" / "report"
    monkeypatch.setattr(render, "render_markdown", broken)  # after the plots and tables are written
    with pytest.raises(RuntimeError, match="disk on fire"):
        write_uqflight_report([decay_results], out)
    assert list(out.parent.iterdir()) == []
    old = tmp_path / "old"  # an earlier report: the one thing a report replaces (test_report.py)
    (old / "tables").mkdir(parents=True)
    (old / "report.html").write_text("previous report")
    (old / "tables" / "stale.csv").write_text("x")
    with pytest.raises(RuntimeError):
        write_uqflight_report([decay_results], old)
    assert sorted(p.name for p in old.rglob("*")) == ["report.html", "stale.csv", "tables"]
    assert (old / "report.html").read_text() == "previous report" and len(list(tmp_path.iterdir())) == 2
    monkeypatch.undo()
    written = write_uqflight_report([decay_results], old)
    assert not (old / "tables" / "stale.csv").exists() and (old / "report.html") in written
