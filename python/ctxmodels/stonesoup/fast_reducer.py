r"""A batched drop-in for Stone Soup's Gaussian-mixture reducer.

:class:`FastGaussianMixtureReducer` has the Properties of
:class:`~stonesoup.mixturereducer.gaussianmixture.GaussianMixtureReducer` and returns the same
components, merged in the same order:

* **prune**: components with :math:`w <` ``prune_threshold`` are dropped and their total
  weight is shared equally by the others (their ``weight`` is updated in place, as stock);
* **merge**: repeatedly take the heaviest remaining component :math:`b` (ties: the later one
  in input order) and walk the others in increasing weight; each :math:`c` whose squared
  Mahalanobis distance to the *running* merged mean,
  :math:`(m_c - m_b)^T P_c^{+} (m_c - m_b)` (pseudo-inverse of :math:`c`'s covariance), is
  below ``merge_threshold`` is merged into it pairwise,

  .. math::
      w = w_b + w_c,\quad m = \tfrac{w_b}{w} m_b + \tfrac{w_c}{w} m_c,\quad
      P = \tfrac{w_b}{w} P_b + \tfrac{w_c}{w} P_c + \tfrac{w_b w_c}{w^2} (m_b - m_c)(m_b - m_c)^T,

  with :math:`w` capped at 1 after each merge (the cap feeds the next merge, as stock). The
  merged component keeps :math:`b`'s tag and timestamp; components sharing a tag afterwards
  keep it on the heaviest and get new tags otherwise (tags visited in first-appearance
  order). With ``kdtree_max_distance`` the candidates are those within that Euclidean
  distance of :math:`b`, visited in increasing weight like the others;
* **truncate**: keep the ``max_number_components`` heaviest, sharing the rest's weight.

Instead of one Mahalanobis call per pair, a k-d tree over the means finds, once, the pairs
that can merge at all (:math:`\delta^T P_c^{+} \delta \ge \lambda_{\min}(P_c^{+})
\lVert\delta\rVert^2`); a pass with no such pair keeps its component without any arithmetic,
and the others compute the exact distances of their candidates in one array operation,
again after each merge (the running mean moves).

**Order.** Two places of the stock reducer iterate a ``set``: the shared-tag pass (a set of
random ``uuid4`` tag strings, whose order changes with ``PYTHONHASHSEED``) and the
``kdtree_max_distance`` candidates (a set of components, in address order). Both orders
change from process to process, so the stock results are not reproducible there. This
reducer uses the order it has everywhere else instead — first appearance for tags,
increasing weight (ties in input order) for k-d-tree candidates — and equals the stock
reducer whenever the stock sets happen to iterate in that order.
"""
from __future__ import annotations

import uuid
from operator import attrgetter

import numpy as np
from scipy.spatial import KDTree
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.state import TaggedWeightedGaussianState, WeightedGaussianState

from .fast import ObjectFactory, gaussian_arrays

_PROBE = dict(state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
              weight=0.5)
_TAGGED = ObjectFactory(TaggedWeightedGaussianState, dict(_PROBE, tag="probe"))
_WEIGHTED = ObjectFactory(WeightedGaussianState, _PROBE)


def _plain_floats(weights) -> bool:
    """Weights NumPy can order exactly as Python's sort does (no Probability, no NaN)."""
    if not all(type(w) in (float, int, np.float64) for w in weights):
        return False
    return not np.isnan(np.asarray(weights, dtype=np.float64)).any()


_RADIUS_SLACK = 1e-6


