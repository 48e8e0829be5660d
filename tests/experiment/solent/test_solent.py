"""The Solent study: its declared window and truth rules, the simulated radars' coverage (its
own NumPy geometry) against the trackers' context models (the core), determinism, and the
study run end to end through the command line."""
import numpy as np
import pytest

from ctxmodels import Pose
from ctxmodels.cli import main
from ctxmodels.experiment.solent import radars, scene
from ctxmodels.experiment.solent.run import make_solent
from ctxmodels.experiment.solent.trackers import site_models
from ctxmodels.geo.plane import lonlat_to_local

from ...cli.setups import usage_error


def test_the_window_is_the_declared_rules():
    assert scene.busiest_window() == scene.WINDOW_START


def test_sites_are_on_the_shore_and_see_what_the_scene_says():
    models = site_models("context")
    platform = Pose(x=0.0, y=0.0, heading=0.0)
    places = {"eastern Spithead": (-1.06, 50.74), "south of the Isle of Wight": (-1.15, 50.55),
              "off Ryde": (-1.17, 50.74), "Channel east of the Nab": (-0.85, 50.67)}
    xy = lonlat_to_local(list(places.values()), scene.ORIGIN)
    states = np.column_stack([xy[:, 0], np.zeros(len(xy)), xy[:, 1], np.zeros(len(xy))])
    seen = {name: (model.detection.evaluate(model.sensor_pose(platform), states) > 0).tolist()
            for name, model in models.items()}
    assert seen == {"foreland": [True, True, False, True], "southsea": [True, False, True, False]}


def test_truth_coverage_matches_the_context_models():
    """The simulation's NumPy geometry and the trackers' core models agree on what each radar
    sees, wherever nudging a point by half a metre does not change the truth's answer."""
    rng = np.random.default_rng(7)
    corners = lonlat_to_local([(scene.BOX[0], scene.BOX[1]), (scene.BOX[2], scene.BOX[3])], scene.ORIGIN)
    points = rng.uniform(corners[0], corners[1], (6000, 2))
    points = points[radars.on_water(points, scene.land())]
    models = site_models("context")
    platform = Pose(x=0.0, y=0.0, heading=0.0)
    states = np.column_stack([points[:, 0], np.zeros(len(points)), points[:, 1], np.zeros(len(points))])
    for site in scene.SITES:
        truth = radars.covered(site, points, scene.land())
        nudged = [radars.covered(site, points + d, scene.land())
                  for d in ([0.5, 0], [-0.5, 0], [0, 0.5], [0, -0.5])]
        robust = np.all([n == truth for n in nudged], axis=0)
        model = models[site.name]
        context = model.detection.evaluate(model.sensor_pose(platform), states) > 0
        assert robust.mean() > 0.99
        np.testing.assert_array_equal(context[robust], truth[robust])
        assert 0.02 < truth.mean() < 0.9


def test_truth_is_known_on_water_within_reach_and_seen_once():
    run = make_solent(3)
    log = scene.traffic()
    by_mmsi = {t.mmsi: t for t in log.trajectories}
    assert run.truths
    xy, owner = [], []
    for path in run.truths:
        mmsi = int(path.id.split("/")[0])
        times = np.array([(s.timestamp - log.epoch).total_seconds() for s in path.states])
        states = np.array([[s.state_vector[0, 0], s.state_vector[2, 0]] for s in path.states])
        np.testing.assert_allclose(states, by_mmsi[mmsi].position_at(times), atol=1e-9)
        xy.append(states)
        owner += [mmsi] * len(states)
    xy, owner = np.concatenate(xy), np.array(owner)
    assert radars.on_water(xy, scene.land()).all()
    assert np.logical_or.reduce([radars.within_reach(site, xy) for site in scene.SITES]).all()
    # every scored vessel is seen by some radar at some time; land may hide it meanwhile
    covered = np.logical_or.reduce([radars.covered(site, xy, scene.land()) for site in scene.SITES])
    assert set(owner[covered]) == set(owner)
    assert not covered.all()  # (the window has vessels behind land for a while)
    # every vessel detection is of a path at its time, and within that radar's coverage
    for site in scene.SITES:
        for scan in run.scans[site.name]:
            for detection in scan.detections:
                if detection.metadata["source"] == "target":
                    state = detection.groundtruth_path[scan.timestamp]
                    xy = np.array([[state.state_vector[0, 0], state.state_vector[2, 0]]])
                    assert radars.covered(site, xy, scene.land()).all()


def test_same_seed_same_run():
    def signature(run):
        return [(name, scan.timestamp, sorted((d.metadata["source"], float(d.state_vector[0, 0]),
                                               float(d.state_vector[1, 0])) for d in scan.detections))
                for name, scans in run.scans.items() for scan in scans]
    first, again, other = make_solent(5, 30.0), make_solent(5, 30.0), make_solent(6, 30.0)
    assert signature(first) == signature(again)
    assert signature(first) != signature(other)
    periods = [np.diff([s.timestamp.timestamp() for s in first.scans[site.name]]) for site in scene.SITES]
    assert [set(np.round(p, 6)) for p in periods] == [{2.5}, {1.0}]


def test_the_study_runs_on_the_solent(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["experiment", "--scenarios", "solent", "--seeds", "2", "--duration", "60",
                 "--workers", "1", "--quiet", "--no-plots", "--output", str(out)]) == 0
    text = (out / "findings.md").read_text()
    assert "radar-only GM-PHD > uniform (Solent)" in text
    results = (out / "results.csv").read_text()
    for tracker in ("gmphd-uniform", "gmphd-radar-only", "gmphd-pd-aware", "gmphd-sight", "gmphd-learned"):
        assert f"{tracker},solent," in results


@pytest.mark.parametrize("argv, option", [
    (["experiment", "--scenarios", "solent", "--truth", "stress"], "--truth"),
    (["experiment", "--scenarios", "solent", "--radar-clutter", "1", "2"], "--radar-clutter"),
    (["sweep", "--scenarios", "solent"], "--scenarios"),
    (["experiment", "--scenarios", "solent", "--trackers", "jpda"], "--trackers"),
])
def test_the_solent_refuses_what_does_not_apply(argv, option, tmp_path, capsys):
    line = usage_error([*argv, "--output", str(tmp_path / "o")], capsys)
    assert f"argument {option}:" in line
    assert not (tmp_path / "o").exists()


def test_same_numbers_with_one_worker_or_two():
    from ctxmodels.experiment.runner import ExperimentConfig, run_experiment
    scores = []
    for workers in (1, 2):
        config = ExperimentConfig(scenarios=("solent",), trackers=("gmphd-uniform", "gmphd-sight"),
                                  seeds=(21, 22), duration=40.0, workers=workers, plot_seed=None)
        results = run_experiment(config, progress=False)
        scores.append(sorted((r.job.tracker, r.job.seed, r.hota.hota, float(r.gospa.rms))
                             for r in results.results))
    assert scores[0] == scores[1]
    assert len({s[2] for s in scores[0]}) > 1
