"""Concurrency: contexts and models are shared, immutable, and evaluate with the GIL released.

* Many Python threads evaluating the same context at once (P_D, expected P_D, λ, and log
  P_D over the same states as particle columns; each call large enough that the core also
  splits it over its own Rayon threads) give results bit-identical to serial ones.
* Results do not depend on the number of Rayon threads (a subprocess with
  RAYON_NUM_THREADS=1 reproduces them bit for bit).
* A long evaluation lets another Python thread run meanwhile (the GIL is released): a counter
  thread advances while the main thread is inside one Rust call. No timing thresholds.
"""
import os
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from .setups import N, digest, evaluate_all, inputs, sensor


def test_threads_sharing_one_context_match_serial_bit_for_bit():
    context = sensor("gauss-hermite").context((20.0, -30.0, 0.7))
    jobs = [inputs(seed) for seed in range(6)]
    serial = [evaluate_all(context, *job) for job in jobs]
    with ThreadPoolExecutor(max_workers=6) as pool:
        # Every job twice, interleaved, so the same arrays are also read concurrently.
        futures = [pool.submit(evaluate_all, context, *jobs[k % 6]) for k in range(12)]
        parallel = [f.result() for f in futures]
    for k, result in enumerate(parallel):
        for got, want in zip(result, serial[k % 6]):
            np.testing.assert_array_equal(got, want)
    assert {v for r in serial for v in np.unique(r[0])} <= {0.0, 0.4}
    assert any(np.any(r[0] == 0.4) for r in serial)


def test_threads_with_out_buffers_and_many_contexts():
    """Each thread its own context (pose) and out buffer: no cross-talk between calls."""
    model = sensor()
    means, _, _ = inputs(7)
    poses = [(float(x), float(-x), 0.1 * x) for x in range(8)]
    expected = [model.context(p).prob_detection_array(means) for p in poses]

    def run(k):
        out = np.full(N, np.nan)
        result = model.context(poses[k]).prob_detection_array(means, out=out)
        assert result is out
        return out

    with ThreadPoolExecutor(max_workers=8) as pool:
        results = list(pool.map(run, range(8)))
    for got, want in zip(results, expected):
        np.testing.assert_array_equal(got, want)
    assert not all(np.array_equal(expected[0], e) for e in expected[1:])  # poses matter


ROOT = Path(__file__).resolve().parents[2]  # the repository, holding the tests package
_CHILD = """
import hashlib, sys
sys.path.insert(0, {root!r})  # the repository: the tests package
from tests.core.setups import sensor, inputs, evaluate_all, digest
context = sensor("unscented").context((20.0, -30.0, 0.7))
print(digest([r for seed in range(3) for r in evaluate_all(context, *inputs(seed))]))
"""


def test_results_do_not_depend_on_the_number_of_rayon_threads():
    context = sensor("unscented").context((20.0, -30.0, 0.7))
    here = digest([r for seed in range(3) for r in evaluate_all(context, *inputs(seed))])
    code = _CHILD.format(root=str(ROOT))
    for threads in ("1",):
        env = dict(os.environ, RAYON_NUM_THREADS=threads)
        child = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                               check=True)
        assert child.stdout.strip() == here, (threads, child.stderr)


@pytest.mark.parametrize("call", ["expected", "particles"])
def test_evaluation_releases_the_gil(call):
    """While the main thread is inside one long Rust call, a pure-Python counter thread keeps
    running. The switch interval is made huge, so the main thread never has the GIL taken
    from it: between reading the counter and returning from the call, the counter can only
    advance if the call itself releases the GIL. No timing thresholds."""
    context = sensor("gauss-hermite").context((0.0, 0.0, 0.0))
    means, covars, _ = inputs(3, n=200_000)
    if call == "particles":  # P_D and its log at 2e5 particles, land + sight
        particles = np.ascontiguousarray(means.T)
        evaluate = lambda: context.prob_detection_particles(particles, log=True)  # noqa: E731
    else:
        evaluate = lambda: context.prob_detection_array(means, covars)  # noqa: E731
    context.prob_detection_array(means[:10], covars[:10])  # compile and warm up first
    stop = threading.Event()
    running = threading.Event()
    count = [0]

    def counter():
        running.set()
        while not stop.is_set():
            count[0] += 1
            time.sleep(0)  # hand the GIL back at once, so the main thread can take it

    old = sys.getswitchinterval()
    sys.setswitchinterval(60.0)
    thread = threading.Thread(target=counter)
    try:
        thread.start()
        running.wait()
        time.sleep(0)
        before = count[0]
        result = evaluate()  # expected: 16 nodes x 2e5 rows, land + sight
        during = count[0] - before
    finally:
        stop.set()
        sys.setswitchinterval(old)
        thread.join()
    result = np.exp(result) if call == "particles" else result
    assert result.shape == (200_000,) and np.all((result >= 0) & (result <= 1))
    assert during > 0, "the counter thread never ran while P_D was being evaluated"


def test_the_gil_test_would_notice_a_call_that_holds_the_gil():
    """Control for the test above: the same harness around a pure-Python loop (which holds
    the GIL throughout) sees no progress, so the assertion there can fail."""
    stop = threading.Event()
    running = threading.Event()
    count = [0]

    def counter():
        running.set()
        while not stop.is_set():
            count[0] += 1
            time.sleep(0)

    old = sys.getswitchinterval()
    sys.setswitchinterval(60.0)
    thread = threading.Thread(target=counter)
    try:
        thread.start()
        running.wait()
        time.sleep(0)
        before = count[0]
        total = 0
        for k in range(300_000):  # GIL held: no blocking call, switch interval not reached
            total += k
        during = count[0] - before
    finally:
        stop.set()
        sys.setswitchinterval(old)
        thread.join()
    assert total > 0 and during == 0


def _evaluate_in_child(connection, means, covars, areas):
    context = sensor().context((0.0, 0.0, 0.3))
    connection.send(digest([evaluate_all(context, means, covars, areas)]))
    connection.close()


def test_large_batches_evaluate_in_a_child_forked_after_the_pool_started():
    """A forked child inherits Rayon's pool without its threads: the core must not hand it
    work there (it would wait forever). The child's results equal the parent's."""
    import multiprocessing
    if "fork" not in multiprocessing.get_all_start_methods():
        pytest.skip("no fork on this platform")
    data = inputs(11)
    here = digest([evaluate_all(sensor().context((0.0, 0.0, 0.3)), *data)])  # pool started
    context = multiprocessing.get_context("fork")
    receiver, sender = context.Pipe(duplex=False)
    child = context.Process(target=_evaluate_in_child, args=(sender, *data))
    child.start()
    sender.close()
    answered = receiver.poll(120)  # a hang, not a slow machine: serial takes ~1 s
    if not answered:
        child.kill()
    child.join(10)
    assert answered, "the forked child hung in a large evaluation"
    assert receiver.recv() == here
    assert child.exitcode == 0