def _merge_candidates(means: np.ndarray, inverses: np.ndarray, threshold: float) -> list:
    r"""For each component (in the order given), the earlier components that could merge
    into it before its mean moves: an exact superset of the pairs with
    :math:`(m_c - m_b)^T V_c (m_c - m_b) < t`, :math:`V_c` the candidate's inverse
    covariance.

    Since :math:`\delta^T V_c \delta \ge \lambda_{\min}(V_c) \lVert\delta\rVert^2`, a pair can
    only merge when :math:`\lVert m_c - m_b\rVert < r_c = \sqrt{t / \lambda_{\min}(V_c)}`, found
    for all :math:`c` with one k-d tree query (radii padded for rounding; a candidate with
    :math:`\lambda_{\min} \le 0`, e.g. a singular covariance, is paired with everything). The
    candidates it returns are then checked with the exact distance.
    """
    n, dim = means.shape
    if n < 2 or not (np.all(np.isfinite(means)) and np.all(np.isfinite(inverses))):
        return [np.arange(r, dtype=np.intp) for r in range(n)]
    symmetric = (inverses + inverses.transpose(0, 2, 1)) / 2
    spectra = np.linalg.eigvalsh(symmetric)
    # eigenvalues are accurate to about eps·|λ_max|: shrink λ_min by that much
    lam_min = spectra[:, 0] - 8 * dim * np.finfo(np.float64).eps * np.abs(spectra).max(axis=1)
    bounded = lam_min > 0
    radius = np.zeros(n)
    radius[bounded] = np.sqrt(threshold / lam_min[bounded]) * (1 + _RADIUS_SLACK)
    lists: list = [[] for _ in range(n)]
    tree = KDTree(means)
    for c, neighbours in enumerate(tree.query_ball_point(means, r=radius)):
        if bounded[c]:
            for b in neighbours:
                if c < b:
                    lists[b].append(c)
        else:
            for b in range(c + 1, n):
                lists[b].append(c)
    return [np.array(sorted(found), dtype=np.intp) for found in lists]


