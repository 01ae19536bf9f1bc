"""What the tests share: paths, the command line, file readers and the closed-form models they check
the numbers against. Test modules import these names (`from conftest import ...`)."""
from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).parent / "data"
CAMPAIGNS = DATA / "campaigns"
UQFLIGHT = str(Path(sys.executable).with_name("uqflight"))


def cli(*args, cwd=None, timeout: float = 300) -> subprocess.CompletedProcess:
    """`uqflight ARGS...` in a fresh process, its output captured."""
    return subprocess.run([UQFLIGHT, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=timeout)


def cli_in_process(*args, cwd=None) -> subprocess.CompletedProcess:
    """`uqflight ARGS...` run in this process (no interpreter start-up: for tests that call the
    command many times); the same exit code, stdout and stderr as `cli`."""
    from typer.testing import CliRunner

    from uqflight.cli.commands import app

    here = os.getcwd()
    try:
        if cwd is not None:
            os.chdir(cwd)
        result = CliRunner().invoke(app, [str(a) for a in args])
    finally:
        os.chdir(here)
    return subprocess.CompletedProcess(list(args), result.exit_code, result.stdout, result.stderr)


@contextlib.contextmanager
def mounted_tmpfs(folder, size: str):
    """A tmpfs of `size` (e.g. "8m") mounted at FOLDER/disk for the block: a disk that fills on demand.
    The test is skipped where it cannot be mounted (it needs root)."""
    mount = Path(folder) / "disk"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(mount)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here ({done.stderr.strip()}); needs root")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)


def scheduler_address(file: Path, tries: int = 600) -> str:
    """The address a `dask scheduler --scheduler-file FILE` writes, once it has written it (0.1 s apart)."""
    import time

    for _ in range(tries):
        if file.exists() and file.stat().st_size:
            break
        time.sleep(0.1)
    return json.loads(file.read_text())["address"]


def read_results(path) -> dict[str, np.ndarray]:
    """Every dataset of a results file (design, status, raw outputs or tSVD factors), by path."""
    found = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda key, item: found.update({key: item[()]}) if isinstance(item, h5py.Dataset) else None)
    return found


def assert_same_results(a, b) -> None:
    """Two results files hold the same datasets, bit for bit."""
    ra, rb = read_results(a), read_results(b)
    assert ra.keys() == rb.keys()
    for key in ra:
        np.testing.assert_array_equal(ra[key], rb[key], err_msg=key)


def _refuse_constant(name: str):
    raise ValueError(f"{name} is not JSON: summary.json must be strict")


def read_summary(path) -> dict:
    """A summary.json (or any JSON the tool writes), read as a strict parser would: NaN, Infinity and
    -Infinity are errors."""
    return json.loads(Path(path).read_text(encoding="utf-8"), parse_constant=_refuse_constant)


def ishigami(xi, a=7.0, b=0.1):
    """Ishigami function of x = πξ, ξ ~ U(−1, 1)³."""
    x = np.pi * np.asarray(xi, dtype=float)
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami_indices(a=7.0, b=0.1) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form first and total Sobol' indices of the Ishigami function."""
    v1 = 0.5 * (1 + b * np.pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = b**2 * np.pi**8 * (1 / 18 - 1 / 50)
    variance = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / variance, np.array([v1 + v13, v2, v13]) / variance


def run_python_campaign(folder: Path, text: str, name: str = "c"):
    """Write the campaign text to FOLDER/NAME.yaml, run it with one worker into FOLDER/NAME.h5, and
    return the results path (python simulators only: quick)."""
    from uqflight.campaign import load_campaign
    from uqflight.running.runner import run_campaign

    source = Path(folder) / f"{name}.yaml"
    source.write_text(text, encoding="utf-8")
    out = Path(folder) / f"{name}.h5"
    run_campaign(load_campaign(source), out=out, workers=1)
    return out


DECAY_TWO_INPUTS = """
name: decay-people
seed: 3
simulator: {kind: python, function: "uqflight.simulators.models:exp_decay"}
parameters:
  a: {distribution: normal, lower: 0.5, upper: 1.5}
  b: {distribution: uniform, lower: 1.0, upper: 2.0, nominal: 1.4}
design: {kind: sparse_grid, level: 3}
method: {kind: pseudo_galerkin, order: 2}
analysis: {band_samples: 500, bootstrap: 0}
"""


@pytest.fixture(scope="session")
def decay_results(tmp_path_factory) -> Path:
    """The DECAY_TWO_INPUTS campaign flown once per session into its own folder (decay.yaml, decay.h5):
    tests read it and write elsewhere (a test that writes beside it copies it first)."""
    from uqflight.campaign import parse_campaign
    from uqflight.running.runner import run_campaign

    root = tmp_path_factory.mktemp("decay")
    (root / "decay.yaml").write_text(DECAY_TWO_INPUTS)
    path = root / "decay.h5"
    run_campaign(parse_campaign(DECAY_TWO_INPUTS, str(root / "decay.yaml")), out=path, workers=1)
    return path


def hostile_campaign_text(function, samples=40, chunk=8, workers=1, extra="", name="hostile"):
    """A Monte Carlo campaign over x ~ U(-2, 2) of a model of data/hostile_model.py that misbehaves on
    purpose (crashing, hanging, slow, long_histories)."""
    return f"""
name: {name}
seed: 5
simulator: {{kind: python, function: "{DATA / 'hostile_model.py'}:{function}"}}
parameters:
  x: {{distribution: uniform, lower: -2, upper: 2}}
design: {{kind: monte_carlo, samples: {samples}}}
execution: {{workers: {workers}, chunk: {chunk}{extra}}}
"""


def hostile_campaign(function, **kwargs):
    """hostile_campaign_text parsed (as if from data/hostile.yaml)."""
    from uqflight.campaign import parse_campaign

    return parse_campaign(hostile_campaign_text(function, **kwargs), str(DATA / "hostile.yaml"))


CLOSED_FORMS = DATA / "trust_models.py"
NORMAL_2D = ("  x1: {distribution: normal, lower: -3, upper: 3}\n"
             "  x2: {distribution: normal, lower: -3, upper: 3}\n")
UNIFORM_X = "  x: {distribution: uniform, lower: -1, upper: 1}\n"
NORMAL_X = "  x: {distribution: normal, lower: -3, upper: 3}\n"


def closed_form_campaign(name, function, parameters, design, method="", extra=""):
    """The text of a campaign of a closed-form model of data/trust_models.py (`parameters`: YAML lines such
    as NORMAL_2D; `method`, `extra`: whole lines)."""
    return (f"name: {name}\nseed: 5\nsimulator: {{kind: python, function: \"{CLOSED_FORMS}:{function}\"}}\n"
            f"parameters:\n{parameters}design: {design}\n{method}{extra}"
            "analysis: {band_samples: 2000, bootstrap: 0}\n")


def strict_json(data: dict) -> dict:
    """`data` through a strict JSON writer and reader, as summary.json is written and read."""
    return json.loads(json.dumps(data, allow_nan=False))


@pytest.fixture(scope="session")
def flown(tmp_path_factory):
    """fly(TEXT, NAME): the results file of a python campaign's TEXT, flown once per session (and xdist
    worker) into a folder of its own, for the tests of several modules that only read it."""
    files = {}

    def fly(text: str, name: str = "c") -> Path:
        if text not in files:
            files[text] = run_python_campaign(tmp_path_factory.mktemp(name), text, name)
        return files[text]

    return fly
