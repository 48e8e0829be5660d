"""Gaussian-mixture reduction in a reproducible order, for the component-path trackers.

Stone Soup 1.9.1's ``GaussianMixtureReducer.merge`` regroups components that share a tag by
walking a ``set`` of their tag strings — random uuids, so the order of the reduced mixture
changes from call to call and process to process. The order matters: the next scan's PHD
normalisers are sums over the mixture in that order, so the weights (and, through them, the
tracks) differ in their last bits from run to run. :func:`reduce_mixture` performs the stock
reduction — the stock ``prune``, ``merge_components`` and ``truncate``, the same greedy
merge with the same distances — with the two order-dependent steps made stable, as the Rust
core does them (``rust/gmphd/reduce.rs``):

* shared tags are resolved in the order the tags first appear among the merged components
  (within a tag, the heaviest keeps it and the others get new uuids, as stock);
* with ``kdtree_max_distance``, the candidates inside the gate are visited lightest first,
  as without the gate (stock visits a set of components, i.e. memory-address order).
"""
from __future__ import annotations

import uuid
from operator import attrgetter

import numpy as np
from scipy.spatial import KDTree
from stonesoup.measures import SquaredMahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.types.state import TaggedWeightedGaussianState


def reduce_mixture(reducer, components: list) -> list:
    """``reducer.reduce(components)``, in a reproducible order when ``reducer`` is the stock
    ``GaussianMixtureReducer`` (any other reducer is called as it is)."""
    if type(reducer) is not GaussianMixtureReducer:
        return reducer.reduce(components)
    if not components:
        return components
    if reducer.pruning:
        components = reducer.prune(components)
    if len(components) > 1 and reducer.merging:
        components = _merge(reducer, components)
    if len(components) > reducer.max_number_components and reducer.truncating:
        components = reducer.truncate(components)
    return components


def _merge(reducer: GaussianMixtureReducer, components: list) -> list:
    """Greedy merging (Vo & Ma): the heaviest remaining component absorbs every lighter one
    within ``merge_threshold`` (squared Mahalanobis distance, with the candidate's
    covariance, to the absorbing component as merged so far), lightest candidate first."""
    near = _gate(reducer, components)
    measure = SquaredMahalanobis(state_covar_inv_cache_size=None)
    remaining = sorted(components, key=attrgetter("weight"))  # ties keep the input order
    merged = []
    while remaining:
        best = remaining.pop()  # the heaviest (of equal weights, the later)
        inside = None if near is None else near(best)
        kept = []
        for candidate in remaining:
            if ((inside is None or id(candidate) in inside)
                    and measure(state1=candidate, state2=best) < reducer.merge_threshold):
                best = reducer.merge_components(best, candidate)
            else:
                kept.append(candidate)
        remaining = kept
        merged.append(best)
    if not all(isinstance(c, TaggedWeightedGaussianState) for c in merged):
        return merged
    return _unique_tags(merged)


def _gate(reducer, components):
    """With ``kdtree_max_distance``: a function giving the ids of the components whose state
    lies within that Euclidean distance of a component's state; None without a gate."""
    if reducer.kdtree_max_distance is None:
        return None
    tree = KDTree(np.vstack([c.state_vector[:, 0] for c in components]))

    def near(component):
        found = tree.query_ball_point(component.state_vector.ravel(),
                                      r=reducer.kdtree_max_distance)
        return {id(components[i]) for i in found}
    return near


def _unique_tags(merged: list) -> list:
    """Components that share a tag after merging: grouped in first-appearance order of the
    tags, the heaviest of each group first keeping the tag, the others renamed."""
    groups: dict = {}
    for component in merged:
        groups.setdefault(component.tag, []).append(component)
    if len(groups) == len(merged):
        return merged
    ordered = []
    for members in groups.values():
        members.sort(key=attrgetter("weight"), reverse=True)
        ordered.extend(members)
        for component in members[1:]:
            component.tag = str(uuid.uuid4())
    return ordered


__all__ = ["reduce_mixture"]
