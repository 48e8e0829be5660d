"""Mixture reduction in a reproducible order (``reduce_mixture``): the stock reduction's
components, bit for bit and in the order the stock reducer gives when its shared-tag pass is
made to visit tags in first-appearance order, and the Rust core's (k-d tree gate included);
an order that depends on the components' values and input order only, never on the random
tag strings."""
import copy
import uuid

import numpy as np
import pytest
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.types.state import TaggedWeightedGaussianState, WeightedGaussianState

from ctxmodels import _core
from ctxmodels.stonesoup.gmphd.reduction import reduce_mixture


def _mixture(seed, n=60, tags=8):
    """Clusters of components, many sharing tags (as after an update: one tag per
    prediction, one component per detection), some with equal weights."""
    rng = np.random.default_rng(seed)
    names = [str(uuid.uuid4()) for _ in range(tags)]
    centres = rng.normal(0, 30, (6, 4))
    components = []
    for _ in range(n):
        mean = centres[rng.integers(6)] + rng.normal(0, 2, 4)
        a = rng.normal(0, 1, (4, 4))
        weight = float(rng.choice([0.5, 0.25, rng.uniform(1e-8, 1)]))
        components.append(TaggedWeightedGaussianState(
            mean.reshape(4, 1), a @ a.T + np.eye(4), weight=weight,
            tag=names[rng.integers(tags)]))
    return components


def _key(components):
    return [(c.state_vector.tobytes(), c.covar.tobytes(), float(c.weight)) for c in components]


REDUCERS = [GaussianMixtureReducer(prune_threshold=1e-6, merge_threshold=16),
            GaussianMixtureReducer(prune_threshold=1e-6, merge_threshold=16,
                                   kdtree_max_distance=25.0),
            GaussianMixtureReducer(prune_threshold=1e-3, merge_threshold=4,
                                   max_number_components=5)]


@pytest.mark.parametrize("reducer", REDUCERS)
@pytest.mark.parametrize("seed", range(4))
def test_equals_the_stock_reduction_in_first_appearance_order(reducer, seed, monkeypatch):
    import stonesoup.mixturereducer.gaussianmixture as module
    base = _mixture(seed)
    original = {c.tag for c in base}
    ours = reduce_mixture(reducer, copy.deepcopy(base))
    if reducer.kdtree_max_distance is None:
        # stock, its tag set iterated in first-appearance order (what reduce_mixture does)
        monkeypatch.setattr(module, "set", lambda items: list(dict.fromkeys(items)),
                            raising=False)
        stock = reducer.reduce(copy.deepcopy(base))
        assert _key(ours) == _key(stock)
        # the same components keep their tags (the others are renamed, with new uuids)
        assert [c.tag if c.tag in original else None for c in ours] == \
            [c.tag if c.tag in original else None for c in stock]
    # and the Rust core's reduction (the array tracker's), gate or not: the same
    # components in the same order, to round-off (its own linear algebra)
    core = _core.GaussianMixtureArrays(4)
    names = list(dict.fromkeys(c.tag for c in base))
    core.reserve_tags(len(names))
    core.extend(np.array([c.state_vector.ravel() for c in base]),
                np.array([c.covar for c in base]), np.array([float(c.weight) for c in base]),
                [names.index(c.tag) + 1 for c in base], [0] * len(base))
    core.reduce(pruning=reducer.pruning, prune_threshold=reducer.prune_threshold,
                merging=reducer.merging, merge_threshold=reducer.merge_threshold,
                truncating=reducer.truncating,
                max_components=int(min(reducer.max_number_components, 2 ** 63)),
                kdtree_max_distance=reducer.kdtree_max_distance)
    assert len(core) == len(ours)
    np.testing.assert_allclose(core.means(), [c.state_vector.ravel() for c in ours], rtol=1e-12)
    np.testing.assert_allclose(core.covars(), [c.covar for c in ours], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(core.weights(), [float(c.weight) for c in ours], rtol=1e-12)
    assert len(ours) < len(base)  # something was pruned or merged
    if reducer.max_number_components > len(ours):
        # merging left components sharing a tag, and the tag pass renamed some of them
        assert any(c.tag not in original for c in ours)
    tags = [c.tag for c in ours]
    assert len(set(tags)) == len(tags)  # tags made unique


@pytest.mark.parametrize("reducer", REDUCERS)
def test_order_does_not_depend_on_the_tag_strings(reducer):
    """The same mixture under other (random) tag names reduces to the same components in
    the same order; stock's order follows the tags' hashes."""
    first = _mixture(7)
    renamed = copy.deepcopy(first)
    names = {tag: str(uuid.uuid4()) for tag in dict.fromkeys(c.tag for c in first)}
    for c in renamed:
        c.tag = names[c.tag]
    assert _key(reduce_mixture(reducer, first)) == _key(reduce_mixture(reducer, renamed))


def test_untagged_and_other_reducers():
    untagged = [WeightedGaussianState(c.state_vector, c.covar, weight=c.weight)
                for c in _mixture(3)]
    reducer = REDUCERS[0]
    ours = reduce_mixture(reducer, copy.deepcopy(untagged))
    assert _key(ours) == _key(reducer.reduce(copy.deepcopy(untagged)))
    assert reduce_mixture(reducer, []) == []

    class Halving:  # any other reducer is called as it is
        def reduce(self, components):
            return components[::2]
    assert reduce_mixture(Halving(), [1, 2, 3]) == [1, 3]


def test_component_path_tracker_is_reproducible_within_a_process():
    """Two component-path GM-PHDs on one simulated run: the same mixture, in the same
    order, bit for bit, after every scan (the order differed from scan 55 on, where the
    stock reducer renamed shared tags)."""
    from ctxmodels.experiment.scenarios import make_scenario
    from ctxmodels.experiment.trackers import build_tracker
    from ctxmodels.trackers import TRACKERS
    run = make_scenario("mixed-range", 2, 15.0)
    a, b = (build_tracker(TRACKERS["gmphd-context"], run, fast=False) for _ in range(2))
    scans = 0
    for (_, _), (_, _) in zip(a, b):
        assert _key(a.gaussian_mixture.components) == _key(b.gaussian_mixture.components)
        scans += 1
    assert scans > 150
