"""The study's trackers — the paper's Table I (JPDA, the uniform, radar-only, P_D-aware and
context-aware GM-PHD) and ours (a tuned and a context-aware JPDA, learned λ and P_D, line of
sight, a coastal band) — by name, for anyone's sensor data:

.. code-block:: python

    from ctxmodels.trackers import paper_tracker
    for time, tracks in paper_tracker("gmphd-context", streams, sensor_models, navigation):
        ...

:data:`TRACKERS` names them (``ctxmodels list``) with their settings
(:class:`TrackerSpec`, :mod:`~ctxmodels.trackers.specs`); :func:`paper_tracker` checks the
inputs and assembles the Stone Soup components (:mod:`~ctxmodels.trackers.components`), the
sensor models each reads (:mod:`~ctxmodels.trackers.models`), and returns a
:class:`PaperTracker`."""
from .factory import paper_tracker
from .specs import TRACKERS, TrackerSpec
from .tracker import PaperTracker

__all__ = ["PaperTracker", "TRACKERS", "TrackerSpec", "paper_tracker"]
