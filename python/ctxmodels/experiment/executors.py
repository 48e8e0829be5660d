"""How the experiment runs its jobs and writes its files so that Ctrl-C is clean.

A terminal's Ctrl-C (SIGINT) reaches the whole process group. The default process pool's
workers ignore it (:func:`worker_ignores_sigint`) and the parent stops them at once
(:func:`stop_now`), instead of ``shutdown()`` first running every queued job. Files are
written beside their final name and renamed (:func:`write_atomic`), and steps that must not
be cut short hold Ctrl-C back until they end (:func:`sigint_deferred`).
"""
from __future__ import annotations

import concurrent.futures
import contextlib
import json
import math
import os
import signal
import threading
from pathlib import Path

import numpy as np


def write_atomic(path: Path, text: str) -> None:
    """Writes ``text`` to a temporary name in the same folder, then renames it: an
    interrupted write never leaves a truncated file under the final name."""
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        with partial.open("w", newline="") as handle:
            handle.write(text)
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


def _plain(value):
    """``value`` with NumPy scalars and arrays as Python numbers and lists, and every NaN
    or infinity as None (JSON has no token for them)."""
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(item) for item in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, np.integer)) and not isinstance(value, np.bool_):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    number = float(value)  # float, NumPy floats (and anything else float() takes)
    return number if math.isfinite(number) else None


def json_text(value) -> str:
    """The study's one JSON writer (results, findings, sweep): indented, NumPy values as
    plain numbers, and NaN/±infinity as ``null`` — strict JSON, which every parser reads
    (Python's ``json`` would otherwise write the non-standard ``NaN`` token)."""
    return json.dumps(_plain(value), indent=2, allow_nan=False)


def write_json(path: Path, value) -> None:
    """:func:`json_text` of ``value`` written with :func:`write_atomic`."""
    write_atomic(path, json_text(value))


def worker_ignores_sigint() -> None:
    """Pool initializer. A terminal's Ctrl-C reaches the whole process group; the workers
    ignore it (each would print a traceback and the pool would break mid-job), and the
    parent stops them (:func:`stop_now`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


@contextlib.contextmanager
def sigint_blocked(active: bool = True):
    """Blocks SIGINT in this thread (pending until exit); processes forked meanwhile inherit
    the block until :func:`worker_ignores_sigint` lifts it."""
    if not active or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextlib.contextmanager
def sigint_deferred():
    """Holds back Ctrl-C around steps that must not be cut short; a Ctrl-C meanwhile is
    raised on exit. (Swaps the Python handler: a signal mask would not do, since another
    thread — tqdm's monitor, say — can take the signal and the main thread still raises.)"""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is None:
        yield  # only the main thread ever raises KeyboardInterrupt
        return
    caught = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if caught:
        if callable(previous):
            previous(signal.SIGINT, None)
        elif previous == signal.SIG_DFL:
            signal.raise_signal(signal.SIGINT)  # the default action, now that it is back


def stop_now(executor: concurrent.futures.Executor) -> None:
    """Cancels the queued jobs and ends the worker processes without waiting for the jobs
    they are running (which ignore SIGINT and may take many minutes)."""
    if not isinstance(executor, concurrent.futures.ProcessPoolExecutor):
        return
    with sigint_deferred():  # a second Ctrl-C must not leave workers behind
        processes = list((getattr(executor, "_processes", None) or {}).values())
        manager = getattr(executor, "_executor_manager_thread", None)
        executor.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()
        for process in processes:
            process.join(timeout=5)
            if process.is_alive():
                process.kill()
                process.join(timeout=5)
        # The pool's manager thread closes its wake-up pipe as it ends; if it is still ending
        # at interpreter exit, CPython's exit hook can write to that pipe as it closes
        # (EBADF, printed as a traceback). Once it has ended, the hook sees it closed.
        if manager is not None:
            manager.join(timeout=10)


class InlineExecutor(concurrent.futures.Executor):
    """Runs jobs in the calling process (one worker, or debugging)."""

    def submit(self, fn, /, *args, **kwargs):
        future = concurrent.futures.Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except Exception as err:  # handed to the caller through the future
            future.set_exception(err)
        # KeyboardInterrupt and SystemExit propagate: a Ctrl-C must stop the whole run,
        # not fail one job and go on with the next.
        return future
