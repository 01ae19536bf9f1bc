"""An aircraft loaded once in a throw-away process before any process of ours loads it.

JSBSim 1.3 kills the whole process on some aircraft errors: a function that reads a property no
model defines loads without complaint, but FGFDMExec's destructor then throws from a noexcept
context and std::terminate aborts (SIGABRT, no Python exception). A campaign's own process must
not die that way: the throw-away process dies instead, and its message (JSBSim's `what():` line)
is raised as AircraftUnreadable. A load that survived is remembered in the cache under the hash of
the files JSBSim reads (the aircraft's folder and the root's engine/ and systems/ folders), so each
version of an aircraft costs one check (~0.3 s) per machine.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from .aircraft import AircraftUnreadable, cache_dir, length_prefixed_sha256

CHILD = """
import sys
import jsbsim
jsbsim.set_logger(jsbsim.DefaultLogger(jsbsim.LogLevel.FATAL))
fdm = jsbsim.FGFDMExec(sys.argv[1])
fdm.set_debug_level(0)
loaded = fdm.load_model(sys.argv[2])
del fdm  # the destructor is where JSBSim aborts
sys.exit(0 if loaded else 3)
"""
TIMEOUT_S = 120


def files_digest(root: Path, aircraft: str) -> str:
    """sha256 over the XML files JSBSim may read for `aircraft` under `root`, with their paths
    (length-prefixed: no two sets of files hash alike)."""
    parts = [str(root.resolve()).encode()]
    for folder in (root / "aircraft" / aircraft, root / "engine", root / "systems"):
        for path in sorted(folder.rglob("*.xml")) if folder.is_dir() else ():
            parts += [path.relative_to(root).as_posix().encode(), path.read_bytes()]
    return length_prefixed_sha256(parts)


def check_loads(root: Path, aircraft: str) -> None:
    """Load `aircraft` from `root` in a throw-away process unless this version loaded before;
    AircraftUnreadable with JSBSim's message when that process dies. (A load JSBSim merely refuses
    is left to the caller, which says so in its own words.)"""
    marker = cache_dir("loads", files_digest(root, aircraft)[:32])
    if marker.exists():
        return
    try:
        child = subprocess.run([sys.executable, "-c", CHILD, str(root), aircraft], capture_output=True,
                               text=True, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        raise AircraftUnreadable(f"JSBSim did not finish loading aircraft {aircraft!r} from {root} within "
                                 f"{TIMEOUT_S} s") from None
    if child.returncode < 0 or child.returncode not in (0, 3):
        lines = [line.strip() for line in child.stderr.splitlines() if line.strip()]
        what = next((line.split("what():", 1)[1].strip() for line in lines if "what():" in line),
                    lines[-1] if lines else f"exit code {child.returncode}")
        raise AircraftUnreadable(f"JSBSim kills the process that loads aircraft {aircraft!r} from {root}: {what}; "
                                 "fix the aircraft's files")
    if child.returncode == 0:
        try:
            marker.parent.mkdir(parents=True, exist_ok=True)
            marker.touch()
        except OSError:  # a cache we cannot write: the check runs again next time
            pass
