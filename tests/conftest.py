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
