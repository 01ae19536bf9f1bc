"""What JSBSim does with the names in the files it reads: checked as JSBSim reads them, and its
input and output directives removed before it reads them.

JSBSim 1.3 reads element names as written, without XML namespaces (its expat parser has no
namespace processing), and skips an entity defined in another file. In the files it reads it
- reads the file any `file=` attribute names (FGModelLoader::Open: a metrics, aerodynamics,
  system, engine, thruster, planet, input or output element; an absolute path as it is);
- writes the file an `<output name=...>` names (types CSV and TABULAR, at `run_ic`: an absolute
  path as it is, a relative one below its output path), and connects to the host and port of an
  output of type SOCKET or FLIGHTGEAR (FGOutput, FGOutputSocket, FGfdmSocket);
- listens on the port of an `<input port=...>` (FGInput, FGInputSocket: a telnet server) or
  receives on it (type QTJSBSIM);
- loads a `<child name=NAME>` aircraft from the root's `aircraft/NAME/NAME.xml` (FGFDMExec::ReadChild);
- writes `NAME_lin.sce` in the working directory when a script event or a component sets
  `simulation/do_linearization` (FGFDMExec::DoLinearization), and `initfile.T.xml` below its output
  path for `simulation/write-state-file` (FGPropagate::WriteStateFile).

`jsbsim_tree` reads a file as JSBSim does: element and attribute names as written, a default
namespace ignored and a prefix kept (`<p:event>` is no event to JSBSim), so that what uqflight finds
in a file (the aerodynamic functions, the trim events) is what JSBSim finds, and a file it writes back
(`ElementTree.tostring`) names its elements as the original did. `checked` refuses a file Python's parser cannot read (JSBSim's may still read it, and what it
holds would go unchecked), a `file=` or output file name leading out of its folder, and a mention
of `simulation/do_linearization`; element names are compared without their namespace. A
`<child>` is the caller's to refuse (only an aircraft's main file has one). `without_io` removes
the `<input>` and `<output>` directives of an aircraft's main file or a script (the elements
JSBSim reads as directives: the document's own children), so that JSBSim writes, connects to and
listens on nothing whatever they name; the flights set JSBSim's output path to os.devnull, below
which no state file can be created.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from xml.parsers import expat

from ..text.console import one_line
from .safe_paths import relative_name

IO_DIRECTIVES = ("input", "output")
NETWORK_OUTPUTS = ("SOCKET", "FLIGHTGEAR")  # `<output type=...>` whose name is a host, not a file
LINEARIZATION = "do_linearization"  # simulation/do_linearization: JSBSim writes NAME_lin.sce in the working directory


def local_name(tag) -> str:
    """An element's name without a namespace or a prefix (the checks take `<p:output>` for an output too)."""
    return tag.rsplit("}", 1)[-1].rsplit(":", 1)[-1] if isinstance(tag, str) else ""


def jsbsim_tree(data: bytes) -> ET.Element:
    """The document's root element with its names as JSBSim reads them (expat without namespace
    processing: `xmlns` attributes are attributes, a prefix is part of the name)."""
    builder = ET.TreeBuilder()
    parser = expat.ParserCreate()
    parser.buffer_text = True
    parser.StartElementHandler = builder.start
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    parser.Parse(data, True)
    return builder.close()


def parsed(data: bytes, file, error: type[Exception]) -> ET.Element:
    """The document's root element as JSBSim reads it (`jsbsim_tree`); `error` naming `file` when
    Python's parser cannot read it."""
    try:
        ET.fromstring(data)  # refuses what JSBSim would skip unread: an entity defined in another file
        return jsbsim_tree(data)
    except (ET.ParseError, expat.ExpatError) as exc:
        raise error(f"{file} is not well-formed XML ({exc}): uqflight checks every file JSBSim may read and "
                    "cannot check this one (an entity defined in another file, a prefix without its namespace); "
                    "fix it (or move it out of the folder, if JSBSim does not need it)") from None


def checked(root: ET.Element, file, error: type[Exception], inside: str) -> list[tuple[str, str]]:
    """(element name, file= value) of every element naming a file, once every name in the document
    stays where it is read from: `error` naming `file`, the element and the attribute otherwise
    (`inside` says where, e.g. "the script's folder"). The name of an `<output>` that writes a
    file is checked too, and no text or attribute may mention simulation/do_linearization."""
    names = []
    for element in root.iter():
        tag = local_name(element.tag)
        attributes = ["file"]
        if tag == "output" and (element.get("type") or "").upper() not in NETWORK_OUTPUTS:
            attributes.append("name")
        for attribute in attributes:
            value = element.get(attribute)
            if value is not None and relative_name(value) is None:
                raise error(f'{file}: <{tag} {attribute}="{one_line(value)}">: expected a path relative to {inside}, without '
                            "/ at the start, .. leading out of it, a drive or a backslash; uqflight neither reads "
                            "nor copies a file outside them, nor lets JSBSim write one")
        for text in (element.text, *element.attrib.values()):
            if text and LINEARIZATION in text:
                raise error(f"{file}: <{tag}> names simulation/{LINEARIZATION}: JSBSim would run a linearization and "
                            "write NAME_lin.sce in the working directory; uqflight does not fly it: remove it")
        if element.get("file") is not None:
            names.append((tag, element.get("file")))
    return names


def without_io(data: bytes) -> bytes | None:
    """The document without its own `<input>` and `<output>` children (namespace or prefix or not), its
    other names as written; None when it has none (the file then goes to JSBSim as it is)."""
    root = jsbsim_tree(data)
    directives = [child for child in root if local_name(child.tag) in IO_DIRECTIVES]
    if not directives:
        return None
    for child in directives:
        root.remove(child)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)
