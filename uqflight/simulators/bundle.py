"""What travels with a task to workers that share no disk with the client.

`make_bundle` packs, on the client, the files a simulator needs: the aircraft's XML files (the
patched copy when parameters scale or offset its functions; engines and systems included) or a
`file.py` python simulator, as bytes, with their sha256; and the files of a script scenario (the
script, its initialisation file: `scenarios.ScenarioKind.files`). `localized` unpacks them on the worker
into its own cache (`$UQFLIGHT_CACHE`, else `$XDG_CACHE_HOME/uqflight`, else ~/.cache/uqflight),
keyed by the hash, and returns the spec's simulator mapping pointing there. Before a worker
flies, it hashes the aircraft files it is about to load; files that differ from the client's
(a stale or edited copy in its cache) are refused with an `AircraftMismatch`.
"""
from __future__ import annotations

import hashlib
import io
import os
import shutil
import zipfile
from dataclasses import replace
from pathlib import Path

from .aircraft import AircraftFiles, cache_dir
from .scenarios import scenario_entry


class AircraftMismatch(RuntimeError):
    """The worker's aircraft files are not the client's: the worker refuses to fly them."""


def _zip(files: dict[str, bytes]) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as z:
        for key in sorted(files):
            z.writestr(zipfile.ZipInfo(key, date_time=(1980, 1, 1, 0, 0, 0)), files[key])
    return buffer.getvalue()


def _unzip(data: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        return {name: z.read(name) for name in z.namelist()}


def make_bundle(simulator: dict, properties, base: str | Path) -> dict | None:
    """{"kind", "name", "hash", "zip"} for the simulator's files, or None when there is nothing to send."""
    if simulator["kind"] == "jsbsim":
        from .patch import PreparedAircraft

        if "root" in simulator:
            return None
        prepared = PreparedAircraft(simulator.get("aircraft_path", simulator.get("aircraft", "bacm")), Path(base),
                                    properties)
        bundle = {"kind": "aircraft", "name": prepared.name, "hash": prepared.hash, "zip": _zip(prepared.files.files)}
        files = scenario_entry(simulator).files(simulator)  # a script scenario's script and initialisation
        if files:
            bundle["scenario"] = {"hash": AircraftFiles("", files).hash(), "zip": _zip(files)}
        return bundle
    module, _, attribute = str(simulator.get("function", "")).partition(":")
    if module.endswith(".py"):
        file = Path(module) if Path(module).is_absolute() else Path(base) / module
        data = file.read_bytes()
        return {"kind": "python", "name": file.name, "attribute": attribute,
                "hash": hashlib.sha256(data).hexdigest(), "zip": _zip({file.name: data})}
    return None


def localized(spec):
    """The WorkerSpec with its simulator reading the bundle's files from this worker's cache
    (unpacked on first use); raises AircraftMismatch when the files found there differ."""
    bundle = getattr(spec, "bundle", None)
    if not bundle:
        return spec
    simulator = dict(spec.simulator)
    if bundle["kind"] == "aircraft":
        files = AircraftFiles(bundle["name"], _unzip(bundle["zip"]))
        root = files.write_root(cache_dir("aircraft", bundle["hash"][:24]))
        check_aircraft(root, bundle["name"], bundle["hash"])
        simulator.update(root=str(root), aircraft=bundle["name"])
        simulator.pop("aircraft_path", None)
        if bundle.get("scenario"):
            folder = _unpacked(bundle["scenario"], cache_dir("scenario", bundle["scenario"]["hash"][:24]))
            simulator = scenario_entry(simulator).localize(simulator, folder)
    else:
        folder = cache_dir("python", bundle["hash"][:24])
        file = folder / bundle["name"]
        if not file.is_file():
            folder.mkdir(parents=True, exist_ok=True)
            file.write_bytes(_unzip(bundle["zip"])[bundle["name"]])
        if hashlib.sha256(file.read_bytes()).hexdigest() != bundle["hash"]:
            raise AircraftMismatch(f"worker: {file} differs from the client's {bundle['name']} "
                                   f"(sha256 {bundle['hash'][:12]}): refusing to run it; delete {folder}")
        simulator["function"] = f"{file}:{bundle['attribute']}"
    return replace(spec, simulator=simulator, bundle=None)


def _unpacked(files: dict, folder: Path) -> Path:
    """A scenario's files written once into `folder` (all or nothing); AircraftMismatch when the files
    found there do not hash to the client's."""
    if not folder.is_dir():
        tmp = folder.parent / f".{folder.name}.{os.getpid()}.tmp"
        for name, data in _unzip(files["zip"]).items():
            path = (tmp / name).resolve()
            if not path.is_relative_to(tmp.resolve()):
                raise AircraftMismatch(f"worker: the bundle's file {name!r} leads outside its folder")
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
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
