"""ctxmodels under the detector-context interface of Stone Soup's pull request #1291 (the
stand-in of ``tests/upstream/upstream_interface.py``, installed in a fresh process before
anything imports ctxmodels) and under released Stone Soup; and its Stone Soup plugin entry
point."""
import subprocess
import sys
from pathlib import Path

import stonesoup.base

import ctxmodels

TESTS = Path(__file__).resolve().parent

UNDER_STANDIN = r'''
import math, pickle, sys
sys.path.insert(0, TESTS)
import upstream_interface
standin = upstream_interface.install()

import numpy as np
import ctxmodels
from stonesoup.base import Base
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.serialise import YAML
from stonesoup.types.detection import Detection, DetectionSet as UpstreamSet
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.numeric import Probability
from stonesoup.types.prediction import GaussianStatePrediction

# Both interfaces at once: a Stone Soup component and the upstream abstract class.
assert issubclass(ctxmodels.DetectorContext, standin.DetectorContext)
assert issubclass(ctxmodels.DetectorContext, Base)
assert issubclass(ctxmodels.DetectionSet, UpstreamSet)
sensor = ctxmodels.SensorModel(
    detection=ctxmodels.DetectionProbabilityModel(factors=[
        ctxmodels.RangeBands(edges=(50.0, 1612.0), values=(0.0, 0.4, 0.0), upper_owns=(False, True)),
        ctxmodels.AngularSector.blind(math.pi, math.radians(65))]),
    clutter=ctxmodels.ClutterDensityModel(factors=[
        ctxmodels.RangeBands(edges=(1000.0,), values=(1e-5, 2e-5))]))
context = sensor.context((10.0, -20.0, 0.4))
assert isinstance(context, standin.DetectorContext)
assert not type(context).__abstractmethods__  # both abstract methods implemented
scan = ctxmodels.DetectionSet([], context)
assert isinstance(scan, UpstreamSet) and scan.detector_context is context

# A stock-style consumer asks per hypothesis and per detection, as the pull request's
# updaters do; the answers are the ones of ctxmodels' array calls.
rng = np.random.default_rng(3)
means = rng.uniform(-1800, 1800, size=(200, 4))
hypotheses = [SingleHypothesis(GaussianStatePrediction(m.reshape(-1, 1), np.eye(4)), None)
              for m in means]
per_call = [context.prob_detection(h) for h in hypotheses]
assert all(isinstance(p, Probability) for p in per_call)
array = context.prob_detection_array(means)
assert [p.log_value for p in per_call] == [Probability(v).log_value for v in array]
model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.eye(2))
detections = [Detection(m[[0, 2]].reshape(-1, 1), measurement_model=model) for m in means[:50]]
per_detection = [context.clutter_spatial_density(d) for d in detections]
assert per_detection == list(context.clutter_spatial_density_detections(detections))
assert set(per_detection) == {1e-5, 2e-5}

# Still a Stone Soup component: it prints, pickles and round-trips through YAML.
assert repr(context).startswith("DetectorContext(")
copy = pickle.loads(pickle.dumps(context))
assert isinstance(copy, standin.DetectorContext)
assert copy.prob_detection_array(means).tobytes() == array.tobytes()
loaded = YAML().load(YAML().dumps(context))
assert loaded.prob_detection_array(means).tobytes() == array.tobytes()

# The pull request's scalar-or-callable context, unchanged beside ours.
simple = standin.SimpleDetectorContext(0.7, lambda detection: 3e-4)
assert float(simple.prob_detection(hypotheses[0])) == 0.7
assert simple.clutter_spatial_density(detections[0]) == 3e-4
print("ok")
'''


def test_import_and_use_under_the_upstream_interface():
    result = subprocess.run([sys.executable, "-c", f"TESTS = {str(TESTS)!r}\n" + UNDER_STANDIN],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok"


def test_released_stonesoup_has_no_upstream_base():
    """Under Stone Soup 1.9.1 the context is a plain Stone Soup component and the set a set."""
    assert ctxmodels.DetectorContext.__bases__ == (stonesoup.base.Base,)
    assert ctxmodels.DetectionSet.__bases__ == (set,)


def test_stonesoup_plugin_entry_point():
    """``stonesoup.plugins`` loads every package registered under its entry-point group."""
    result = subprocess.run(
        [sys.executable, "-c",
         "import stonesoup.plugins.ctxmodels as plugin, ctxmodels; "
         "assert plugin is ctxmodels; print(plugin.DetectorContext.__name__)"],
        capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "DetectorContext"


def test_dependency_range_admits_development_builds_of_1_9():
    """Stone Soup's pull-request branch builds as 1.9.devN; releases up to 2 are admitted."""
    from importlib.metadata import requires

    from packaging.requirements import Requirement

    (stonesoup_req,) = [Requirement(r) for r in requires("ctxmodels")
                        if Requirement(r).name == "stonesoup"]
    admitted = {v: stonesoup_req.specifier.contains(v, prereleases=True)
                for v in ("1.8.3", "1.9.dev347", "1.9", "1.9.1", "1.12.0", "2.0.dev1", "2.0")}
    assert admitted == {"1.8.3": False, "1.9.dev347": True, "1.9": True, "1.9.1": True,
                        "1.12.0": True, "2.0.dev1": False, "2.0": False}


def test_metadata_names_the_interfaces_it_plugs_into():
    """Project URLs: Stone Soup and its DetectorContext pull request (no homepage is
    claimed: the project has none yet)."""
    from importlib.metadata import metadata

    urls = dict(entry.split(", ", 1) for entry in metadata("ctxmodels").get_all("Project-URL"))
    assert urls == {"Stone Soup": "https://stonesoup.readthedocs.io",
                    "Stone Soup DetectorContext proposal":
                        "https://github.com/dstl/Stone-Soup/pull/1291"}
