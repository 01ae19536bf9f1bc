"""`run --executor dask` over TLS, as docs/security.md says: a `tls://` scheduler address,
and the client's certificates from dask's own configuration (`distributed.comm.tls.*`, here through
its environment variables), which dask's Client reads when given no security of its own. A
separately started scheduler and worker that require TLS; a client without the certificates cannot
connect. Real processes, real certificates (openssl)."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import UQFLIGHT, assert_same_results, scheduler_address

BIN = Path(sys.executable).parent
CAMPAIGN = """
name: tls
simulator: {kind: python, function: "uqflight.simulators.models:ishigami"}
parameters:
  x1: {distribution: uniform, lower: -3.14159, upper: 3.14159}
  x2: {distribution: uniform, lower: -3.14159, upper: 3.14159}
  x3: {distribution: uniform, lower: -3.14159, upper: 3.14159}
design: {kind: monte_carlo, samples: 24}
execution: {workers: 1, chunk: 4}
"""


@pytest.fixture
def tls_cluster(tmp_path):
    if shutil.which("openssl") is None:
        pytest.skip("openssl is needed to make the test's certificates")
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", str(key), "-out", str(cert),
                    "-days", "1", "-subj", "/CN=uqflight-test"], check=True, capture_output=True)
    tls = ["--tls-ca-file", str(cert), "--tls-cert", str(cert), "--tls-key", str(key)]
    file = tmp_path / "scheduler.json"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "cwd": tmp_path}
    procs = [subprocess.Popen([str(BIN / "dask"), "scheduler", "--protocol", "tls", "--host", "127.0.0.1", "--port", "0",
                               "--no-dashboard", "--scheduler-file", str(file), *tls], **quiet)]
    try:
        address = scheduler_address(file)
        assert address.startswith("tls://")
        procs.append(subprocess.Popen([str(BIN / "dask"), "worker", address, "--nworkers", "1", "--nthreads", "1",
                                       "--no-dashboard", *tls], **quiet))
        yield address, {"DASK_DISTRIBUTED__COMM__TLS__CA_FILE": str(cert),
                        "DASK_DISTRIBUTED__COMM__TLS__CLIENT__CERT": str(cert),
                        "DASK_DISTRIBUTED__COMM__TLS__CLIENT__KEY": str(key)}
    finally:
        for p in reversed(procs):
            p.terminate()
            p.wait(timeout=30)


@pytest.mark.slow
def test_run_on_a_tls_scheduler_with_dask_config_certificates(tls_cluster, tmp_path):
    address, certificates = tls_cluster
    campaign = tmp_path / "c.yaml"
    campaign.write_text(CAMPAIGN)
    env = {**os.environ, **certificates}
    remote = subprocess.run([UQFLIGHT, "run", str(campaign), "--out", str(tmp_path / "tls.h5"), "--executor", "dask",
                             "--scheduler", address], env=env, capture_output=True, text=True, timeout=300)
    assert remote.returncode == 0, remote.stderr
    local = subprocess.run([UQFLIGHT, "run", str(campaign), "--out", str(tmp_path / "local.h5")],
                           capture_output=True, text=True, timeout=300)
    assert local.returncode == 0, local.stderr
    assert_same_results(tmp_path / "tls.h5", tmp_path / "local.h5")
    # without the certificates the client cannot talk to the scheduler: nothing runs
    bare = {k: v for k, v in os.environ.items() if not k.startswith("DASK_DISTRIBUTED__COMM__TLS")}
    refused = subprocess.run([UQFLIGHT, "run", str(campaign), "--out", str(tmp_path / "bare.h5"), "--executor", "dask",
                              "--scheduler", address], env={**bare, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "5s"},
                             capture_output=True, text=True, timeout=300)
    assert refused.returncode != 0
