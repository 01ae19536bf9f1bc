"""Names that come from files never lead outside their folder (issue 22, items 1, 6 and bundles).

Every hostile name is aimed at a sentinel folder next to the cache (`home/` holds only `cache/`);
each test checks that nothing was written outside the cache and that the refusal says why. Real
files, real JSBSim, real worker processes."""
import io
import os
import re
import shutil
import zipfile
from pathlib import Path

import jsbsim
import numpy as np
import pytest
from conftest import cli_in_process

from uqflight.running.runner import Task, WorkerError, WorkerPool
from uqflight.simulators.aircraft import (MAX_BYTES, MAX_FILES, AircraftFiles, AircraftLocation, AircraftUnsafe,
                                          cache_dir, jsbsim_root, locate, unsafe_key)
from uqflight.simulators.bundle import BundleRefused, _unzip, _zip
from uqflight.simulators.kinds import localized, make_bundle
from uqflight.simulators.jsbsim import quiet_jsbsim
from uqflight.simulators.spec import SimulatorSpec
from uqflight.running.worker import WorkerSpec

BACM = Path(__file__).resolve().parents[1] / "uqflight" / "aircraft" / "bacm"
TRAVERSAL = {  # (tag, the text it replaces in bacm.xml, or None to add the element before </fdm_config>)
    "autopilot": None, "system": None,
    "engine": '<engine file="PW119B">', "thruster": '<thruster file="HD-E6C">'}


@pytest.fixture
def home(tmp_path, monkeypatch):
    """The sentinel folder `home/`, holding only the cache `home/cache` ($UQFLIGHT_CACHE)."""
    monkeypatch.setenv("UQFLIGHT_CACHE", str(tmp_path / "home" / "cache"))
    (tmp_path / "home" / "cache").mkdir(parents=True)
    return tmp_path / "home"


def files_outside_cache(tmp_path: Path) -> dict[str, bytes]:
    cache = tmp_path / "home" / "cache"
    return {p.relative_to(tmp_path).as_posix(): p.read_bytes() for p in tmp_path.rglob("*")
            if p.is_file() and cache not in p.parents}


def assert_nothing_outside_the_cache(tmp_path: Path, before: dict[str, bytes]) -> None:
    assert sorted(os.listdir(tmp_path / "home")) == ["cache"]
    assert files_outside_cache(tmp_path) == before


def plan_refused(tmp_path: Path, aircraft: str, parameter: str) -> str:
    """`uqflight plan` of a campaign flying `aircraft` with one parameter: exit 2, nothing written
    outside the cache; its stderr."""
    (tmp_path / "c.yaml").write_text(
        f"name: hostile\nsimulator: {{kind: jsbsim, aircraft: {aircraft}, duration_s: 2}}\n"
        f"parameters:\n  CL: {parameter}, distribution: normal, interval_pct: 10}}\n"
        "design: {kind: monte_carlo, samples: 4}\n")
    before = files_outside_cache(tmp_path)
    result = cli_in_process("plan", tmp_path / "c.yaml")
    assert result.returncode == 2, result.stdout + result.stderr
    assert_nothing_outside_the_cache(tmp_path, before)
    return result.stderr


def cache_holds(home: Path, text: bytes) -> bool:
    return any(text in p.read_bytes() for p in (home / "cache").rglob("*") if p.is_file())


