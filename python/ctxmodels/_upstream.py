"""What ctxmodels relies on inside Stone Soup: every private attribute of Stone Soup (1.9.1)
that ctxmodels reads, writes, calls or reproduces, why, and the names the rest of the
package reaches it through. No other module of ctxmodels touches a Stone Soup private
attribute (``tests/upstream/test_private_use.py`` walks the package's syntax trees and fails
otherwise); ``tests/upstream/test_internals.py`` checks each entry of :data:`INTERNALS`
against the installed Stone Soup, in the test suite and in the run of Stone Soup's own tests
with the drop-ins substituted (``scripts/upstream_tests.py``).

The internals, by what they are for:

Property slots (``Property._property_name``)
    A Stone Soup ``Property`` keeps an instance's value in the instance dictionary under
    ``"_property_<name>"`` (:func:`property_slot`). The array paths build thousands of
    states, hypotheses and tracks per scan by writing those slots directly, without Stone
    Soup's per-Property constructor: ``stonesoup._batch.ObjectFactory`` (predictions,
    updates, measurement predictions, hypotheses), ``stonesoup.jpda._initiator_births``
    (new tracks), ``stonesoup.jpda.array_tracker`` (the lazily built JPDA hypotheses and
    their pickles), ``stonesoup.gmphd.region`` (a scan's surveillance disc). They read them
    back without the descriptor where every track is touched every scan
    (``stonesoup._batch.plain_track_lists``, the priors in ``stonesoup.jpda.array_tracker``).
    ctxmodels' own components are Stone Soup ``Base`` classes too, whose fast constructors
    and pickles write the same slots (``_component``, ``pose``, ``context``).

A plain ``Base`` instance is its slots (``Base.__init__``)
    For a class whose ``__init__`` chain only stores its arguments, the constructor's whole
    effect is the slot of every Property (defaults and default factories applied) in a plain
    instance ``__dict__``, which also takes attributes that are not Properties. That is why
    ``object.__new__`` plus a slot dictionary is the same object (the factories above check
    it once per class against the real constructor), and why the GM-PHD updater can hand
    the tracker a scan's clutter probabilities on the mixture it returns, which the tracker
    takes off again (:func:`take_attribute`, ``stonesoup.gmphd.tracker``).

``Property._getter`` and ``Property._setter``
    A Property with a getter or a setter is not read or written through its slot.
    :func:`plain_property` (the array JPDA tracker's priors) and :func:`has_setter` (which
    classes ``ObjectFactory`` may build from slots) ask.

``Track.metadatas`` and ``Track._update_metadata_from_state``
    ``Track([state])`` sets three Property slots (``states``, ``id``: a fresh uuid4 string,
    ``init_metadata``), the plain attribute ``metadatas`` (the metadata after each state),
    and appends the first state's metadata with ``_update_metadata_from_state``. The array
    initiator builds its new tracks the same way (:func:`update_track_metadata`,
    :data:`TRACK_STATES`, :data:`TRACK_ID`, :data:`TRACK_INIT_METADATA`,
    :data:`TRACK_METADATAS`), and ``plain_track_lists`` reads a track's states and
    metadatas lists without ``StateMutableSequence``'s attribute hook.

``Updater._check_measurement_model``
    The measurement model an updater uses for a detection: the detection's, else the
    updater's own, else ``ValueError``. The batched measurement predictions
    (``stonesoup._batch``), the fast GNN (``stonesoup.gnn``), the array initiator's scan
    (``stonesoup.jpda._initiator_scan``) and the array GM-PHD tracker
    (``stonesoup.gmphd.array_tracker``) resolve models with the updater's own rule
    (:func:`check_measurement_model`), so its errors and choices are the stock ones.

``MultiTargetMixtureTracker._tracks``
    The live set of the tracker's tracks (``tracks`` returns it). The JPDA trackers
    (``stonesoup.jpda.tracker``, ``stonesoup.jpda.array_tracker``) delete from and add to
    it in place, as the stock scan does (:func:`live_tracks`).

``BernoulliParticleUpdater._log_space_product`` and ``SMCPHDUpdater._get_measurement_loglikelihoods``
    The particle drop-ins (``stonesoup.particle``) call the stock updaters' own helpers, so
    that a constant context gives the stock result to the bit (:func:`log_space_product`,
    :func:`measurement_loglikelihoods`).

``PDAHypothesiser._gate_threshold`` (reproduced, not called)
    The stock PDA hypothesiser gates a detection when its squared Mahalanobis distance is
    at most :math:`F^{-1}_{\\chi^2_n}(P_G)`, ``chi2.ppf(float(prob_gate), n)``.
    :func:`gate_threshold` computes the same number for ctxmodels' PDA hypothesiser and the
    array JPDA tracker.

``CreatableFromState.class_mapping``
    The registry behind ``Prediction.from_state`` / ``Update.from_state``: per base class,
    which subclass a state of each type becomes (:func:`from_state_classes`;
    ``stonesoup._batch.from_state_target`` resolves it once per type pair).

This module imports nothing from ctxmodels, so the core and the Stone Soup drop-ins can both
use it without an import circle.
"""
from __future__ import annotations

import functools

from scipy.stats import chi2
from stonesoup.base import Property
from stonesoup.types.state import CreatableFromState
from stonesoup.types.track import Track


# --- Property slots -------------------------------------------------------------------------
def property_slot(name: str) -> str:
    """The instance-dictionary key under which a Stone Soup Property ``name`` keeps its
    value (``Property._property_name``)."""
    return f"_property_{name}"


