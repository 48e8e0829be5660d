"""Which path each scan of an array tracker ran, counted, and said once when it was not the
array path.

An array tracker (:class:`~ctxmodels.stonesoup.ArrayPointProcessTracker`,
:class:`~ctxmodels.stonesoup.ArrayJPDATracker`) runs a scan it cannot compute in the Rust
core through its component path: the same tracks, many times slower. That is silent in
the results, so it is counted (``array_scans``, ``component_scans``) and the first such
scan of each tracker raises a :class:`ComponentPathWarning` naming why.
"""
from __future__ import annotations

import warnings


class ComponentPathWarning(UserWarning):
    """An array tracker ran a scan on its (slower, same-results) component path; raised
    once per tracker, on the first such scan, naming why. The tracker's
    ``component_scans`` counts all of them."""


class PathCounts:
    """``array_scans`` and ``component_scans`` for an array tracker (a mixin: call
    :meth:`_count_paths` from ``__init__``)."""

    def _count_paths(self) -> None:
        #: Scans computed in the Rust core.
        self.array_scans = 0
        #: Scans run on the component path (the stock components; same tracks, slower).
        self.component_scans = 0
        self._component_path_warned = False

    def _ran_array_scan(self) -> None:
        self.array_scans += 1

    def _ran_component_scan(self, time, reason: str) -> None:
        """Counts a component-path scan; the tracker's first one warns, naming ``reason``."""
        self.component_scans += 1
        if not self._component_path_warned:
            self._component_path_warned = True
            warnings.warn(
                f"{type(self).__name__}: the scan at {time} ran on the component path (same "
                f"tracks, much slower): {reason}. Warned once per tracker; its "
                "component_scans counts such scans (see the tracker's 'Supported' list).",
                ComponentPathWarning, stacklevel=3)


__all__ = ["ComponentPathWarning", "PathCounts"]