# -- XML file= attributes ------------------------------------------------------------------
@pytest.mark.parametrize("tag", list(TRAVERSAL))
def test_a_file_attribute_leading_out_of_the_folder_is_refused_and_nothing_is_written(tag, tmp_path, home):
    """The root's engine/ and systems/ are 6 levels below tmp_path, the aircraft folder 7, the cache's
    temporary root's engine/ and systems/ 5: `../` x 4 + home/payload.xml reaches r1/r2/home/ from
    the root, r1/r2/r3/home/ from the aircraft folder (both hold a payload JSBSim loads), and
    home/home/ from the cache (before the fix, `plan` wrote the payload there)."""
    root = tmp_path / "r1" / "r2" / "r3" / "r4" / "root"
    folder = root / "aircraft" / "evil"
    shutil.copytree(BACM, folder)
    (root / "engine").mkdir()
    (root / "systems").mkdir()
    payload = {"engine": (BACM / "Engines" / "PW119B.xml").read_bytes(),
               "thruster": (BACM / "Engines" / "HD-E6C.xml").read_bytes()}.get(tag, f'<{tag} name="payload"/>'.encode())
    for where in (tmp_path / "r1" / "r2" / "home", tmp_path / "r1" / "r2" / "r3" / "home"):
        where.mkdir()
        (where / "payload.xml").write_bytes(payload)
    name = "../" * 4 + "home/payload.xml"
    xml = (folder / "bacm.xml").read_text()
    (folder / "bacm.xml").unlink()
    element = TRAVERSAL[tag]
    if element is None:
        xml = xml.replace("</fdm_config>", f'<{tag} file="{name}"/>\n</fdm_config>')
    else:
        xml = xml.replace(element, element.replace(element.split('"')[1], name), 1)
    (folder / "evil.xml").write_text(xml)
    stderr = plan_refused(tmp_path, "r1/r2/r3/r4/root/aircraft/evil",
                          "{function: aero/coefficient/CL-total, perturbation: scale")
    assert f'{folder / "evil.xml"}: <{tag} file="{name}">' in stderr
    assert "uqflight neither reads nor copies a file outside them" in stderr
    assert not cache_holds(home, b"payload")


@pytest.mark.parametrize("name", ["/etc/hostname", "Engines/../../x", "C:engine", "a\\..\\..\\x"])
def test_absolute_drive_and_backslash_names_are_refused_too(name, tmp_path, home):
    folder = tmp_path / "planes" / "odd"
    shutil.copytree(BACM, folder)
    xml = (folder / "bacm.xml").read_text().replace("</fdm_config>", f'<system file="{name}"/></fdm_config>')
    (folder / "bacm.xml").unlink()
    (folder / "odd.xml").write_text(xml)
    with pytest.raises(AircraftUnsafe, match=re.escape(f'odd.xml: <system file="{name}">')):
        AircraftFiles.read(locate(folder))


def test_an_output_directive_writing_outside_is_refused(tmp_path, home):
    """JSBSim writes an aircraft's `<output name=FILE type="CSV">` itself, at any absolute path."""
    folder = tmp_path / "planes" / "chatty"
    shutil.copytree(BACM, folder)
    (folder / "bacm.xml").rename(folder / "chatty.xml")
    written = home / "written.csv"
    xml = (folder / "chatty.xml").read_text().replace(
        "</fdm_config>", f'<output name="{written}" type="CSV" rate="1"><property>velocities/vt-fps</property>'
        "</output></fdm_config>")
    (folder / "chatty.xml").write_text(xml)
    stderr = plan_refused(tmp_path, "planes/chatty", "{property: aero/uq/CL0")
    assert f'chatty.xml: <output name="{written}">' in stderr and "nor lets JSBSim write one" in stderr


# -- symbolic links --------------------------------------------------------------------------
@pytest.mark.parametrize("link", ["Engines/PW119B.xml", "Engines"])
def test_a_symlink_leaving_the_aircraft_folder_is_refused_and_not_copied(link, tmp_path, home):
    folder = tmp_path / "planes" / "linky"
    shutil.copytree(BACM, folder)
    (folder / "bacm.xml").rename(folder / "linky.xml")
    outside = tmp_path / "outside"
    shutil.copytree(BACM / "Engines", outside / "Engines")
    engine = outside / "Engines" / "PW119B.xml"
    engine.write_bytes(b"<!-- secret -->" + engine.read_bytes())
    target = outside / link
    path = folder / link
    shutil.rmtree(path) if path.is_dir() else path.unlink()
    path.symlink_to(target)
    stderr = plan_refused(tmp_path, "planes/linky", "{property: aero/uq/CL0")
    assert f"{path} is a symbolic link to {target}, outside the aircraft folder" in stderr
    with pytest.raises(AircraftUnsafe, match="symbolic link"):
        make_bundle(SimulatorSpec("jsbsim", {"aircraft": "planes/linky"}), (), tmp_path)
    assert not cache_holds(home, b"secret")


def test_a_symlink_that_stays_in_the_folder_is_read(tmp_path, home):
    folder = tmp_path / "planes" / "alias"
    shutil.copytree(BACM, folder)
    (folder / "bacm.xml").rename(folder / "alias.xml")
    (folder / "Engines" / "same.xml").symlink_to("PW119B.xml")
    (folder / "loop").symlink_to(".")  # a loop, walked once
    files = AircraftFiles.read(locate(folder)).files
    assert files["Engines/same.xml"] == files["Engines/PW119B.xml"]
    assert not any(key.startswith("loop/loop/") for key in files)


