"""The study on a cluster: ``run_experiment`` with a Dask ``LocalCluster`` (two worker
processes) and with Ray (the few-line executor of docs/study.md) gives the process pool's results,
job by job and bit for bit."""
from __future__ import annotations

import concurrent.futures
import os

import pytest

from ctxmodels.experiment.runner import ExperimentConfig, run_experiment
from .setups import fingerprint

CONFIG = dict(scenarios=("mixed-range", "islands"),
              trackers=("gmphd-context", "jpda-context", "gmphd-sight"),
              seeds=(0, 1), duration=16.0, plot_seed=None, workers=2)


def _by_job(results):
    return {(r.job.scenario, r.job.tracker, r.job.seed): fingerprint(r) for r in results.results}


@pytest.fixture(scope="module")
def pool_results():
    return run_experiment(ExperimentConfig(**CONFIG), progress=False)


def _assert_same(pool, other):
    expected, got = _by_job(pool), _by_job(other)
    assert len(expected) == len(ExperimentConfig(**CONFIG).jobs()) >= 6
    assert got == expected

    def scores(results):  # the summaries, without their wall-clock timings
        return [{k: v for k, v in row.items() if k != "seconds"} for row in results.scores()]
    assert scores(other) == scores(pool)


def test_dask_local_cluster_gives_the_process_pools_results(pool_results):
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        results = run_experiment(ExperimentConfig(**CONFIG), executor=client.get_executor(),
                                 progress=False)
        # the jobs ran in the cluster's worker processes, not here
        worker_pids = set(client.run(os.getpid).values())
    assert len(worker_pids) == 2 and os.getpid() not in worker_pids
    _assert_same(pool_results, results)


class RayExecutor(concurrent.futures.Executor):
    """The executor of docs/study.md: a remote task's ``ObjectRef.future()`` is a
    ``concurrent.futures.Future``."""

    def submit(self, fn, /, *args, **kwargs):
        import ray
        return ray.remote(fn).remote(*args, **kwargs).future()


def test_ray_gives_the_process_pools_results(pool_results):
    import ray

    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False,
             configure_logging=False)
    assert ray.cluster_resources().get("CPU") == 2
    try:
        results = run_experiment(ExperimentConfig(**CONFIG), executor=RayExecutor(),
                                 progress=False)
    finally:
        ray.shutdown()
    _assert_same(pool_results, results)
