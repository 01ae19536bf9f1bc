"""Perturb any aerodynamic function of an aircraft without editing the aircraft.

A patch `(function, kind)` rewrites the aircraft's `<function name="FUNCTION">BODY</function>` as

    scale:        <product> <property> aero/uq/scale/NAME </property> BODY </product>
    offset_value: <sum> <property> aero/uq/offset_value/NAME </property> BODY </sum>
    offset:       <sum> <product> <property> aero/uq/offset/NAME </property> REFERENCE </product> BODY </sum>

where REFERENCE is the function's reference factor as properties (`aero/qbar-psf`
`metrics/Sw-sqft`, and `metrics/cbarw-ft` or `metrics/bw-ft` for moments; see aero_factors.py):
an `offset` is a coefficient increment ΔC, an `offset_value` a value in the function's own unit
(lbf, lbf·ft, or whatever a helper function outside the axes holds). `offset` on a function
without a reference factor is refused. Several kinds nest in the order scale, offset_value,
offset (the sum around the product), and the new properties are declared in `<aerodynamics>`
with their nominal values (scale 1, offsets 0). NAME is the function's last path component
(`aero/coefficient/CLwbh` -> `aero/uq/scale/CLwbh`), or the whole function name when two
functions share it. JSBSim's product and sum evaluate their arguments left to right, so the
patched function is s * f, v + f and ((o * qbar) * S) [* c̄] + f in floating point.

The patched aircraft is written as a copy (a JSBSim root) in uqflight's cache, keyed by the
hash of its files, the patched text included: a copy patched to other semantics is another
text, so another key. The user's folder is never written.
"""
from __future__ import annotations

import difflib
import xml.etree.ElementTree as ET

from .aircraft import AircraftFiles, aero_functions
from .base import SimulatorSettingError
from .directives import jsbsim_tree
from .aero_factors import AeroFactor, aero_factors

KINDS = ("scale", "offset_value", "offset")  # the order they nest in, innermost first
NOMINAL = {"scale": 1.0, "offset_value": 0.0, "offset": 0.0}
PREFIX = "aero/uq/"


def patch_property(function: str, kind: str, functions: list[str] | None = None) -> str:
    """The property that scales or offsets `function` (`aero/uq/scale/CLwbh`)."""
    short = function.rsplit("/", 1)[-1]
    if functions is not None and sum(f.rsplit("/", 1)[-1] == short for f in functions) > 1:
        short = function
    return f"{PREFIX}{kind}/{short}"


def function_hint(name: str, functions: list[str]) -> str:
    """'; did you mean X or Y?' from the aircraft's function names (full or last component)."""
    by_short = {f.rsplit("/", 1)[-1].lower(): f for f in functions}
    close = difflib.get_close_matches(name.lower(), [f.lower() for f in functions], n=3, cutoff=0.6)
    lowered = {f.lower(): f for f in functions}
    picks = [lowered[c] for c in close]
    if not picks:
        picks = [by_short[c] for c in difflib.get_close_matches(name.rsplit("/", 1)[-1].lower(), by_short, n=3, cutoff=0.6)]
    return f"; did you mean {' or '.join(picks)}?" if picks else ""


def resolve_function(name: str, functions: list[str]) -> str:
    """The aircraft's function `name` names: its full name, or a unique last component."""
    if name in functions:
        return name
    matches = [f for f in functions if f.rsplit("/", 1)[-1] == name]
    if len(matches) == 1:
        return matches[0]
    if len(matches) > 1:
        raise SimulatorSettingError(f"{name!r} names several functions ({', '.join(matches)}): give the full name")
    raise SimulatorSettingError(f"expected one of the aircraft's aerodynamic functions (`uqflight aircraft` lists "
                                f"them), got {name!r}{function_hint(name, functions)}")


def check_perturbation(function: str, kind: str, refs: dict[str, AeroFactor]) -> None:
    """Refuse an unknown kind, and `offset` on a function without a reference factor (naming it)."""
    if kind not in KINDS:
        raise SimulatorSettingError(f"perturbation: expected one of {', '.join(KINDS)}, got {kind!r}")
    ref = refs.get(function)
    if kind == "offset" and ref is not None and ref.refusal:
        unit = f" ({ref.unit})" if ref.unit else ""
        raise SimulatorSettingError(f"an offset is a coefficient increment, added times the function's reference "
                                    f"factor, and {function!r} has none: {ref.refusal}; give perturbation: offset_value "
                                    f"(--offset-value on the command line) to add a value in its own unit{unit}")