# -- bundles on the worker --------------------------------------------------------------------
def _c172p_bundle(extra: dict[str, bytes] = {}, **fields) -> dict:
    files = {**AircraftFiles.read(locate("c172p")).files, **extra}
    bundle = {"kind": "aircraft", "name": "c172p", "hash": AircraftFiles("c172p", files).hash(), "zip": _zip(files)}
    return {**bundle, **fields}


def _spec(bundle: dict, simulator=None) -> WorkerSpec:
    return WorkerSpec(simulator=simulator or SimulatorSpec("jsbsim", {"aircraft": "c172p"}), parameter_names=(),
                      properties=(), base="/", bundle=bundle)


def hostile_bundles(home: Path) -> dict[str, tuple[dict, str]]:
    """Each hostile bundle aimed at home/ (outside the cache), and the refusal it must meet."""
    python = {"kind": "python", "attribute": "f", "hash": "0" * 64}
    return {
        "traversal key": (_c172p_bundle({"../../../../../trav1.xml": b"<x/>"}),
                          "file '../../../../../trav1.xml': expected a relative path"),
        "@root//abs key": (_c172p_bundle({f"@root/{home}/abs.xml": b"<x/>"}),
                           f"file '@root/{home}/abs.xml': expected a relative path"),
        "hash ../../..": (_c172p_bundle(hash="../../.."), "hash '../../..': expected 64 lowercase hexadecimal"),
        "python module /abs/x.py": ({**python, "name": str(home / "x.py"), "zip": _zip({str(home / "x.py"): b"1"})},
                                    f"name '{home / 'x.py'}': expected a single file name ending in .py"),
    }


@pytest.mark.parametrize("case", ["traversal key", "@root//abs key", "hash ../../..", "python module /abs/x.py"])
def test_a_hostile_bundle_is_refused_before_anything_is_unpacked(case, tmp_path, home):
    bundle, message = hostile_bundles(home)[case]
    before = files_outside_cache(tmp_path)
    with pytest.raises(BundleRefused, match="refusing the client's bundle, nothing unpacked") as refused:
        localized(_spec(bundle))
    assert message in str(refused.value)
    assert_nothing_outside_the_cache(tmp_path, before)
    assert not (home / "cache" / "aircraft").exists() and not (home / "cache" / "python").exists()


def test_a_worker_process_refuses_the_bundle_and_the_runner_reports_it(tmp_path, home):
    """Through a real `python -m uqflight.running.worker` process: the refusal reaches the runner as a
    WorkerError (which `run` turns into exit 2), and the worker wrote nothing outside its cache."""
    bundle, message = hostile_bundles(home)["traversal key"]
    before = files_outside_cache(tmp_path)
    pool = WorkerPool(_spec(bundle), 1, 60.0)
    try:
        with pytest.raises(WorkerError, match="BundleRefused: worker: refusing the client's bundle") as refused:
            list(pool.run([Task(np.arange(1), np.zeros((1, 0)))], 11, ["alpha_deg"]))
    finally:
        pool.close()
    assert message in str(refused.value)
    assert_nothing_outside_the_cache(tmp_path, before)


def test_a_worker_refuses_to_fly_bundled_xml_whose_file_attribute_leads_out(tmp_path, home):
    """Keys inside the cache, but the main XML names a file outside it: the worker's check of the
    unpacked aircraft refuses it before JSBSim could read that file."""
    files = AircraftFiles.read(locate("c172p")).files
    main = files["c172p.xml"].replace(b"</fdm_config>", b'<system file="../../../../../../x"/></fdm_config>')
    bundle = _c172p_bundle({"c172p.xml": main})
    with pytest.raises(AircraftUnsafe, match=re.escape('c172p.xml: <system file="../../../../../../x">')):
        localized(_spec(bundle))


