"""Workers that share no disk with the client: separately started Dask scheduler and workers
(loopback, another working directory, their own cache) get the patched aircraft with the task,
give bit-identical results to the local pool, and refuse other aircraft files."""
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import scheduler_address

from uqflight.campaign import load_campaign
from uqflight.running.runner import run_campaign, worker_spec
from uqflight.simulators.aircraft_properties import AircraftProperties

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


@pytest.fixture
def cluster(tmp_path):
    """A scheduler and one single-process worker, started as separate processes."""
    where = tmp_path / "elsewhere"
    where.mkdir()
    env = {**os.environ, "UQFLIGHT_CACHE": str(tmp_path / "worker-cache")}
    file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", "0",
                               "--no-dashboard", "--scheduler-file", str(file)], cwd=where, env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        address = scheduler_address(file, 300)
        procs.append(subprocess.Popen([str(BIN / "dask"), "worker", address, "--nworkers", "1", "--nthreads", "1",
                                       "--no-dashboard"], cwd=where, env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from dask.distributed import Client

        with Client(address) as client:
            client.wait_for_workers(1, timeout=60)
        yield address, tmp_path / "worker-cache"
    finally:
        for p in reversed(procs):
            p.terminate()
            p.wait(timeout=30)


def _outputs(path):
    with h5py.File(path, "r") as f:
        return f["samples/status"][:], {k: f[f"outputs/{k}"][:] for k in f["outputs"]}, f.attrs["aircraft_hash"]


@pytest.mark.slow
def test_separate_dask_workers_match_the_local_pool_and_refuse_other_aircraft(cluster, tmp_path, monkeypatch):
    monkeypatch.setenv("UQFLIGHT_CACHE", str(tmp_path / "client-cache"))
    address, worker_cache = cluster
    campaign = load_campaign(REPO / "campaigns" / "c172p-scale-l2.yaml", read_aircraft=AircraftProperties)
    local = run_campaign(campaign, out=tmp_path / "local.h5", workers=2, executor="local")
    remote = run_campaign(campaign, out=tmp_path / "dask.h5", workers=1, executor="dask", scheduler=address)
    status_l, out_l, hash_l = _outputs(local.path)
    status_d, out_d, hash_d = _outputs(remote.path)
    assert np.all(status_l == 0) and np.all(status_d == 0) and hash_l == hash_d
    for name in out_l:
        np.testing.assert_array_equal(out_d[name], out_l[name])  # bit-identical
    # the worker unpacked the patched aircraft in its own cache; tamper with it: refused
    spec = worker_spec(campaign)
    root = worker_cache / "aircraft" / spec.bundle["hash"][:24]
    main = root / "aircraft" / "c172p" / "c172p.xml"
    assert main.is_file()
    main.write_bytes(main.read_bytes().replace(b"</fdm_config>", b"<!-- edited --></fdm_config>"))
    with pytest.raises(Exception, match="refusing to fly another aircraft"):
        run_campaign(campaign, out=tmp_path / "refused.h5", workers=1, executor="dask", scheduler=address)
