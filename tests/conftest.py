"""Shared Hypothesis profiles.

``default``: no per-example deadline (examples evaluate 10⁴-point arrays, and the first call
of a Rust model may spin up its thread pool). ``ci``: the same, derandomised so a CI run is
reproducible. ``thorough``: ten times the examples, for hunting edge cases locally.
Choose one with ``HYPOTHESIS_PROFILE=<name> pytest``.
"""
import os

from hypothesis import HealthCheck, settings

_common = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow], print_blob=True)
settings.register_profile("default", **_common)
settings.register_profile("ci", derandomize=True, **_common)
settings.register_profile("thorough", max_examples=1000, **_common)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))


import pytest  # noqa: E402


@pytest.fixture
def stock_in_stable_order(monkeypatch):
    """Stock Stone Soup's Gaussian-mixture reducer visits shared tags in the order of a
    ``set`` of random uuid strings, which changes with the process. ctxmodels' trackers
    visit them in first-appearance order (the core, and ``reduce_mixture`` on the component
    path); with this fixture the stock reducer does the same, so stock Stone Soup trackers
    and ours can be compared bit for bit ("the stock pipeline under the same stable order")."""
    import stonesoup.mixturereducer.gaussianmixture as module
    monkeypatch.setattr(module, "set", lambda items: list(dict.fromkeys(items)), raising=False)


@pytest.fixture
def no_work(monkeypatch):
    """Fails the test if the experiment or the sweep gets as far as running a job."""
    from ctxmodels.experiment import runner, sweep

    def refuse(*args, **kwargs):
        raise AssertionError("work started before the arguments were checked")
    monkeypatch.setattr(runner, "run_experiment", refuse)
    monkeypatch.setattr(sweep, "run_sweep", refuse)
