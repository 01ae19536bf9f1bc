"""Engine set-up before every trim, per JSBSim engine kind.

JSBSim's engines need different care to give a steady, repeatable trimmed flight:
- every kind: fuel frozen (`propulsion/fuel_freeze`; fuel burn alone drifts ~1-2 ft in 50 s) and
  `propulsion/set-running` = -1 after every reset (a reset stops the engines; a stopped engine
  still "trims" and then sinks);
- piston: mixture full rich and magnetos on both (`fcs/mixture-cmd-norm[i]` = 1,
  `propulsion/magneto_cmd` = 3), propeller advance fine (`fcs/advance-cmd-norm[i]` = 1);
- turboprop (and any engine with a propeller): advance 1 (governor at its highest rpm); the
  engines are brought to steady state after the trim (`get_steady_state`, done by the trim),
  because the turboprop makes no power during the trim's evaluations (see the notes);
- turbine (jets): nothing but the above; the trim stays out of the afterburner range (throttle < 1);
- electric: nothing but the above.
"""
from __future__ import annotations

from pathlib import Path

from .directives import jsbsim_tree

KINDS = ("piston", "turbine", "turboprop", "electric", "rocket")
_KIND_CACHE: dict[str, list[tuple[str, str, str]]] = {}


def engine_file(fdm, name: str) -> Path | None:
    """The engine or thruster file JSBSim would load for `name` (aircraft's Engines/, then engine/)."""
    file = name if name.endswith(".xml") else name + ".xml"
    aircraft = Path(fdm.get_full_aircraft_path())
    for candidate in (aircraft / "Engines" / file, aircraft / file, Path(fdm.get_engine_path()) / file):
        if candidate.is_file():
            return candidate
    return None


def engine_kinds(fdm) -> list[tuple[str, str, str]]:
    """(engine name, kind, thruster kind) per engine of the loaded aircraft, e.g.
    ("eng_io320", "piston", "propeller")."""
    aircraft = Path(fdm.get_full_aircraft_path())
    main = aircraft / f"{fdm.get_model_name()}.xml" if hasattr(fdm, "get_model_name") else None
    if main is None or not main.is_file():
        candidates = sorted(aircraft.glob("*.xml"), key=lambda p: p.stem != aircraft.name)
        main = candidates[0]
    key = str(main)
    if key not in _KIND_CACHE:
        found = []
        for engine in jsbsim_tree(main.read_bytes()).iter("engine"):
            name = engine.get("file", "")
            kind = thruster_kind = "unknown"
            path = engine_file(fdm, name)
            if path is not None:
                kind = jsbsim_tree(path.read_bytes()).tag.removesuffix("_engine")
            thruster = engine.find("thruster")
            if thruster is not None and thruster.get("file"):
                tpath = engine_file(fdm, thruster.get("file"))
                if tpath is not None:
                    thruster_kind = jsbsim_tree(Path(tpath).read_bytes()).tag
            found.append((name, kind, thruster_kind))
        _KIND_CACHE[key] = found
    return _KIND_CACHE[key]


def prepare_engines(fdm, settle: bool = True) -> None:
    """Engines ready for the trim, after the reset and the sample's settings (see the module doc).
    `settle`: `propulsion/set-running` = -1, which also brings them to their steady state; otherwise
    each engine is only set running (the Newton trim runs its own steady states)."""
    kinds = engine_kinds(fdm)
    fdm["propulsion/fuel_freeze"] = 1
    for i, (_, kind, thruster) in enumerate(kinds):
        if thruster == "propeller":
            fdm[f"fcs/advance-cmd-norm[{i}]"] = 1.0
        if kind == "piston":
            fdm[f"fcs/mixture-cmd-norm[{i}]"] = 1.0
    if any(kind == "piston" for _, kind, _ in kinds):
        fdm["propulsion/magneto_cmd"] = 3
    if settle:
        fdm["propulsion/set-running"] = -1
    else:
        for i in range(len(kinds)):
            fdm[f"propulsion/engine[{i}]/set-running"] = 1
