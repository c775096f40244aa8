"""`aeroform.sweep` on a Dask LocalCluster equals the local run bit for bit, also when a
worker is killed mid-run."""

import json
import os
import signal
import threading
import time

import pytest

import aeroform
from conftest import SCENARIOS

distributed = pytest.importorskip("distributed")


def map_spec(n_mu=4, n_sigma=4, lco=False):
    spec = {
        "kind": "flutter_map",
        "structure": str(SCENARIOS / "plate-rig.structure.toml"),
        "model": str(SCENARIOS / "plate-truth.model.toml"),
        "speeds": [1.0 + 0.25 * i for i in range(60)],
        "grid": {"mu": [20.0 + 5.0 * i for i in range(n_mu)],
                 "sigma": [0.3 + 0.1 * i for i in range(n_sigma)]},
    }
    if lco:
        spec["lco_speeds"] = [8.0, 10.0]
    return spec


def dumps(doc):
    return json.dumps(doc, sort_keys=True)


@pytest.fixture(scope="module")
def cluster():
    c = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                 dashboard_address=None, silence_logs=40)
    client = distributed.Client(c)
    yield c, client
    client.close()
    c.close()


def test_map_on_a_local_cluster_equals_the_local_run(cluster):
    _, client = cluster
    spec = map_spec(lco=True)
    local = aeroform.sweep_local(spec)
    dist = aeroform.sweep(spec, client=client, chunk_size=3)
    assert dumps(local) == dumps(dist)
    pts = local["points"]
    assert len(pts) == 16 and [p["index"] for p in pts] == list(range(16))
    assert all(p["error"] is None for p in pts)
    # Heavier sections flutter at higher speeds (σ fixed): a physical check of the grid.
    u = [p["critical"]["speed"] for p in pts if p["sigma"] == pts[0]["sigma"]]
    assert u == sorted(u)


def test_blind_benchmark_on_a_local_cluster_equals_the_local_run(cluster):
    _, client = cluster
    # Index 0 of every draw is a static offset; seed 9's set is diagnosed in 4.5 s, seed 7's
    # (used before round 38) in 7.6 s, and the test diagnoses it twice.
    spec = {"kind": "blind", "n": 1, "seed": 9}
    local = aeroform.sweep_local(spec)
    dist = aeroform.sweep(spec, client=client, chunk_size=1)

    def strip(doc):  # wall-clock fields are the only ones that may differ
        doc = json.loads(json.dumps(doc))
        doc["summary"].pop("mean_seconds")
        for o in doc["outcomes"]:
            o.pop("seconds")
        return doc

    assert dumps(strip(local)) == dumps(strip(dist))
    assert [o["spec"]["index"] for o in local["outcomes"]] == [0]


def test_killing_a_worker_mid_run_still_completes_identically(cluster):
    c, client = cluster
    spec = map_spec(n_mu=6, n_sigma=5, lco=True)
    local = aeroform.sweep_local(spec)
    result = {}
    t = threading.Thread(target=lambda: result.setdefault(
        "doc", aeroform.sweep(spec, client=client, chunk_size=1)))
    t.start()
    # Wait until a worker is computing a sweep task, then kill that worker's process.
    victim = None
    deadline = time.time() + 60
    while victim is None and time.time() < deadline:
        proc = client.processing()
        busy = [w for w, tasks in proc.items() if tasks]
        if busy:
            victim = busy[0]
        else:
            time.sleep(0.05)
    assert victim is not None, "no task started"
    pid = client.run(os.getpid, workers=[victim])[victim]
    os.kill(pid, signal.SIGKILL)
    t.join(timeout=300)
    assert not t.is_alive()
    assert dumps(result["doc"]) == dumps(local)
    # The nanny restarted the worker: the cluster is whole again.
    client.wait_for_workers(2, timeout=60)
    assert pid not in client.run(os.getpid).values()


def test_bad_specs_raise_naming_the_field():
    spec = map_spec()
    spec["grid"]["r2"] = [0.25, -1.0]
    with pytest.raises(aeroform.AeroformError, match=r"grid.r2\[1\]"):
        aeroform.sweep_local(spec)
    with pytest.raises(aeroform.AeroformError, match="unknown variant|kind"):
        aeroform.sweep_local({"kind": "teleport"})


def test_cli_shards_merge_into_the_unsharded_run(tmp_path):
    from conftest import run_cli

    spec = map_spec(n_mu=3, n_sigma=3)
    (tmp_path / "map.json").write_text(json.dumps(spec))
    run_cli("sweep", tmp_path / "map.json", "--out", tmp_path / "whole.json")
    parts = []
    for i in range(4):
        p = tmp_path / f"part{i}.json"
        run_cli("sweep", tmp_path / "map.json", "--shard", f"{i}/4", "--out", p)
        parts.append(p)
    run_cli("merge", tmp_path / "merged.json", *reversed(parts))
    whole = json.loads((tmp_path / "whole.json").read_text())
    assert whole == json.loads((tmp_path / "merged.json").read_text())
    assert whole == aeroform.sweep_local(spec)
