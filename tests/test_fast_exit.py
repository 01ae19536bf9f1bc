"""uqflight.cli.fast_exit: the console script ends without the interpreter's teardown only where nothing can be
lost; each case runs in a real Python process."""
import subprocess
import sys
import textwrap

import h5py
import numpy as np
import pytest
from conftest import ROOT, cli

# an object whose finaliser runs only in the interpreter's teardown: it says whether the teardown ran
TEARDOWN_PROBE = """
import sys
class Probe:
    def __del__(self):
        sys.stderr.write("teardown ran\\n")
probe = Probe()
"""


def _python(code: str, tmp_path):
    return subprocess.run([sys.executable, "-c", TEARDOWN_PROBE + textwrap.dedent(code)], cwd=tmp_path,
                          capture_output=True, text=True, timeout=60)


def test_a_finished_command_skips_the_teardown_but_runs_atexit_and_flushes(tmp_path):
    done = _python("""
        import atexit, pathlib
        from uqflight.cli.fast_exit import exit_fast
        atexit.register(lambda: pathlib.Path("atexit-ran").write_text("yes"))
        print("last line", end="")  # buffered: only a flush writes it
        exit_fast(3)
    """, tmp_path)
    assert done.returncode == 3
    assert done.stdout == "last line"
    assert (tmp_path / "atexit-ran").read_text() == "yes"
    assert "teardown ran" not in done.stderr


def test_a_running_thread_gets_a_normal_exit_that_waits_for_it(tmp_path):
    done = _python("""
        import pathlib, threading, time
        from uqflight.cli.fast_exit import exit_fast
        def late():
            time.sleep(0.3)
            pathlib.Path("thread-done").write_text("yes")
        threading.Thread(target=late).start()
        exit_fast(0)
    """, tmp_path)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "thread-done").read_text() == "yes"
    assert "teardown ran" in done.stderr


def test_an_open_hdf5_file_gets_a_normal_exit_that_closes_it(tmp_path):
    done = _python("""
        import h5py, numpy as np
        from uqflight.cli.fast_exit import exit_fast
        f = h5py.File("open.h5", "w")
        f["x"] = np.arange(1000.0)
        exit_fast(0)
    """, tmp_path)
    assert done.returncode == 0, done.stderr
    assert "teardown ran" in done.stderr
    with h5py.File(tmp_path / "open.h5", "r") as f:
        np.testing.assert_array_equal(f["x"][()], np.arange(1000.0))


def test_a_message_code_is_printed_with_status_1(tmp_path):
    done = _python("""
        from uqflight.cli.fast_exit import exit_fast
        exit_fast("cannot go on")
    """, tmp_path)
    assert done.returncode == 1
    assert "cannot go on" in done.stderr


@pytest.mark.slow
def test_the_console_script_keeps_the_commands_exit_status_and_output(tmp_path):
    bad = cli("report", tmp_path / "none.h5")
    assert bad.returncode == 2 and "no such results file" in bad.stderr
    listed = cli("plan", "campaigns/paper-pg2-l2.yaml", cwd=ROOT)
    assert listed.returncode == 0, listed.stderr
    assert "sparse_grid: 113 points in 7 dimensions" in listed.stdout
    assert listed.stdout.splitlines()[-1].startswith("estimated time:")  # the last line written, not lost
