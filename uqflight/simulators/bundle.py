"""What travels with a task to workers that share no disk with the client.

`kinds.make_bundle` packs, on the client, the files a simulator needs: the aircraft's XML files (the
patched copy when parameters scale or offset its functions; engines and systems included) or a
`file.py` python simulator, as bytes, with their sha256; and the files of a script scenario (the
script, its initialisation file: `ScenarioKind.files`). `unpacked` unpacks them on the worker
into its own cache (`$UQFLIGHT_CACHE`, else `$XDG_CACHE_HOME/uqflight`, else ~/.cache/uqflight),
keyed by the hash, and `kinds.localized` points the spec's simulator mapping there. Before a worker
flies, it hashes the aircraft files it is about to load; files that differ from the client's
(a stale or edited copy in its cache) are refused with an `AircraftMismatch`.

Before unpacking anything, the worker checks the bundle (`BundleRefused` otherwise): its hash is
a sha256, its name one file name, every key a relative path inside the aircraft's root (no
leading `/`, `..`, `@root//...`, drive or backslash), at most MAX_FILES files and MAX_BYTES
uncompressed, and the files hash to the bundle's hash.
"""
from __future__ import annotations

import hashlib
import io
import os
import re
import shutil
import zipfile
import zlib
from dataclasses import replace
from pathlib import Path

from ..text.bounded import OutsideBounds, read_bounded
from .aircraft import MAX_BYTES, MAX_FILES, AircraftFiles, AircraftUnsafe, cache_dir, unsafe_key
from .safe_paths import relative_name, single_name
from .spec import SimulatorSpec

SHA256 = re.compile(r"[0-9a-f]{64}")


class AircraftMismatch(RuntimeError):
    """The worker's aircraft files are not the client's: the worker refuses to fly them."""


class BundleRefused(RuntimeError):
    """A bundle with a name, key or hash that would lead outside the worker's cache, or more files
    or bytes than an aircraft has (MAX_FILES, MAX_BYTES): refused before anything is unpacked."""