def _wrapper(kind: str, prop: str, ref: AeroFactor) -> ET.Element:
    """The element that scales or offsets a function body by `prop` (the body is appended after)."""
    wrapper = ET.Element("product" if kind == "scale" else "sum")
    holder = ET.SubElement(wrapper, "product") if kind == "offset" else wrapper
    for name in (prop, *(ref.factor if kind == "offset" else ())):
        ET.SubElement(holder, "property").text = f" {name} "
    return wrapper


def patch_xml(xml: bytes, patches: list[tuple[str, str]]) -> bytes:
    """The aircraft XML with every (function, kind) patch applied (see the module doc)."""
    tree = ET.ElementTree(jsbsim_tree(xml))
    root = tree.getroot()
    aero = root.find("aerodynamics")
    names = [f.name for f in aero_functions(xml)]
    refs = aero_factors(xml)
    wanted: dict[str, set[str]] = {}
    for function, kind in patches:
        full = resolve_function(function, names)
        check_perturbation(full, kind, refs)
        wanted.setdefault(full, set()).add(kind)
    declared = []
    for element in aero.iter("function"):
        name = (element.get("name") or "").strip()
        if name not in wanted:
            continue
        keep = [c for c in element if c.tag == "description"]
        body = [c for c in element if c.tag != "description"]
        if len(body) != 1:
            raise SimulatorSettingError(f"function {name!r} has {len(body)} top-level elements, expected 1")
        node = body[0]
        for kind in KINDS:  # the product inside the sums: o·qbar·S + (v + s * f)
            if kind in wanted[name]:
                prop = patch_property(name, kind, names)
                wrapper = _wrapper(kind, prop, refs[name])
                wrapper.append(node)
                node = wrapper
                declared.append((prop, NOMINAL[kind]))
        tail = element[-1].tail if len(element) else None
        for child in list(element):
            element.remove(child)
        for child in keep:
            element.append(child)
        node.tail = tail
        element.append(node)
    for i, (prop, value) in enumerate(declared):
        decl = ET.Element("property", value=repr(value))
        decl.text = f" {prop} "
        decl.tail = "\n    "
        aero.insert(i, decl)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)


def patched_files(files: AircraftFiles, patches: list[tuple[str, str]]) -> AircraftFiles:
    """The aircraft's files with its main XML patched (the files themselves when no patch)."""
    if not patches:
        return files
    return files.with_main(patch_xml(files.main, sorted(set(patches))))


def patches_from_properties(properties, functions: list[str], existing=lambda p: False) -> list[tuple[str, str]]:
    """The patches that the properties `aero/uq/KIND/NAME` ask for (KIND one of KINDS;
    properties the aircraft already defines are its own and ask for nothing)."""
    return [patch for prop in properties if not existing(prop)
            for patch in [patch_request(prop, functions)] if patch is not None]


def patch_kind(prop: str) -> str | None:
    """KIND when `prop` is a patch property `aero/uq/KIND/NAME`, else None."""
    return next((kind for kind in KINDS if prop.startswith(f"{PREFIX}{kind}/")), None)


def patch_request(prop: str, functions: list[str]) -> tuple[str, str] | None:
    """(function, kind) when `prop` is a patch property `aero/uq/KIND/NAME`, else None; raises
    SimulatorSettingError when NAME is none of `functions`."""
    kind = patch_kind(prop)
    if kind is None:
        return None
    return resolve_function(prop[len(f"{PREFIX}{kind}/"):], functions), kind


def declared_properties(xml: bytes) -> set[str]:
    """Properties the aircraft declares itself (`<property>` elements anywhere)."""
    return {(e.text or "").strip() for e in jsbsim_tree(xml).iter("property") if e.get("value") is not None}


class PreparedAircraft:
    """The aircraft a simulator flies: its name, the root JSBSim loads it from, its files (patched
    when parameters scale or offset its functions, without the main file's `<input>` and `<output>`
    directives: see directives.py) and their hash. Files changed either way are flown from a copy in
    the cache."""

    def __init__(self, aircraft: str, base=None, properties=(), patches=()):
        from .aircraft import locate

        self.location = locate(aircraft, base)
        original = AircraftFiles.read(self.location)
        self.functions = [f.name for f in aero_functions(original.main)]
        own = declared_properties(original.main)
        self.patches = sorted(set(patches) | set(patches_from_properties(
            properties, self.functions, existing=lambda p: p in own)))
        self.files = patched_files(original, self.patches).without_io()  # JSBSim's input and output directives go
        self.name = self.location.name
        if self.files is not original or not self.location.loadable_from_root:
            self.root = self.files.cached_root()
        else:
            self.root = self.location.root

    @property
    def hash(self) -> str:
        return self.files.hash()
