"""The Stone Soup internals ctxmodels relies on (``ctxmodels._upstream.INTERNALS``), checked
against the installed Stone Soup: each exists and behaves as ``_upstream`` relies on it, so a
Stone Soup release that renames or reshapes one fails here, naming it, rather than somewhere
inside a tracker.

Run by the test suite, and also inside the run of Stone Soup's own tests with the drop-ins
substituted: ``tests/upstream/upstream_substitute.py`` adds this module to that session and
reports its checks apart from the upstream tests (``scripts/upstream_tests.py``). So the
module is self-contained (no conftest fixture), and it looks Stone Soup's classes up only
while a check runs (:func:`stock`): while the plugin collects, the stock names of the classes
it substitutes are bound to the ctxmodels drop-ins.
"""
from __future__ import annotations

import datetime
import importlib
import uuid

import numpy as np
import pytest
import stonesoup
from scipy.special import logsumexp
from scipy.stats import chi2
from stonesoup.base import Base, Property

from ctxmodels import _upstream

START = datetime.datetime(2024, 1, 1)
CHECKS = {}


def stock(dotted: str):
    """The Stone Soup object named ``package.module.Name``, looked up at the call."""
    module, _, name = dotted.rpartition(".")
    return getattr(importlib.import_module(module), name)


def check(internal: str):
    def register(function):
        CHECKS[internal] = function
        return function
    return register


class _Probe(Base):
    """A Stone Soup component with one Property of each kind."""

    plain: float = Property(doc="A plain Property.")
    fixed: int = Property(default=3, doc="With a default.")
    listed: list = Property(default_factory=list, doc="With a default factory.")
    computed: float = Property(default=None, doc="With a getter.")
    guarded: float = Property(default=None, doc="With a setter.")

    @computed.getter
    def computed(self):
        return 2 * self.plain

    @guarded.setter
    def guarded(self, value):
        self.__dict__["guarded_by_setter"] = value


def _gaussian(mean=(1.0, 0.5, -2.0, 0.25), metadata=None):
    state_vector = stock("stonesoup.types.array.StateVector")(list(mean))
    covar = stock("stonesoup.types.array.CovarianceMatrix")(np.eye(len(mean)))
    if metadata is None:
        return stock("stonesoup.types.state.GaussianState")(state_vector, covar, timestamp=START)
    detection = stock("stonesoup.types.detection.Detection")(
        stock("stonesoup.types.array.StateVector")([1.0, 2.0]), timestamp=START, metadata=metadata)
    hypothesis = stock("stonesoup.types.hypothesis.SingleHypothesis")(None, detection)
    return stock("stonesoup.types.update.GaussianStateUpdate")(
        state_vector, covar, hypothesis=hypothesis, timestamp=START)


def _linear_model(noise=1.0):
    return stock("stonesoup.models.measurement.linear.LinearGaussian")(
        ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2) * noise)


# --- Property slots and descriptor internals ----------------------------------------------------
@check("stonesoup.base.Property._property_name")
def _property_name():
    prop = _Probe.__dict__["plain"]
    assert prop._property_name == _upstream.property_slot("plain") == "_property_plain"
    probe = _Probe(plain=1.5)
    assert probe.__dict__[_upstream.property_slot("plain")] == 1.5
    probe.__dict__[_upstream.property_slot("plain")] = 4.0  # what a fast constructor writes
    assert probe.plain == 4.0
    assert _upstream.plain_property(_Probe, "plain")


@check("stonesoup.base.Property._getter")
def _getter():
    assert _Probe.__dict__["plain"]._getter is None
    assert _Probe.__dict__["computed"]._getter is not None
    assert _upstream.plain_property(_Probe, "plain") and _upstream.plain_property(_Probe, "fixed")
    assert not _upstream.plain_property(_Probe, "computed")
    assert not _upstream.plain_property(_Probe, "no_such_property")
    assert _Probe(plain=2.0, computed=1.0).computed == 4.0  # the getter, not the slot
    # the Properties the array JPDA tracker reads off a prior from its slots
    for name in ("state_vector", "covar", "timestamp"):
        assert _upstream.plain_property(stock("stonesoup.types.state.GaussianState"), name), name


@check("stonesoup.base.Property._setter")
def _setter():
    assert not _upstream.has_setter(_Probe.__dict__["plain"])
    assert _upstream.has_setter(_Probe.__dict__["guarded"])
    probe = _Probe(plain=1.0, guarded=5.0)
    assert probe.__dict__["guarded_by_setter"] == 5.0  # the setter, not the slot
    assert _upstream.property_slot("guarded") not in probe.__dict__


