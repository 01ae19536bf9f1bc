"""Where an aircraft's files are, what they are, and a JSBSim root directory that flies them.

`simulator.aircraft` (and `uqflight simulate --aircraft`) names either
1. a path to an aircraft folder `X/NAME/` holding `NAME.xml` (relative to the campaign file's
   folder, or to the working directory on the command line); tried first when it exists;
2. an aircraft of this project: `aircraft/NAME/` in the source tree, or the copy shipped as
   package data (`uqflight/aircraft/NAME/`) in an installed uqflight;
3. one of JSBSim's own aircraft (`jsbsim.get_default_root_dir()/aircraft/NAME/`).

An aircraft is flown from a *root*: a folder with `aircraft/NAME/NAME.xml`, and `engine/` and
`systems/` for the shared files it names. The aircraft's files are its folder's XML files plus
the engines, thrusters and systems it names that live in the root's shared folders:
`AircraftFiles` holds them as bytes (keyed by path), hashes them, and writes them out as a root
of their own (the patched copies and the copies on remote workers are such roots). Every name in
those files (`file=` attributes, output files, symbolic links) must stay in the folders JSBSim
looks in, every file must be one Python's parser reads (JSBSim's may read more), and the main file
names no `<child>` aircraft: `AircraftUnsafe` otherwise, before anything is read or written
(directives.py says what JSBSim does with each name).
"""
from __future__ import annotations

import hashlib
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import jsbsim

from ..text import Refusal
from ..text.console import one_line
from .directives import checked, jsbsim_tree, local_name, parsed, without_io
from .safe_paths import is_inside, outside_links, relative_name, single_name

PACKAGE_ROOT = Path(__file__).resolve().parents[1]  # uqflight/: holds aircraft/bacm as package data
SOURCE_ROOT = Path(__file__).resolve().parents[2]   # the repository, when run from the source tree
SHARED = "@root/"  # key prefix of files from the root's shared engine/ and systems/ folders


class AircraftNotFound(Refusal, FileNotFoundError):
    """No aircraft of that name or path; the message lists where it looked and close names."""


class AircraftUnreadable(Refusal, RuntimeError):
    """An aircraft whose main file is not well-formed XML."""


def cache_dir(*parts: str) -> Path:
    """uqflight's cache: $UQFLIGHT_CACHE, else $XDG_CACHE_HOME/uqflight, else ~/.cache/uqflight.
    Each part is one folder or file name (ValueError otherwise): a cache key never leaves the cache."""
    for part in parts:
        if not single_name(part):
            raise ValueError(f"cache key {part!r}: expected a single file name (no /, \\, :, NUL, . or ..)")
    base = os.environ.get("UQFLIGHT_CACHE")
    if not base:
        base = str(Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "uqflight")
    return Path(base, *parts)


def project_roots() -> list[Path]:
    """Roots holding this project's aircraft: the source tree first, then the package data."""
    return [root for root in (SOURCE_ROOT, PACKAGE_ROOT) if (root / "aircraft").is_dir()]


def jsbsim_root() -> Path:
    return Path(jsbsim.get_default_root_dir())


@dataclass(frozen=True)
class AircraftLocation:
    """An aircraft found on disk: its name, its folder, and the root JSBSim loads it from."""

    name: str
    folder: Path
    root: Path
    origin: str  # "path", "project" or "jsbsim"

    @property
    def file(self) -> Path:
        return self.folder / f"{self.name}.xml"

    @property
    def loadable_from_root(self) -> bool:
        """True when `FGFDMExec(root).load_model(name)` finds exactly this folder."""
        return (self.root / "aircraft" / self.name).resolve() == self.folder.resolve()


def _is_aircraft_folder(folder: Path) -> bool:
    return (folder / f"{folder.name}.xml").is_file()


def known_aircraft() -> dict[str, list[str]]:
    """Names of the project's and JSBSim's aircraft, for messages and `uqflight aircraft`."""
    found = {"project": set(), "jsbsim": set()}
    for origin, roots in (("project", project_roots()), ("jsbsim", [jsbsim_root()])):
        for root in roots:
            found[origin].update(p.name for p in (root / "aircraft").iterdir() if _is_aircraft_folder(p))
    return {k: sorted(v) for k, v in found.items()}


