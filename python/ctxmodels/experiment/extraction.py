r"""Which of a tracker's states are scored: the extraction rule.

A Stone Soup GM-PHD tracker (``PointProcessMultiTargetTracker``, and ctxmodels' array
tracker with the same tracks) *starts* a track when a tagged component's weight exceeds the
extraction threshold (0.85 in the paper's Table I) and then appends that component's state
at every scan while the component survives pruning — at any weight above the prune
threshold (1e-6). A clutter track therefore lingers, reported, for as long as its weight
takes to decay below 1e-6 (tens of seconds at a radar P_D of 0.4), and a real target's track
keeps being reported through a long run of misses. Many GM-PHD implementations instead
report, at each scan, the components whose current weight is at least a fixed value. The
paper does not say which rule it scored, so the study offers both:

``stone-soup`` (the default)
    every state of every reported track (Stone Soup's rule);
``weight``
    a state is scored only when its weight is at least :data:`WEIGHT_THRESHOLD` = 0.5
    (:math:`w \ge 0.5`: the component stands for at least half a target). A track keeps
    its identity across the scans where it drops below, so a dip is a gap, not a new
    track.

States without a weight (JPDA tracks) are always scored: the rule concerns the GM-PHD only.
"""
from __future__ import annotations

from stonesoup.types.track import Track

#: The ``weight`` rule's threshold on a state's weight.
WEIGHT_THRESHOLD = 0.5
#: The rules by name (``ctxmodels experiment --extract``).
EXTRACTIONS = ("stone-soup", "weight")


def extracted(tracks: list, rule: str = "stone-soup") -> list:
    """The tracks as ``rule`` scores them (see the module docs), in the given order; a track
    left with no state is dropped."""
    if rule not in EXTRACTIONS:
        raise ValueError(f"rule: unknown extraction rule {rule!r}; choose from {list(EXTRACTIONS)}")
    if rule == "stone-soup":
        return list(tracks)
    kept = []
    for track in tracks:
        states = [state for state in track.states
                  if getattr(state, "weight", None) is None or state.weight >= WEIGHT_THRESHOLD]
        if len(states) == len(track.states):
            kept.append(track)
        elif states:
            kept.append(Track(states, id=track.id))
    return kept


__all__ = ["EXTRACTIONS", "WEIGHT_THRESHOLD", "extracted"]