def _zip(files: dict[str, bytes]) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as z:
        for key in sorted(files):
            info = zipfile.ZipInfo(key, date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED  # a bare ZipInfo would store the file uncompressed
            z.writestr(info, files[key])
    return buffer.getvalue()


def _refuse(what: str) -> BundleRefused:
    return BundleRefused(f"worker: refusing the client's bundle, nothing unpacked: {what}")


def _unzip(data: bytes, unsafe) -> dict[str, bytes]:
    """The bundle's files, once every name passes `unsafe(name)` (None, or why not) and their count and
    declared total size are within the limits; reading stops at the declared sizes (zipfile checks
    each file's length and CRC), so no file grows past what was checked."""
    # what zipfile raises on a hostile or broken archive: RuntimeError for an encrypted file,
    # NotImplementedError for a compression method it lacks
    unreadable = (zipfile.BadZipFile, zlib.error, EOFError, ValueError, RuntimeError, NotImplementedError)
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except unreadable as exc:
        raise _refuse(f"not a readable zip ({type(exc).__name__}: {exc})") from None
    with archive:
        infos = archive.infolist()
        if len(infos) > MAX_FILES:
            raise _refuse(f"{len(infos)} files, more than {MAX_FILES}")
        if len({info.filename for info in infos}) != len(infos):
            raise _refuse("a file name appears twice")
        for info in infos:
            why = unsafe(info.orig_filename) or unsafe(info.filename)
            if why:
                raise _refuse(f"file {info.orig_filename!r}: {why}")
            if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
                raise _refuse(f"file {info.filename!r}: compression method {info.compress_type}")
        size = sum(info.file_size for info in infos)
        if size > MAX_BYTES:
            raise _refuse(f"{size} bytes uncompressed, more than {MAX_BYTES} ({MAX_BYTES / 2**20:.0f} MiB)")
        try:
            return {info.filename: archive.read(info) for info in infos}
        except unreadable as exc:
            raise _refuse(f"not a readable zip ({type(exc).__name__}: {exc})") from None


def _checked(bundle) -> dict:
    """The bundle, once its kind, name and hash are ones the worker can use as names in its cache."""
    if not isinstance(bundle, dict) or bundle.get("kind") not in UNPACK:
        raise _refuse(f"expected a bundle of kind {' or '.join(map(repr, UNPACK))}")
    if not isinstance(bundle.get("hash"), str) or not SHA256.fullmatch(bundle["hash"]):
        raise _refuse(f"hash {bundle.get('hash')!r}: expected 64 lowercase hexadecimal digits (a sha256)")
    name, suffix = bundle.get("name"), SUFFIX[bundle["kind"]]
    if not single_name(name) or not name.endswith(suffix):
        raise _refuse(f"name {name!r}: expected a single file name{' ending in ' + suffix if suffix else ''} "
                      "(no /, \\, :, NUL, . or ..)")
    if not isinstance(bundle.get("zip"), bytes):
        raise _refuse("expected the files as zip bytes")
    return bundle


def aircraft_bundle(simulator: SimulatorSpec, properties, base: str | Path, scenario_files) -> dict | None:
    """A JSBSim simulator's aircraft (the patched copy when `properties` perturb its functions) and its
    scenario's files (`scenario_files(simulator)`); None when the simulator already reads a worker's local
    copy (`root`)."""
    from .patch import PreparedAircraft

    if simulator.root is not None:
        return None
    prepared = PreparedAircraft(simulator.aircraft_path or simulator.get("aircraft", "bacm"), Path(base),
                                properties)
    bundle = {"kind": "aircraft", "name": prepared.name, "hash": prepared.hash, "zip": _zip(prepared.files.files)}
    files = scenario_files(simulator)  # a script scenario's script and initialisation
    if files:
        bundle["scenario"] = {"hash": AircraftFiles("", files).hash(), "zip": _zip(files)}
    return bundle


def python_bundle(simulator: SimulatorSpec, base: str | Path) -> dict | None:
    """A python simulator's file (`file.py:callable`); None for an installed module."""
    module, _, attribute = str(simulator.get("function", "")).partition(":")
    if not module.endswith(".py"):
        return None
    file = Path(module) if Path(module).is_absolute() else Path(base) / module
    try:  # a regular file, bounded as an aircraft's files
        data = read_bounded(file, MAX_BYTES, "a python model")
    except OutsideBounds as exc:
        raise OutsideBounds(f"simulator.function: {file}: {exc}") from None
    return {"kind": "python", "name": file.name, "attribute": attribute,
            "hash": hashlib.sha256(data).hexdigest(), "zip": _zip({file.name: data})}


def unpacked(bundle, simulator: SimulatorSpec) -> tuple[SimulatorSpec, Path | None]:
    """The simulator spec reading the bundle's files from this worker's cache (unpacked on first use),
    and the folder of its scenario's files (None: none travel). Raises BundleRefused when the bundle's
    names, hash, size or file count are unsafe (before unpacking anything), AircraftMismatch when the
    files differ from its hash."""
    bundle = _checked(bundle)
    return UNPACK[bundle["kind"]](bundle, simulator)


def _unpacked_aircraft(bundle: dict, simulator: SimulatorSpec) -> tuple[SimulatorSpec, Path | None]:
    name, digest = bundle["name"], bundle["hash"]
    files = AircraftFiles(name, _unzip(bundle["zip"], unsafe_key))
    if f"{name}.xml" not in files.files or files.hash() != digest:
        raise _refuse(f"the files of {name!r} do not hash to the bundle's sha256 {digest[:12]} "
                      f"(or lack {name}.xml)")
    try:
        root = files.write_root(cache_dir("aircraft", digest[:24]))
    except AircraftUnsafe as exc:
        raise _refuse(str(exc)) from None
    check_aircraft(root, name, digest)
    simulator = replace(simulator.with_settings(aircraft=name), root=str(root), aircraft_path=None)
    scenario = bundle.get("scenario")
    if not scenario:
        return simulator, None
    if not (isinstance(scenario, dict) and isinstance(scenario.get("hash"), str)
            and SHA256.fullmatch(scenario["hash"]) and isinstance(scenario.get("zip"), bytes)):
        raise _refuse("scenario: expected a sha256 and the files as zip bytes")
    return simulator, _unpacked(scenario, cache_dir("scenario", scenario["hash"][:24]))


def _unpacked_python(bundle: dict, simulator: SimulatorSpec) -> tuple[SimulatorSpec, None]:
    if not (isinstance(bundle.get("attribute"), str) and bundle["attribute"].isidentifier()):
        raise _refuse(f"attribute {bundle.get('attribute')!r}: expected a Python name")
    name, digest = bundle["name"], bundle["hash"]
    data = _unzip(bundle["zip"], lambda key: None if key == name else f"expected only {name!r}")
    if name not in data or hashlib.sha256(data[name]).hexdigest() != digest:
        raise _refuse(f"{name!r} does not hash to the bundle's sha256 {digest[:12]}")
    folder = cache_dir("python", digest[:24])
    file = folder / name
    if not file.is_file():
        folder.mkdir(parents=True, exist_ok=True)
        file.write_bytes(data[name])
    if hashlib.sha256(file.read_bytes()).hexdigest() != digest:
        raise AircraftMismatch(f"worker: {file} differs from the client's {name} "
                               f"(sha256 {digest[:12]}): refusing to run it; delete {folder}")
    return simulator.with_settings(function=f"{file}:{bundle['attribute']}"), None


# the bundles' kinds: how each unpacks, and the suffix of its name
UNPACK = {"aircraft": _unpacked_aircraft, "python": _unpacked_python}
SUFFIX = {"aircraft": "", "python": ".py"}


def _unsafe_scenario_key(key: str) -> str | None:
    """Why `key` cannot name a scenario file (None when it can): a normalized path inside its folder."""
    return None if isinstance(key, str) and relative_name(key) == key else (
        "expected a relative path inside the scenario's folder (no leading /, no .., backslash, drive or NUL)")


def _unpacked(files: dict, folder: Path) -> Path:
    """A scenario's files written once into `folder` (all or nothing), once their names, count, size and
    hash are checked (BundleRefused, nothing written); AircraftMismatch when the files found there do not
    hash to the client's."""
    if not folder.is_dir():
        data = _unzip(files["zip"], _unsafe_scenario_key)
        if AircraftFiles("", data).hash() != files["hash"]:
            raise _refuse(f"the scenario's files do not hash to the bundle's sha256 {files['hash'][:12]}")
        tmp = folder.parent / f".{folder.name}.{os.getpid()}.tmp"
        for name, content in data.items():
            path = tmp / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(content)
        try:
            tmp.rename(folder)
        except OSError:  # another process wrote it first
            shutil.rmtree(tmp, ignore_errors=True)
    found = {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}
    if AircraftFiles("", found).hash() != files["hash"]:
        raise AircraftMismatch(f"worker: the scenario files in {folder} differ from the client's (sha256 "
                               f"{files['hash'][:12]}): refusing to fly them; delete {folder}")
    return folder


def check_aircraft(root: Path, name: str, expected: str) -> None:
    """Refuse (AircraftMismatch) when the aircraft under `root` does not hash to `expected`."""
    from .aircraft import AircraftLocation

    found = AircraftFiles.read(AircraftLocation(name, Path(root) / "aircraft" / name, Path(root), "cache")).hash()
    if found != expected:
        raise AircraftMismatch(
            f"worker: the aircraft files of {name!r} in {root} have sha256 {found[:12]}, the campaign's "
            f"(the client's) {expected[:12]}: refusing to fly another aircraft; delete {root} to let the "
            "worker unpack the client's files")