def locate(aircraft: str | os.PathLike, base: Path | None = None) -> AircraftLocation:
    """The aircraft named by `aircraft` (a path, a project aircraft or a JSBSim aircraft)."""
    text = str(aircraft)
    candidate = Path(text).expanduser()
    if not candidate.is_absolute():
        candidate = Path(base or Path.cwd()) / candidate
    if candidate.is_file() and candidate.suffix == ".xml":
        candidate = candidate.parent
    if candidate.is_dir() and _is_aircraft_folder(candidate):
        folder = candidate.resolve()
        parent = folder.parent
        # A folder inside a root's aircraft/ keeps that root (its shared engines and systems).
        root = parent.parent if parent.name == "aircraft" else jsbsim_root()
        return AircraftLocation(folder.name, folder, root, "path")
    if "/" not in text and os.sep not in text:
        for root in project_roots():
            if _is_aircraft_folder(root / "aircraft" / text):
                return AircraftLocation(text, (root / "aircraft" / text).resolve(), root, "project")
        if _is_aircraft_folder(jsbsim_root() / "aircraft" / text):
            return AircraftLocation(text, (jsbsim_root() / "aircraft" / text).resolve(), jsbsim_root(), "jsbsim")
    import difflib

    names = known_aircraft()
    everything = names["project"] + names["jsbsim"]
    close = difflib.get_close_matches(text, everything, n=3, cutoff=0.6)
    hint = f"; did you mean {' or '.join(close)}?" if close else ""
    raise AircraftNotFound(
        f"no aircraft {text!r}: expected a folder X/NAME/ holding NAME.xml (relative to "
        f"{base or Path.cwd()}), or one of the project's aircraft ({', '.join(names['project'])}) or of "
        f"JSBSim's ({len(names['jsbsim'])}, e.g. c172p, 737, f16; `uqflight aircraft --list`){hint}")


# -- the files an aircraft consists of -----------------------------------------------------
MAX_FILES = 4096          # an aircraft's files, and a bundle's (the largest stock aircraft: 13 files)
MAX_BYTES = 64 * 2**20    # their total size (the largest stock aircraft: 0.3 MB)
ENGINE_TAGS, SYSTEM_TAGS = ("engine", "thruster"), ("system", "flight_control", "autopilot")


class AircraftUnsafe(AircraftUnreadable):
    """A name in an aircraft's files that leads outside its folder (a `file=` attribute, a symbolic
    link, a bundle key), or more files than uqflight reads: nothing of it is read or written."""


def unsafe_key(key: str) -> str | None:
    """Why `key` cannot name one of an aircraft's files (None when it can): a key is a normalized
    relative path ending in .xml, or `@root/engine/...` / `@root/systems/...`."""
    rel = key[len(SHARED):] if isinstance(key, str) and key.startswith(SHARED) else key
    if not isinstance(key, str) or relative_name(rel) != rel:
        return ("expected a relative path inside the aircraft's folder (no leading /, no .. out of it, no "
                "backslash, drive or NUL)")
    if not rel.endswith(".xml"):
        return "expected an .xml file"
    if key.startswith(SHARED) and rel.split("/", 1)[0] not in ("engine", "systems"):
        return "expected @root/engine/... or @root/systems/..."
    return None


def _folder_files(folder: Path) -> dict[str, Path]:
    """Key -> path of the .xml files under `folder`; refuses links leaving it and too many files."""
    for link in outside_links(folder):
        raise AircraftUnsafe(f"{link} is a symbolic link to {os.readlink(link)}, outside the aircraft folder "
                             f"{folder}: uqflight neither follows nor copies it; put a copy of the file in the "
                             "folder instead")
    found: dict[str, Path] = {}
    for top, dirs, names in os.walk(folder, followlinks=True):  # links inside the folder stay inside
        here = os.path.realpath(top)
        dirs[:] = sorted(d for d in dirs if not is_inside(here, os.path.join(top, d)))  # no loops
        for name in sorted(names):
            path = Path(top, name)
            if name.endswith(".xml") and path.is_file():
                found[path.relative_to(folder).as_posix()] = path
        if len(found) > MAX_FILES:
            raise AircraftUnsafe(f"{folder} holds more than {MAX_FILES} .xml files: expected an aircraft folder")
    return found