def plain_property(cls: type, name: str) -> bool:
    """Whether ``cls.name`` (found along the MRO) is exactly a Stone Soup ``Property`` with no
    getter, read from the slot :func:`property_slot` names."""
    found = next((c.__dict__[name] for c in cls.__mro__ if name in c.__dict__), None)
    return type(found) is Property and found._getter is None \
        and found._property_name == property_slot(name)


def has_setter(prop: Property) -> bool:
    """Whether the Property ``prop`` is set through a setter rather than its slot."""
    return prop._setter is not None


def take_attribute(obj, name: str):
    """Removes the attribute ``name`` (not a Property) from a Stone Soup object's instance
    dictionary and returns it; None when it has none."""
    return vars(obj).pop(name, None)


# --- tracks -----------------------------------------------------------------------------------
#: The slots ``Track([state])`` sets, and its plain (non-Property) metadata list.
TRACK_STATES = property_slot("states")
TRACK_ID = property_slot("id")
TRACK_INIT_METADATA = property_slot("init_metadata")
TRACK_METADATAS = "metadatas"

#: ``update_track_metadata(track, state)``: appends the metadata ``track`` has after
#: ``state`` to ``track.metadatas``, as ``Track`` does for each state it is given (the stock
#: method itself, ``Track._update_metadata_from_state``).
update_track_metadata = Track._update_metadata_from_state


def live_tracks(tracker) -> set:
    """The live set of a Stone Soup ``MultiTargetMixtureTracker``'s tracks (the one its
    ``tracks`` returns), to update in place."""
    return tracker._tracks


# --- updaters -----------------------------------------------------------------------------------
def check_measurement_model(updater, model):
    """The measurement model ``updater`` uses for a detection measured by ``model``: ``model``,
    else the updater's own; ``ValueError`` (Stone Soup's) when both are None."""
    return updater._check_measurement_model(model)


def log_space_product(updater, a, b):
    """The Bernoulli particle updater's product of log-space matrices ``a`` and ``b``."""
    return updater._log_space_product(a, b)


def measurement_loglikelihoods(updater, prediction, detections):
    """The SMC-PHD updater's log-likelihood of every detection at every particle of
    ``prediction``, (N, len(detections))."""
    return updater._get_measurement_loglikelihoods(prediction, detections)


# --- the PDA gate -------------------------------------------------------------------------------
@functools.lru_cache(maxsize=256)
def _chi2_quantile(prob_gate: float, ndim: int) -> float:
    return float(chi2.ppf(prob_gate, ndim))


def gate_threshold(prob_gate, ndim: int) -> float:
    r"""The PDA gate on the squared Mahalanobis distance, :math:`\gamma = F^{-1}_{\chi^2_n}(P_G)`
    for ``ndim`` measured values: the value Stone Soup's PDA hypothesiser compares with (a
    test holds the two equal)."""
    return _chi2_quantile(float(prob_gate), int(ndim))


# --- from_state -------------------------------------------------------------------------------
def from_state_classes(base: type) -> dict:
    """``{state type: class}``: what ``base.from_state(state)`` builds for a state of each
    registered type (the nearest registered type along the state's MRO applies)."""
    return CreatableFromState.class_mapping[base]


#: Each Stone Soup internal ctxmodels relies on (see the module docstring) -> the names of
#: this module that reach it. ``tests/upstream/test_internals.py`` checks every entry against
#: the installed Stone Soup.
INTERNALS = {
    "stonesoup.base.Property._property_name": ("property_slot", "plain_property"),
    "stonesoup.base.Property._getter": ("plain_property",),
    "stonesoup.base.Property._setter": ("has_setter",),
    "stonesoup.base.Base.__init__ (an instance is its slots)": ("property_slot",
                                                                "take_attribute"),
    "stonesoup.types.track.Track.metadatas": ("TRACK_STATES", "TRACK_ID",
                                               "TRACK_INIT_METADATA", "TRACK_METADATAS"),
    "stonesoup.types.track.Track._update_metadata_from_state": ("update_track_metadata",),
    "stonesoup.updater.base.Updater._check_measurement_model": ("check_measurement_model",),
    "stonesoup.tracker.simple.MultiTargetMixtureTracker._tracks": ("live_tracks",),
    "stonesoup.updater.particle.BernoulliParticleUpdater._log_space_product":
        ("log_space_product",),
    "stonesoup.updater.particle.SMCPHDUpdater._get_measurement_loglikelihoods":
        ("measurement_loglikelihoods",),
    "stonesoup.hypothesiser.probability.PDAHypothesiser._gate_threshold": ("gate_threshold",),
    "stonesoup.types.state.CreatableFromState.class_mapping": ("from_state_classes",),
}

#: The private attribute names of Stone Soup this module reads or calls (no other module of
#: ctxmodels does).
PRIVATE_NAMES = frozenset({
    "_property_name", "_getter", "_setter", "_update_metadata_from_state",
    "_check_measurement_model", "_tracks", "_log_space_product",
    "_get_measurement_loglikelihoods",
})

__all__ = [
    "INTERNALS", "PRIVATE_NAMES", "TRACK_ID", "TRACK_INIT_METADATA", "TRACK_METADATAS",
    "TRACK_STATES", "check_measurement_model", "from_state_classes", "gate_threshold",
    "has_setter", "live_tracks", "log_space_product", "measurement_loglikelihoods",
    "plain_property", "property_slot", "take_attribute", "update_track_metadata",
]