@check("stonesoup.base.Base.__init__ (an instance is its slots)")
def _instance_is_its_slots():
    slot = _upstream.property_slot
    probe = _Probe(plain=1.0)
    listed = probe.__dict__[slot("listed")]
    assert listed == [] and listed is not _Probe(plain=1.0).listed  # a fresh default per instance
    assert probe.__dict__ == {slot("plain"): 1.0, slot("fixed"): 3, slot("listed"): listed,
                              slot("computed"): None, "guarded_by_setter": None}
    # every factory the array paths build Stone Soup objects with takes the slot route
    from ctxmodels.stonesoup import _batch, gnn
    from ctxmodels.stonesoup.jpda import _initiator_births, _initiator_history, array_tracker
    factories = [value for module in (_batch, gnn, _initiator_births, _initiator_history,
                                      array_tracker)
                 for value in vars(module).values() if isinstance(value, _batch.ObjectFactory)]
    assert len(factories) >= 8
    slow = [factory.cls.__name__ for factory in factories if not factory.fast]
    assert slow == [], f"built by their constructors, not their slots: {slow}"
    # and a plain instance dictionary takes attributes that are not Properties
    mixture = stock("stonesoup.types.mixture.GaussianMixture")([])
    mixture.clutter_probabilities = {"a": 0.5}
    assert _upstream.take_attribute(mixture, "clutter_probabilities") == {"a": 0.5}
    assert not hasattr(mixture, "clutter_probabilities")
    assert _upstream.take_attribute(mixture, "clutter_probabilities") is None


# --- tracks ---------------------------------------------------------------------------------------
@check("stonesoup.types.track.Track.metadatas")
def _track_slots():
    state = _gaussian(metadata={"sensor": 1})
    track = stock("stonesoup.types.track.Track")([state])
    fields = dict(track.__dict__)
    assert set(fields) == {_upstream.TRACK_STATES, _upstream.TRACK_ID,
                           _upstream.TRACK_INIT_METADATA, _upstream.TRACK_METADATAS}
    assert fields[_upstream.TRACK_STATES] == [state]
    assert str(uuid.UUID(fields[_upstream.TRACK_ID])) == fields[_upstream.TRACK_ID]
    assert fields[_upstream.TRACK_INIT_METADATA] == {}
    assert fields[_upstream.TRACK_METADATAS] == [{"sensor": 1}]
    # the array initiator's tracks: the same dictionary, checked once and then built so
    from ctxmodels.stonesoup._batch import plain_track_lists
    from ctxmodels.stonesoup.jpda._initiator_births import _TrackFactory
    factory = _TrackFactory()
    factory(state)
    assert factory.fast is True
    built = factory(state)
    ours = dict(built.__dict__)
    assert type(ours.pop(_upstream.TRACK_ID)) is str
    fields.pop(_upstream.TRACK_ID)
    assert ours == fields
    assert plain_track_lists(track) == ([state], [{"sensor": 1}])


@check("stonesoup.types.track.Track._update_metadata_from_state")
def _update_metadata():
    assert _upstream.update_track_metadata is stock("stonesoup.types.track.Track") \
        ._update_metadata_from_state
    track = stock("stonesoup.types.track.Track")([_gaussian(metadata={"a": 1})])
    state = _gaussian(metadata={"b": 2})
    track.states.append(state)
    _upstream.update_track_metadata(track, state)
    assert track.metadatas == [{"a": 1}, {"a": 1, "b": 2}]
    assert track.metadata == {"a": 1, "b": 2}


# --- updaters and trackers ----------------------------------------------------------------------
@check("stonesoup.updater.base.Updater._check_measurement_model")
def _check_measurement_model():
    own, given = _linear_model(), _linear_model(2.0)
    for name in ("stonesoup.updater.kalman.KalmanUpdater",
                 "stonesoup.updater.kalman.ExtendedKalmanUpdater",
                 "stonesoup.updater.particle.ParticleUpdater"):
        updater = stock(name)(measurement_model=own)
        assert _upstream.check_measurement_model(updater, None) is own, name
        assert _upstream.check_measurement_model(updater, given) is given, name
        bare = stock(name)(measurement_model=None)
        assert _upstream.check_measurement_model(bare, given) is given, name
        with pytest.raises(ValueError):
            _upstream.check_measurement_model(bare, None)


@check("stonesoup.tracker.simple.MultiTargetMixtureTracker._tracks")
def _live_tracks():
    tracker = stock("stonesoup.tracker.simple.MultiTargetMixtureTracker")(
        initiator=None, deleter=None, detector=None, data_associator=None, updater=None)
    live = _upstream.live_tracks(tracker)
    assert type(live) is set and live is tracker.tracks and not live
    track = stock("stonesoup.types.track.Track")([_gaussian()])
    live |= {track}
    assert tracker.tracks == {track}
    live -= {track}
    assert not tracker.tracks