def _file_names(xml: bytes, file: Path) -> list[tuple[str, str]]:
    """(element name, file= value) of every element naming a file, each checked to stay in its folder
    as JSBSim reads it (directives.checked); AircraftUnsafe naming the file when Python cannot parse it."""
    return checked(parsed(xml, file, AircraftUnsafe), file, AircraftUnsafe,
                   "the aircraft's folder (or to JSBSim's engine/ and systems/ folders)")


def _no_child(xml: bytes, file: Path) -> None:
    """Refuse a `<child>` aircraft in the main file: JSBSim would load it from the root, unchecked."""
    for element in jsbsim_tree(xml):
        if local_name(element.tag) == "child":
            raise AircraftUnsafe(f'{file}: <child name="{one_line(element.get("name", ""))}">: JSBSim would load that aircraft '
                                 "from the root's aircraft folder, files uqflight neither checks nor copies; "
                                 "uqflight flies one aircraft: remove the <child> element")


@dataclass
class AircraftFiles:
    """An aircraft's XML files as bytes: `files[key]`, where a key is a path relative to the
    aircraft's folder, or `@root/engine/...` / `@root/systems/...` for shared files."""

    name: str
    files: dict[str, bytes] = field(default_factory=dict)

    @classmethod
    def read(cls, location: AircraftLocation) -> "AircraftFiles":
        """The folder's .xml files, and the root's engines, thrusters and systems any of them names
        (where JSBSim finds them: the folder, its Engines/ or Systems/, then the root's engine/ or
        systems/). Every `file=` attribute and symbolic link must stay in those folders
        (AircraftUnsafe otherwise, naming the file and the attribute)."""
        folder = location.folder
        paths = _folder_files(folder)
        files, size = {}, 0
        for key, path in paths.items():
            files[key] = path.read_bytes()
            size += len(files[key])
            if size > MAX_BYTES:
                raise AircraftUnsafe(f"{folder}: its .xml files exceed {MAX_BYTES / 2**20:.0f} MiB: expected an "
                                     "aircraft folder")
        main = f"{location.name}.xml"
        if main not in files:
            raise AircraftUnreadable(f"{folder / main} is not well-formed XML (no element found); JSBSim "
                                     "cannot load it either")
        names = []
        for key, data in files.items():  # every file JSBSim may read (its main file, or one named) is checked
            names += _file_names(data, paths[key])
        _no_child(files[main], folder / main)
        for tag, name in names:
            if tag not in ENGINE_TAGS + SYSTEM_TAGS:
                continue
            kind, subfolder = ("engine", "Engines") if tag in ENGINE_TAGS else ("systems", "Systems")
            file = relative_name(name if name.endswith(".xml") else name + ".xml")
            if f"{subfolder}/{file}" in files or file in files:
                continue
            shared = location.root / kind / file
            if shared.is_file() and f"{SHARED}{kind}/{file}" not in files:
                if not is_inside(shared, location.root / kind):
                    raise AircraftUnsafe(f"{shared} leads outside {location.root / kind} (a symbolic link): "
                                         "uqflight neither follows nor copies it")
                files[f"{SHARED}{kind}/{file}"] = shared.read_bytes()
                _file_names(files[f"{SHARED}{kind}/{file}"], shared)
        return cls(location.name, files)

    @property
    def main(self) -> bytes:
        return self.files[f"{self.name}.xml"]

    def hash(self) -> str:
        """sha256 over the files in key order, each as the length (8 bytes, big-endian) and bytes of
        its key, then of its contents: two different sets of files never hash alike."""
        return length_prefixed_sha256(part for key in sorted(self.files)
                                      for part in (key.encode(), self.files[key]))

    def with_main(self, xml: bytes) -> "AircraftFiles":
        return AircraftFiles(self.name, {**self.files, f"{self.name}.xml": xml})

    def without_io(self) -> "AircraftFiles":
        """The files with the main file's `<input>` and `<output>` directives removed (directives.py:
        JSBSim then writes, connects to and listens on nothing); the files themselves when it has none."""
        main = without_io(self.main)
        return self if main is None else self.with_main(main)

    def write_root(self, root: Path) -> Path:
        """Write the files as a JSBSim root (`aircraft/NAME/...`, `engine/`, `systems/`); returns root.
        Written into a temporary folder then renamed, so concurrent writers never see half a root.
        A name or key that would lead outside `root` is refused (AircraftUnsafe) before any write."""
        root = Path(root)
        if not single_name(self.name):
            raise AircraftUnsafe(f"aircraft name {self.name!r}: expected a folder name (no /, \\, :, NUL, . or ..)")
        for key in self.files:
            if unsafe_key(key):
                raise AircraftUnsafe(f"aircraft {self.name!r}: file {key!r}: {unsafe_key(key)}")
        if (root / "aircraft" / self.name / f"{self.name}.xml").is_file():
            return root
        root.parent.mkdir(parents=True, exist_ok=True)
        tmp = root.parent / f".{root.name}.{os.getpid()}.tmp"
        shutil.rmtree(tmp, ignore_errors=True)  # a killed writer's leftover (it may hold links)
        for key, data in self.files.items():
            rel = key[len(SHARED):] if key.startswith(SHARED) else f"aircraft/{self.name}/{key}"
            path = tmp / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        for shared in ("engine", "systems"):
            (tmp / shared).mkdir(exist_ok=True)
        try:
            tmp.rename(root)
        except OSError:  # another process wrote it first
            shutil.rmtree(tmp, ignore_errors=True)
        return root

    def cached_root(self) -> Path:
        """The files written once as a root in the cache, under their hash."""
        return self.write_root(cache_dir("aircraft", self.hash()[:24]))