class FastGaussianMixtureReducer(GaussianMixtureReducer):
    """Gaussian-mixture reducer (prune, merge, truncate) with batched merge distances.

    Same Properties and results as
    :class:`stonesoup.mixturereducer.gaussianmixture.GaussianMixtureReducer` (see the module
    docstring for the exact semantics reproduced). Components must be weighted Gaussian
    states (tagged or not), as for the stock reducer.
    """

    def prune(self, components_list):
        """Drop components below :attr:`prune_threshold`; share their weight equally."""
        components = list(components_list)
        if not components:
            return components
        threshold = self.prune_threshold
        pruned_sum = 0
        for component in components:
            if component.weight < threshold:
                pruned_sum += component.weight
        remaining = [c for c in components if c.weight >= threshold]
        for component in remaining:
            component.weight += pruned_sum / len(remaining)
        return remaining

    def merge(self, components_list):
        """Greedy merge (see the module docstring), distances batched per pass."""
        components = list(components_list)
        n = len(components)
        if n == 0:
            return []
        means, covars = gaussian_arrays(components)
        means = means[..., 0]
        # the stock measure takes the pseudo-inverse of each candidate's covariance
        inverses = np.linalg.pinv(covars)
        weights = [c.weight for c in components]

        # ascending weight, ties in input order (a stable sort, as sorted(...) is); the
        # stock pops the heaviest (last) and visits the rest in this order
        if _plain_floats(weights):
            order = np.argsort(np.asarray(weights, dtype=np.float64), kind="stable")
        else:
            order = np.asarray(sorted(range(n), key=lambda i: weights[i]), dtype=np.intp)
        rank = np.empty(n, dtype=np.intp)
        rank[order] = np.arange(n)
        threshold = self.merge_threshold
        reachable = _merge_candidates(means[order], inverses[order], threshold)

        tree = None
        if self.kdtree_max_distance is not None:
            tree = KDTree(np.vstack([c.state_vector[:, 0] for c in components]))
        alive = np.ones(n, dtype=bool)  # by rank: still in the stock's remaining set

        merged_components = []
        for top in range(n - 1, -1, -1):
            if not alive[top]:
                continue
            alive[top] = False
            best = int(order[top])
            reach = reachable[top]
            if tree is None:
                if not reach.size:  # nothing can merge into it: kept as it is
                    merged_components.append(components[best])
                    continue
                # visiting order: alive ranks below top, ascending
                possible = reach[alive[reach]]
                if possible.size == 0:
                    merged_components.append(components[best])
                    continue
                check = order[possible]
                candidates = None
            else:
                indexes = tree.query_ball_point(components[best].state_vector.ravel(),
                                                r=self.kdtree_max_distance)
                # in increasing weight (rank), not the stock set's address order
                alive_ranks = np.sort(np.asarray([rank[i] for i in indexes if alive[rank[i]]],
                                                 dtype=np.intp))
                candidates = order[alive_ranks]
                check = candidates[np.isin(alive_ranks, reach)]

            mean = means[best]
            covar = covars[best]
            weight = weights[best]
            merged_any = False
            while check.size:
                delta = means[check] - mean
                d2 = np.einsum("ni,nij,nj->n", delta, inverses[check], delta)
                hits = np.flatnonzero(d2 < threshold)
                if hits.size == 0:
                    break
                other = int(check[hits[0]])
                alive[rank[other]] = False
                # the stock pairwise merge: component_1 the running merge, component_2 other
                weight_sum = weight + weights[other]
                w1 = weight / weight_sum
                w2 = weights[other] / weight_sum
                other_mean = means[other]
                new_mean = mean * w1 + other_mean * w2
                diff = (mean - other_mean)[:, np.newaxis]
                covar = covar * w1 + covars[other] * w2 + diff * diff.T * w1 * w2
                mean = new_mean
                weight = 1 if weight_sum > 1 else weight_sum
                merged_any = True
                # the mean moved: every later candidate of this pass is checked exactly
                if candidates is None:
                    later = np.arange(rank[other] + 1, top)
                    check = order[later[alive[later]]]
                else:
                    after = int(np.flatnonzero(candidates == other)[0]) + 1
                    check = candidates[after:]

            component = components[best]
            if merged_any:
                values = dict(state_vector=np.asarray(mean, dtype=np.float64)
                              .reshape(-1, 1).view(StateVector),
                              covar=np.asarray(covar, dtype=np.float64).view(CovarianceMatrix),
                              weight=weight, timestamp=component.timestamp)
                if isinstance(component, TaggedWeightedGaussianState):
                    component = _TAGGED(tag=component.tag, **values)
                else:
                    component = _WEIGHTED(**values)
            merged_components.append(component)
        return self._unique_tags(merged_components)

    @staticmethod
    def _unique_tags(merged_components):
        """Components sharing a tag: the heaviest keeps it, the others get new ones."""
        if not all(isinstance(c, TaggedWeightedGaussianState) for c in merged_components):
            return merged_components
        # First-appearance order; stock iterates a set of (randomly hashed) tag strings,
        # which puts the mixture in a different order in every process.
        tags = list(dict.fromkeys(c.tag for c in merged_components))
        if len(tags) == len(merged_components):
            return merged_components
        by_tag: dict = {}
        for component in merged_components:
            by_tag.setdefault(component.tag, []).append(component)
        final = []
        for tag in tags:
            shared = sorted(by_tag[tag], key=attrgetter("weight"), reverse=True)
            final.append(shared[0])
            for component in shared[1:]:
                component.tag = str(uuid.uuid4())
                final.append(component)
        return final

    def truncate(self, components_list):
        """Keep the :attr:`max_number_components` heaviest; share the others' weight."""
        components = list(components_list)
        limit = self.max_number_components
        weights = [c.weight for c in components]
        if _plain_floats(weights):
            # descending, ties in input order: what sorted(..., reverse=True) gives
            values = np.asarray(weights, dtype=np.float64)
            order = np.argsort(-values, kind="stable")
            ranked = [components[i] for i in order]
        else:
            ranked = sorted(components, key=attrgetter("weight"), reverse=True)
        dropped_sum = sum([c.weight for c in ranked[limit:]])
        kept = ranked[:limit]
        share = dropped_sum / limit
        for component in kept:
            component.weight += share
        return kept


__all__ = ["FastGaussianMixtureReducer"]