@check("stonesoup.updater.particle.BernoulliParticleUpdater._log_space_product")
def _log_space_product():
    updater = stock("stonesoup.updater.particle.BernoulliParticleUpdater")
    rng = np.random.default_rng(7)
    a, b = rng.normal(size=6), rng.normal(size=6)
    assert _upstream.log_space_product(updater, a, b) == logsumexp(a + b)
    matrix_a, matrix_b = rng.normal(size=(2, 5)), rng.normal(size=(5, 3))
    expected = [[logsumexp(matrix_a[i] + matrix_b[:, j]) for j in range(3)] for i in range(2)]
    np.testing.assert_allclose(_upstream.log_space_product(updater, matrix_a, matrix_b),
                               expected, rtol=1e-14)


@check("stonesoup.updater.particle.SMCPHDUpdater._get_measurement_loglikelihoods")
def _measurement_loglikelihoods():
    model = _linear_model()
    updater = stock("stonesoup.updater.particle.SMCPHDUpdater")(
        measurement_model=model, prob_detect=0.9, clutter_intensity=1e-3)
    rng = np.random.default_rng(3)
    particles = stock("stonesoup.types.array.StateVectors")(rng.normal(size=(4, 50)))
    prediction = stock("stonesoup.types.state.ParticleState")(
        particles, log_weight=np.full(50, -np.log(50)), timestamp=START)
    detection = stock("stonesoup.types.detection.Detection")
    detections = [detection(stock("stonesoup.types.array.StateVector")([0.1, -0.3]),
                            timestamp=START, measurement_model=model),
                  detection(stock("stonesoup.types.array.StateVector")([1.0, 0.5]),
                            timestamp=START)]
    # (noise=True: the model draws noise from NumPy's global generator, seeded alike here)
    saved = np.random.get_state()
    try:
        np.random.seed(11)
        found = _upstream.measurement_loglikelihoods(updater, prediction, detections)
        np.random.seed(11)
        expected = [model.logpdf(det, prediction, noise=True) for det in detections]
    finally:
        np.random.set_state(saved)
    assert found.shape == (50, 2)
    np.testing.assert_array_equal(found, np.column_stack(expected))


@check("stonesoup.hypothesiser.probability.PDAHypothesiser._gate_threshold")
def _gate_threshold():
    stock_gate = stock("stonesoup.hypothesiser.probability.PDAHypothesiser")._gate_threshold
    probability = stock("stonesoup.types.numeric.Probability")
    for prob_gate in (0.95, 0.99, 0.9999, probability(0.95), np.float64(0.5)):
        for ndim in (1, 2, 3, 4):
            ours = _upstream.gate_threshold(prob_gate, ndim)
            assert ours == stock_gate(prob_gate, ndim) == chi2.ppf(float(prob_gate), ndim), \
                (prob_gate, ndim)


@check("stonesoup.types.state.CreatableFromState.class_mapping")
def _from_state_classes():
    from ctxmodels.stonesoup._batch import from_state_target
    for base in ("stonesoup.types.prediction.Prediction", "stonesoup.types.update.Update"):
        base = stock(base)
        for state in (_gaussian(), _gaussian(metadata={})):
            mapping = _upstream.from_state_classes(base)
            assert isinstance(mapping, dict) and type(state) in mapping or any(
                kind in mapping for kind in type(state).mro())
            kwargs = {"hypothesis": None} if base.__name__ == "Update" else {}
            built = base.from_state(state, **kwargs)
            assert type(built) is from_state_target(base, type(state)), (base, type(state))


# --- the checks ---------------------------------------------------------------------------------
@pytest.mark.parametrize("internal", sorted(_upstream.INTERNALS))
def test_stone_soup_internal_as_relied_on(internal):
    try:
        CHECKS[internal]()
    except (AssertionError, AttributeError, TypeError, KeyError) as error:
        raise AssertionError(
            f"Stone Soup {stonesoup.__version__}: {internal} is not what ctxmodels._upstream "
            f"relies on ({type(error).__name__}: {error})") from error


def test_every_internal_is_checked():
    assert set(CHECKS) == set(_upstream.INTERNALS)
    for names in _upstream.INTERNALS.values():
        assert names and all(hasattr(_upstream, name) for name in names), names


def test_a_changed_internal_fails_its_check(monkeypatch):
    """The checks can fail: an internal renamed (as a Stone Soup release might) or its shape
    changed is reported, naming it."""
    updater_base = stock("stonesoup.updater.base.Updater")
    monkeypatch.delattr(updater_base, "_check_measurement_model")
    with pytest.raises(AssertionError, match="_check_measurement_model is not what"):
        test_stone_soup_internal_as_relied_on(
            "stonesoup.updater.base.Updater._check_measurement_model")
    monkeypatch.setattr(_upstream, "property_slot", lambda name: f"_slot_{name}")
    with pytest.raises(AssertionError, match="_property_name is not what"):
        test_stone_soup_internal_as_relied_on("stonesoup.base.Property._property_name")
