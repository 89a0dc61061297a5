"""Batches on a Dask distributed cluster: the same results as on local processes, figures streamed to disk."""

import json

import pytest

from identification.rig import run_rig, write_run

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def day(tmp_path_factory):
    folder = tmp_path_factory.mktemp("day")
    for i, effects in enumerate(((), ("enveloping",))):
        write_run(run_rig(effects, {"sensor.channels": "FL"}, seed=20 + i), folder / f"run_{i}")
    return folder


def _numbers(out):
    summary = json.loads((out / "summary.json").read_text())
    return {r["source"].rsplit("/", 1)[-1]: (r["diagnosis"]["tires"]["FL"]["k"], r["diagnosis"]["tires"]["FL"]["c"],
                                             r["tires"]["FL"]["paper"]["k"], r["tires"]["FL"]["waveform"]["k"])
            for r in summary["recordings"]}


def test_a_report_on_a_dask_cluster_equals_the_local_one(cli, day, tmp_path):
    local = cli("report", day, "-o", tmp_path / "local", "--workers", "1")
    assert local.code == 0, local.err
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cl:
        res = cli("report", day, "-o", tmp_path / "cluster", "--scheduler", cl.scheduler_address)
    assert res.code == 0, res.err
    assert _numbers(tmp_path / "cluster") == _numbers(tmp_path / "local")
    html = (tmp_path / "cluster" / "report.html").read_text()
    assert html.count("data:image/png;base64,") >= 4          # a small batch: figures embedded
    assert not (tmp_path / "cluster" / ".figures-staging").exists()


@pytest.mark.parametrize("address, problem", [("nonsense://x", "not a Dask scheduler address"),
                                              ("tcp://127.0.0.1:1", "cannot reach the Dask scheduler")])
def test_an_unusable_scheduler_is_one_line_and_exit_2(cli, day, tmp_path, monkeypatch, address, problem):
    import time
    from identification import executors
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 1.0)    # a short connection timeout for the test
    t0 = time.monotonic()
    res = cli("report", day, "-o", tmp_path / "new" / "out", "--scheduler", address)
    assert time.monotonic() - t0 < 8.0                          # refused after the timeout, not the default 10 s
    assert res.code == 2 and res.err.startswith("cleatfmu: error: --scheduler:") and problem in res.err, res.err
    assert res.err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []                   # nothing written, no folder left


def test_tires_keep_the_file_order_whatever_order_the_results_arrive_in(day, tmp_path, monkeypatch):
    import identification.report.batch as batch
    from identification import executors

    class Reversed(executors.LocalExecutor):
        def map_unordered(self, fn, jobs):
            yield from reversed([fn(job) for job in jobs])

    monkeypatch.setattr(executors, "executor_for", lambda workers, scheduler=None: Reversed(1))
    calls = []
    monkeypatch.setattr(batch, "_job", lambda job: calls.append(job) or (
        batch.DiagnosisReport(recording=job[2]) if job[0] == "recording" else
        batch.TireReport(recording=job[2], tire=job[3])))
    from identification.rig import run_rig, write_run
    write_run(run_rig((), {"sensor.channels": "RR,FL"}, seed=3), tmp_path / "two")
    result = batch.run_batch([tmp_path / "two.csv"], tmp_path / "out", workers=1, progress=False)
    from identification.recording import read_recording
    assert [t.tire for t in result.recordings[0].tires] == list(read_recording(tmp_path / "two.csv").tires)


def _timed(job):
    import time
    start = time.perf_counter()
    time.sleep(0.2)
    return job, start, time.perf_counter()


def test_a_threaded_worker_runs_one_job_at_a_time():
    # numba's compilation and matplotlib side by side in one process's threads are not safe (CPython 3.11's
    # AST race seen in CI): a worker of several threads runs the batch's jobs one after the other
    from identification.executors import DaskExecutor

    with distributed.LocalCluster(n_workers=1, threads_per_worker=3, processes=False, dashboard_address=None) as cl:
        with DaskExecutor(cl.scheduler_address) as ex:
            spans = sorted((start, end) for _, start, end in ex.map_unordered(_timed, range(3)))
    assert len(spans) == 3
    for (_, end), (start, _) in zip(spans, spans[1:]):
        assert start >= end, spans