@pytest.mark.slow
def test_a_dask_worker_refuses_the_bundle_and_the_client_gets_the_error(tmp_path, home):
    """The same through Dask (a LocalCluster of worker processes): the client's `run` gets the
    WorkerError (exit 2), and nothing was written outside the cache."""
    from uqflight.running.runner import _execute_dask

    bundle, message = hostile_bundles(home)["@root//abs key"]
    before = files_outside_cache(tmp_path)
    chunks = _execute_dask([Task(np.arange(1), np.zeros((1, 0)))], _spec(bundle), 11, ["alpha_deg"], 1, None, 60.0)
    with pytest.raises(WorkerError, match="BundleRefused: worker: refusing the client's bundle") as refused:
        list(chunks)
    assert message in str(refused.value)
    assert_nothing_outside_the_cache(tmp_path, before)


def _bomb(size: int) -> bytes:
    """A zip of the c172p files plus one file of `size` zero bytes, written in 1 MiB pieces."""
    info = zipfile.ZipInfo("Systems/bomb.xml", date_time=(1980, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_DEFLATED
    buffer = io.BytesIO(_zip(AircraftFiles.read(locate("c172p")).files))
    with zipfile.ZipFile(buffer, "a") as z, z.open(info, "w") as out:
        for start in range(0, size, 2**20):
            out.write(bytes(min(2**20, size - start)))
    return buffer.getvalue()


def test_a_zip_bomb_is_refused_from_its_declared_size_before_unpacking(tmp_path, home):
    data = _bomb(MAX_BYTES + 1)
    assert len(data) < MAX_BYTES / 500  # about 65 kB that would unpack to 64 MiB
    with pytest.raises(BundleRefused, match=f"bytes uncompressed, more than {MAX_BYTES}"):
        localized(_spec({"kind": "aircraft", "name": "c172p", "hash": "0" * 64, "zip": data}))
    many = _zip({f"Systems/f{i}.xml": b"" for i in range(MAX_FILES + 1)})
    with pytest.raises(BundleRefused, match=f"{MAX_FILES + 1} files, more than {MAX_FILES}"):
        localized(_spec({"kind": "aircraft", "name": "c172p", "hash": "0" * 64, "zip": many}))
    assert list((home / "cache").iterdir()) == []


def test_cache_keys_are_single_names(home):
    for key in ("../x", "/abs", "a/b", "..", ""):
        with pytest.raises(ValueError, match="cache key"):
            cache_dir("aircraft", key)


# -- the hash ---------------------------------------------------------------------------------
def test_names_and_contents_no_longer_run_together_in_the_hash():
    one = AircraftFiles("A", {"A.xml": b"<a/>B.xml<b/>"})
    two = AircraftFiles("A", {"A.xml": b"<a/>", "B.xml": b"<b/>"})
    assert one.hash() != two.hash()
    assert AircraftFiles("A", {"A.xml": b"<a/>"}).hash() != AircraftFiles("A", {"A.xm": b"l<a/>"}).hash()


# -- what legitimate aircraft keep -----------------------------------------------------------
def test_every_stock_jsbsim_aircraft_reads_and_passes_the_workers_checks():
    names = sorted(p.name for p in (jsbsim_root() / "aircraft").iterdir() if (p / f"{p.name}.xml").is_file())
    assert len(names) > 50
    for name in names:
        files = AircraftFiles.read(AircraftLocation(name, jsbsim_root() / "aircraft" / name, jsbsim_root(), "jsbsim"))
        assert _unzip(_zip(files.files), unsafe_key) == files.files, name


@pytest.mark.parametrize("aircraft", ["c172p", "737", "f16"])
def test_stock_aircraft_unpack_on_a_worker_compressed_and_load_in_jsbsim(aircraft, tmp_path, home):
    simulator = SimulatorSpec("jsbsim", {"aircraft": aircraft})
    bundle = make_bundle(simulator, ("aero/uq/scale/CLwbh",) if aircraft == "c172p" else (), tmp_path)
    with zipfile.ZipFile(io.BytesIO(bundle["zip"])) as z:
        infos = z.infolist()
    assert all(info.compress_type == zipfile.ZIP_DEFLATED for info in infos)
    assert len(bundle["zip"]) < 0.5 * sum(info.file_size for info in infos)  # XML deflates 3-10x
    root = Path(localized(_spec(bundle, simulator)).simulator.root)
    assert root.parent == home / "cache" / "aircraft"
    quiet_jsbsim()
    fdm = jsbsim.FGFDMExec(str(root))
    fdm.set_debug_level(0)
    assert fdm.load_model(aircraft)