def length_prefixed_sha256(parts) -> str:
    """sha256 (hex) of byte strings, each preceded by its length as 8 big-endian bytes."""
    digest = hashlib.sha256()
    for part in parts:
        digest.update(len(part).to_bytes(8, "big"))
        digest.update(part)
    return digest.hexdigest()


# -- what the aircraft holds: aerodynamic functions and engines ----------------------------
@dataclass(frozen=True)
class AeroFunction:
    axis: str         # LIFT, DRAG, PITCH, ... or "" for a function outside the axes
    name: str         # the JSBSim property it defines, e.g. aero/coefficient/CLwbh
    description: str


def aero_functions(xml: bytes) -> list[AeroFunction]:
    """The named functions of the <aerodynamics> section, in file order, with their axis."""
    tree = jsbsim_tree(xml)
    aero = tree.find("aerodynamics")
    if aero is None:
        return []
    found = []

    def walk(element, axis):
        for child in element:
            if child.tag == "axis":
                walk(child, child.get("name", ""))
            elif child.tag == "function" and child.get("name"):
                desc = child.findtext("description") or ""
                found.append(AeroFunction(axis, child.get("name").strip(), " ".join(desc.split())))
    walk(aero, "")
    return found


# Flight condition used when a campaign or the command line states none: inside each tested
# aircraft's envelope (measured: trims and holds level flight, see docs/own-aircraft.md).
DEFAULT_CONDITIONS = {
    "bacm": {"altitude_ft": 15000.0, "airspeed_ktas": 200.0},
    "c172p": {"altitude_ft": 4000.0, "airspeed_ktas": 100.0},
    "c172x": {"altitude_ft": 4000.0, "airspeed_ktas": 100.0},  # trims level from 45 to 125 KTAS there
    "737": {"altitude_ft": 10000.0, "airspeed_ktas": 280.0},
    "f16": {"altitude_ft": 15000.0, "airspeed_ktas": 400.0},
}
FALLBACK_CONDITION = {"altitude_ft": 15000.0, "airspeed_ktas": 200.0}


def default_condition(name: str) -> dict[str, float]:
    """The aircraft's default trim condition (altitude_ft, airspeed_ktas)."""
    return dict(DEFAULT_CONDITIONS.get(name, FALLBACK_CONDITION))


def elevator_travel_deg(xml: bytes) -> tuple[float, float] | None:
    """(down, up) elevator travel [deg] at command +1 and -1: from the flight control component
    whose output is fcs/elevator-pos-rad (or -deg), its <range> times its <gain>. None if absent."""
    import math

    tree = jsbsim_tree(xml)
    for component in tree.iter():
        output = (component.findtext("output") or "").strip()
        if output not in ("fcs/elevator-pos-rad", "fcs/elevator-pos-deg"):
            continue
        rng = component.find("range")
        if rng is None:
            continue
        gain = float(component.findtext("gain") or 1.0)
        lo, hi = float(rng.findtext("min")) * gain, float(rng.findtext("max")) * gain
        to_deg = 180.0 / math.pi if output.endswith("-rad") else 1.0
        return abs(hi) * to_deg, abs(lo) * to_deg
    return None
