"""A real distributed run: a Dask scheduler and two worker processes started with Dask's own command line
(``dask scheduler``, ``dask worker``) on loopback, a campaign run on them through the CLI's ``--dask ADDRESS``
and through ``swarm.campaign.run(..., dask=...)``, row for row equal to the process pool's.

The cluster is secured as docs/security.md asks of a cluster given by address: TLS with a throw-away
certificate (files readable only by us), given to the CLI through Dask's own ``DASK_DISTRIBUTED__COMM__TLS__*``
settings, so another user of the machine cannot submit code to it while the test runs.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

import swarm
from swarm.campaign import deterministic_rows
from swarm.campaign.store import ResultsStore

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[3]
SPEC = """
[campaign]
name = "dask-loopback"
seed = 11
replicates = 1

[grid]
map = ["building", "cave"]
size = [20]
robots = [1, 2]
spawn = ["together"]
algorithm = ["frontier", "greed"]
radio = ["global", "multiwall"]

[stop]
explored = 0.7
max_ticks = 250
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def dask_command() -> list[str]:
    """Dask's command line next to this interpreter (``dask``), else ``python -m dask``."""
    found = shutil.which("dask", path=str(Path(sys.executable).parent))
    return [found] if found else [sys.executable, "-m", "dask"]


class Cluster:
    """A scheduler and two single-threaded workers as real processes, TLS on 127.0.0.1."""

    def __init__(self, folder: Path) -> None:
        from distributed.security import Security

        temporary = Security.temporary()  # a self-signed certificate: the CA and every role's certificate
        self.cert, self.key = folder / "cert.pem", folder / "key.pem"
        for path, text in ((self.cert, temporary.tls_ca_file), (self.key, temporary.tls_client_key)):
            path.write_text(text)
            path.chmod(0o600)
        self.tls = ["--tls-ca-file", str(self.cert), "--tls-cert", str(self.cert), "--tls-key", str(self.key)]
        self.address = f"tls://127.0.0.1:{free_port()}"
        self.env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
        self.logs = folder
        self.procs: list[subprocess.Popen] = []
        port = self.address.rsplit(":", 1)[1]
        try:
            self._start("scheduler", ["scheduler", "--host", "127.0.0.1", "--port", port, "--protocol", "tls",
                                      "--no-dashboard", *self.tls])
            for i in range(2):
                self._start(f"worker{i}", ["worker", self.address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                                           "--name", f"w{i}", "--local-directory", str(folder / f"w{i}"), *self.tls])
            self.worker_pids = self._wait_for_workers(2, timeout_s=90)
        except BaseException:
            self.stop()  # a cluster that did not come up leaves no process behind
            raise

    def _start(self, name: str, args: list[str]) -> None:
        log = open(self.logs / f"{name}.log", "wb")
        self.procs.append(subprocess.Popen([*dask_command(), *args], env=self.env, stdout=log, stderr=subprocess.STDOUT,
                                           cwd=self.logs))

    def security(self):
        from distributed.security import Security

        return Security(tls_ca_file=str(self.cert), tls_client_cert=str(self.cert), tls_client_key=str(self.key),
                        require_encryption=True)

    def tls_env(self) -> dict[str, str]:
        """Dask's settings for a client of this cluster, as environment variables (what a user exports)."""
        return {"DASK_DISTRIBUTED__COMM__TLS__CA_FILE": str(self.cert),
                "DASK_DISTRIBUTED__COMM__TLS__CLIENT__CERT": str(self.cert),
                "DASK_DISTRIBUTED__COMM__TLS__CLIENT__KEY": str(self.key),
                "DASK_DISTRIBUTED__COMM__REQUIRE_ENCRYPTION": "True"}

    def _wait_for_workers(self, n: int, timeout_s: float) -> set[int]:
        from distributed import Client

        deadline = time.monotonic() + timeout_s
        while True:
            for p in self.procs:
                if p.poll() is not None:
                    raise RuntimeError(f"a Dask process exited ({p.args[:3]}): see {self.logs}")
            try:
                with Client(self.address, security=self.security(), timeout="5s", set_as_default=False) as client:
                    if len(client.scheduler_info()["workers"]) >= n:
                        return set(client.run(os.getpid).values())
            except OSError:
                pass
            if time.monotonic() > deadline:
                raise RuntimeError(f"{n} Dask workers did not register within {timeout_s} s: see {self.logs}")
            time.sleep(0.5)

    def stop(self) -> None:
        for p in reversed(self.procs):
            p.terminate()
        for p in self.procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    c = Cluster(tmp_path_factory.mktemp("dask-cluster"))
    try:
        yield c
    finally:
        c.stop()


@pytest.fixture(scope="module")
def pool_rows(tmp_path_factory):
    out = tmp_path_factory.mktemp("pool")
    swarm.campaign.run(SPEC, out, workers=2)
    return out, deterministic_rows(out)


def pids(folder: Path) -> set[int]:
    return set(ResultsStore(folder).runs_table(columns=("key", "worker_pid")).column("worker_pid").to_pylist())


def same_results(folder: Path, reference: Path) -> None:
    rows, expected = deterministic_rows(folder), deterministic_rows(reference)
    assert len(expected) == 16 and all(r["status"] == "ok" for r in expected)
    assert rows == expected, "every deterministic column of every run equals the process pool's"
    sort = [("key", "ascending"), ("tick", "ascending")]
    assert ResultsStore(folder).timeseries_table().sort_by(sort).equals(ResultsStore(reference).timeseries_table().sort_by(sort))


def test_the_cli_runs_a_campaign_on_the_cluster(cluster, pool_rows, tmp_path):
    spec = tmp_path / "grid.toml"
    spec.write_text(SPEC)
    out = tmp_path / "cli"
    env = {**cluster.env, **cluster.tls_env()}
    done = subprocess.run([sys.executable, "-m", "swarm", "campaign", "run", str(spec), "-o", str(out), "--dask",
                           cluster.address], env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert f"running on dask:{cluster.address}" in done.stdout
    assert pids(out) == cluster.worker_pids, "the runs ran in the two worker processes"
    same_results(out, pool_rows[0])


def test_the_python_api_runs_a_campaign_on_the_cluster(cluster, pool_rows, tmp_path):
    import dask
    from distributed import Client

    settings = {"distributed.comm.tls.ca-file": str(cluster.cert), "distributed.comm.tls.client.cert": str(cluster.cert),
                "distributed.comm.tls.client.key": str(cluster.key), "distributed.comm.require-encryption": True}
    with dask.config.set(settings):
        by_address = swarm.campaign.run(SPEC, tmp_path / "address", dask=cluster.address)
    assert (by_address.ran, by_address.failed) == (16, 0)
    assert pids(tmp_path / "address") == cluster.worker_pids
    same_results(tmp_path / "address", pool_rows[0])
    with Client(cluster.address, security=cluster.security(), set_as_default=False) as client:
        by_client = swarm.campaign.run(SPEC, tmp_path / "client", dask=client)
        assert client.status == "running", "a client the caller holds stays open"
    assert by_client.ran == 16
    same_results(tmp_path / "client", pool_rows[0])
    assert json.loads(by_client.runs()["spec_json"][0])["seed"] == json.loads(by_address.runs()["spec_json"][0])["seed"]


def test_the_cluster_refuses_a_client_without_its_certificate(cluster):
    from distributed import Client

    for address in (cluster.address, cluster.address.replace("tls://", "tcp://")):
        with pytest.raises(Exception):
            Client(address, timeout="3s", set_as_default=False)
