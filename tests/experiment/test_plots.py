"""The experiment's figures: what each one says (legends, labels, markings) is checked on
the matplotlib Figure before saving; that each writes a PNG, on small synthetic inputs."""
import math

import matplotlib  # noqa: F401 (a test dependency: without it these tests fail, not skip)
import numpy as np
import pytest

from ctxmodels.experiment import coverage_plots, summary_plots, track_plots
from ctxmodels.experiment.track_plots import Polyline, classify_tracks, inlier_mask

PNG = b"\x89PNG\r\n\x1a\n"


def legend_texts(fig) -> str:
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
    return " | ".join(t.get_text() for legend in legends for t in legend.get_texts()).lower()


def assert_png(path):
    data = path.read_bytes()
    assert data.startswith(PNG) and len(data) > 1000


def line(times, start, velocity):
    times = np.asarray(times, dtype=float)
    return Polyline(times, np.asarray(start) + np.outer(times, velocity))


@pytest.fixture
def scene():
    times = np.arange(0.0, 20.0, 1.0)
    truths = [line(times, (0, 0), (5, 0)), line(times, (0, 200), (0, -5))]
    inlier = line(times, (3, 4), (5, 0))  # 5 m off the first truth all along
    rng = np.random.default_rng(0)
    clutter = [Polyline(times[:8], rng.uniform(-500, 500, 2) + rng.normal(0, 4, (8, 2)).cumsum(0))
               for _ in range(300)]
    clutter.append(Polyline([3.0], [[5000.0, 5000.0]]))  # one state, far outside the view
    ego = line(times, (-50, -50), (1, 1))
    return dict(truths=truths, tracks=[inlier, *clutter], ego=ego,
                static=np.array([[40.0, 60.0], [-30.0, 20.0]]),
                land=[np.array([[100.0, 100.0], [150.0, 100.0], [150.0, 150.0]])])


# --- classify_tracks -------------------------------------------------------------------


def test_classify_on_truth_is_inlier_and_far_is_clutter():
    times = np.arange(10.0)
    truth = line(times, (0, 0), (10, 0))
    on = line(times, (0, 0), (10, 0))
    far = line(times, (0, 1000), (10, 0))
    inliers, clutter = classify_tracks([far, on], [truth])
    assert inliers == [on] and clutter == [far]


def test_classify_half_near_is_an_inlier_and_less_is_clutter():
    times = np.arange(10.0)
    truth = line(times, (0, 0), (10, 0))
    half = Polyline(times, truth.xy + np.where(times[:, None] < 5, 0.0, 100.0))
    fewer = Polyline(times, truth.xy + np.where(times[:, None] < 4, 0.0, 100.0))
    assert list(inlier_mask([half, fewer], [truth])) == [True, False]


def test_classify_needs_truth_at_the_same_time_and_respects_distance():
    truth = Polyline([0.0, 1.0], [[0, 0], [10, 0]])
    shifted = Polyline([0.5, 1.5], [[0, 0], [10, 0]])  # same place, no truth at its times
    edge = Polyline([0.0, 1.0], [[0, 30.0], [10, 30.0]])
    assert list(inlier_mask([shifted, edge], [truth], distance=30.0)) == [False, True]
    assert list(inlier_mask([edge], [truth], distance=29.9)) == [False]
    assert classify_tracks([], [truth]) == ([], [])
    assert list(inlier_mask([edge], [])) == [False]


def reference_mask(tracks, truths, distance=track_plots.INLIER_DISTANCE):
    """The rule as a plain loop over states, to check the vectorised one against."""
    truth_at = {}
    for truth in truths:
        for t, p in zip(truth.times, truth.xy):
            truth_at.setdefault(round(float(t), 6), []).append(p)
    out = []
    for track in tracks:
        near = 0
        for t, p in zip(track.times, track.xy):
            points = truth_at.get(round(float(t), 6))
            if points:
                near += bool(np.min(np.hypot(*(np.asarray(points) - p).T)) <= distance)
        out.append(near >= len(track.times) / 2)
    return out


def test_classify_matches_the_per_state_rule_on_random_tracks():
    rng = np.random.default_rng(7)
    grid = np.arange(0.0, 30.0, 0.5)
    truths = [Polyline(grid[a:b], rng.uniform(-60, 60, (b - a, 2)))
              for a, b in [(0, 60), (10, 40), (20, 60), (0, 5)]]
    tracks = []
    for _ in range(400):
        n = int(rng.integers(0, 12))
        times = np.sort(rng.choice(np.arange(0.0, 32.0, 0.25), n, replace=False))
        tracks.append(Polyline(times, rng.uniform(-80, 80, (n, 2))))
    assert list(inlier_mask(tracks, truths)) == reference_mask(tracks, truths)


# --- plot_tracks -----------------------------------------------------------------------


def test_track_figure_legend_and_labels(scene):
    fig = track_plots._figure_tracks("islands: jpda", scene["tracks"], scene["truths"], scene["ego"],
                               math.pi / 4, land=scene["land"], static_positions=scene["static"])
    ax = fig.axes[0]
    texts = legend_texts(fig)
    for word in ("truth", "inlier tracks (1)", "clutter tracks (301)", "static objects",
                 "ego path", "ego final pose", "land"):
        assert word in texts, (word, texts)
    assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)"
    assert "beyond this view" in ax.get_title()  # the far single-state clutter track
    # Zoomed to the truths and the ego, not the far clutter.
    assert ax.get_xlim()[1] < 1000 and ax.get_ylim()[1] < 1000
    # The clutter is one LineCollection (plus dots for one-state tracks), beneath the inliers.
    from matplotlib.collections import LineCollection
    collections = [c for c in ax.collections if isinstance(c, LineCollection)]
    assert len(collections) == 2
    clutter, inliers = sorted(collections, key=lambda c: c.get_zorder())
    assert len(clutter.get_segments()) == 300 and len(inliers.get_segments()) == 1
    assert clutter.get_alpha() < 0.5


def test_static_objects_differ_from_clutter_in_marker_and_colour(scene):
    fig = track_plots._figure_tracks("", scene["tracks"], scene["truths"], scene["ego"], 0.0,
                               static_positions=scene["static"])
    legend = fig.axes[0].get_legend()
    handles = dict(zip([t.get_text() for t in legend.get_texts()], legend.legend_handles))
    static = next(h for text, h in handles.items() if text.startswith("static"))
    clutter = next(h for text, h in handles.items() if text.startswith("clutter"))
    assert static.get_marker() == "D" and clutter.get_marker() in ("None", None, "")
    assert static.get_markeredgecolor() != clutter.get_color()


def test_plot_tracks_writes_png_with_old_call(scene, tmp_path):
    path = tmp_path / "tracks.png"
    track_plots.plot_tracks(path, "t", scene["tracks"], scene["truths"], scene["ego"], 0.3,
                      scene["land"], scene["static"], 400.0)
    assert_png(path)
    fig = track_plots._figure_tracks("t", scene["tracks"], scene["truths"], scene["ego"], 0.3,
                               extent=400.0)
    end = scene["ego"].xy[-1]
    assert fig.axes[0].get_xlim() == pytest.approx((end[0] - 400, end[0] + 400))


def test_plot_tracks_without_truth_tracks_or_zoom(tmp_path):
    ego = Polyline([0.0, 1.0], [[0, 0], [1, 1]])
    path = tmp_path / "empty.png"
    track_plots.plot_tracks(path, "nothing", [], [], ego, 0.0, zoom=False)
    assert_png(path)


def test_tracks_on_static_objects_are_distractors_not_clutter(scene):
    truth = scene["truths"][0]
    times = truth.times
    marker = Polyline(times, np.tile([40.0, 60.0], (len(times), 1)) + 2.0)  # on a marker
    half = Polyline(times, np.vstack([np.tile([40.0, 60.0], (10, 1)),
                                      np.tile([900.0, 900.0], (10, 1))]))  # half on it
    stray = Polyline(times, np.tile([700.0, -700.0], (len(times), 1)))
    inliers, distractors, clutter = classify_tracks([marker, half, stray, truth], [truth],
                                                    static_positions=scene["static"])
    assert inliers == [truth] and distractors == [marker, half] and clutter == [stray]
    # without static objects: the two-way split as before
    assert classify_tracks([marker, stray], [truth]) == ([], [marker, stray])
    fig = track_plots._figure_tracks("", [marker, stray, truth], [truth], scene["ego"], 0.0,
                               static_positions=scene["static"])
    texts = legend_texts(fig)
    assert "distractor tracks (1)" in texts and "clutter tracks (1)" in texts
    assert "1 distractor" in fig.axes[0].get_title()


def test_track_panels_side_by_side_each_with_its_own_counts(scene, tmp_path):
    inlier, clutter = scene["tracks"][0], scene["tracks"][1:4]
    panels = [("JPDA (tuned)", [inlier, *clutter]), ("GM-PHD (uniform)", []),
              ("GM-PHD (context-aware)", [inlier])]
    fig = track_plots._figure_track_panels("Scenario 1", panels, scene["truths"], scene["ego"], 0.0,
                                     static_positions=scene["static"])
    axes = [ax for ax in fig.axes if ax.get_legend()]
    assert len(axes) == 3
    titles = [ax.get_title() for ax in axes]
    assert [t.splitlines()[0] for t in titles] == [name for name, _ in panels]
    legends = [" | ".join(t.get_text() for t in ax.get_legend().get_texts()) for ax in axes]
    assert "clutter tracks (3)" in legends[0] and "inlier tracks (1)" in legends[0]
    assert "clutter tracks (0)" in legends[1] and "inlier tracks (0)" in legends[1]
    for legend in legends:
        for word in ("truth", "distractor tracks", "static objects", "ego path"):
            assert word in legend
    assert axes[0].get_xlim() == axes[2].get_xlim()  # one view for all panels
    path = tmp_path / "fig4.png"
    track_plots.plot_track_panels(path, "t", panels, scene["truths"], scene["ego"], 0.0)
    assert_png(path)


def test_mechanism_figure_marks_both_sensors_and_says_where_a_tracker_has_no_mass(tmp_path):
    from ctxmodels.experiment.track_plots import MASS_FLOOR, _figure_mechanism, plot_mechanism
    times = np.arange(0.0, 10.0, 0.1)
    series = [("GM-PHD (uniform)", times, np.zeros(len(times))),
              ("GM-PHD (P_D-aware)", times, np.where(times > 2.0, 1.0, 1e-3))]
    radar, lidar = np.arange(0.0, 10.0, 1.25), times + 0.043
    fig = _figure_mechanism("mechanism", series, radar, lidar, (0.0, 8.0))
    texts = legend_texts(fig)
    assert "gm-phd (uniform)\n(no mass at any scan shown)" in texts
    assert "gm-phd (p_d-aware)" in texts and "no mass" not in texts.split("p_d-aware")[1]
    assert "radar scan" in texts and "lidar scan" in texts
    ax = fig.axes[0]
    assert ax.get_yscale() == "log" and ax.get_ylim()[0] == MASS_FLOOR
    assert ax.get_xlim() == (0.0, 8.0)
    vertical = [x for x in (np.asarray(line.get_xdata(), dtype=float) for line in ax.lines)
                if x.size == 2 and x[0] == x[1]]
    assert len(vertical) == len([t for t in radar if t <= 8.0])  # one line per radar scan
    path = tmp_path / "mechanism.png"
    plot_mechanism(path, "m", series, radar, lidar, (0.0, 8.0))
    assert_png(path)


# --- plot_coverage ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def coverage_figure():
    from ctxmodels.experiment.sensors import paper_sensor_models
    land = [np.array([[300.0, 300.0], [500.0, 300.0], [500.0, 500.0]])]
    return coverage_plots._figure_coverage(paper_sensor_models(land=land), (0.0, 0.0, math.pi / 2),
                                  land=land, resolution=40, title="coverage")


def test_coverage_labels_colour_bar_and_heading_legend(coverage_figure):
    maps = [ax for ax in coverage_figure.axes if ax.images]
    assert len(maps) == 6  # two extents × (radar, lidar, any sensor)
    for ax in maps:
        assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)"
        assert "±" in ax.get_title() and "m" in ax.get_title()
    bars = [ax for ax in coverage_figure.axes if not ax.images]
    assert len(bars) == 1 and bars[0].get_ylabel().startswith("P_D")
    texts = legend_texts(coverage_figure)
    assert "ego heading" in texts and "land" in texts


def test_plot_coverage_writes_png(tmp_path):
    from ctxmodels.experiment.sensors import paper_sensor_models
    path = tmp_path / "coverage.png"
    coverage_plots.plot_coverage(path, {"lidar": paper_sensor_models()["lidar"]}, (5.0, 5.0, 0.0),
                        extents=(100.0,), resolution=30)
    assert_png(path)


def _coastal_radar():
    from ctxmodels import (ClutterDensityModel, DetectionProbabilityModel, RadarEquation,
                           RadarHorizon, SensorModel)
    return SensorModel(detection=DetectionProbabilityModel(factors=[
        RadarEquation(reference_snr=20.0, reference_range=5000.0, false_alarm_probability=1e-6,
                      swerling=3, pulses=2),
        RadarHorizon(antenna_height=15.0, target_height=5.0)]),
        clutter=ClutterDensityModel(factors=[1e-8]))


def test_coverage_draws_the_radar_curves_and_the_horizon():
    radar = _coastal_radar()
    fig = coverage_plots._figure_coverage({"coast": radar}, (0.0, 0.0, 0.0), extents=(20_000.0,),
                                          resolution=60, height=5.0)
    curves = [ax for ax in fig.axes if ax.get_xlabel() == "range (m)"]
    assert len(curves) == 1
    lines = {line.get_label(): line for line in curves[0].get_lines()}
    assert {f"Swerling {c}" for c in (0, 1, 2, 4)} | {"Swerling 3 (the model's)"} <= set(lines)
    own = lines["Swerling 3 (the model's)"]
    assert own.get_linewidth() > lines["Swerling 1"].get_linewidth()
    ranges = np.asarray(own.get_xdata())
    np.testing.assert_array_equal(own.get_ydata(), radar.detection.factors[0](ranges))
    # the horizon of a 5 m target from a 15 m antenna (2kR = 2 · 4/3 · 6 371 km), drawn and named
    reach = 2 * 4 / 3 * 6_371_000.0
    horizon = math.sqrt(reach * 15) + math.sqrt(reach * 5)
    assert coverage_plots.horizon_range(radar, 5.0) == pytest.approx(horizon, rel=1e-3)
    assert f"{horizon / 1000:,.1f} km" in legend_texts(fig)
    # a horizon at each target's height reads the drawn height
    assert coverage_plots.horizon_range(_air_radar(), 200.0) == pytest.approx(
        math.sqrt(reach * 25) + math.sqrt(reach * 200), rel=1e-12)
    (plan,) = [ax for ax in fig.axes if ax.images]
    rings = [c for c in plan.collections if hasattr(c, "get_paths")]
    radii = [np.hypot(*path.vertices.T) for c in rings for path in c.get_paths() if len(path.vertices)]
    assert radii and all(abs(r.mean() - horizon) < 2 * 40_000 / 60 for r in radii)
    # a horizon beyond the map is named as not drawn; two radar equations are said to be
    from ctxmodels import DetectionProbabilityModel, SensorModel
    near = coverage_plots._figure_coverage({"coast": radar}, (0.0, 0.0, 0.0), extents=(1000.0,),
                                           resolution=20)
    assert "(not on these maps)" in legend_texts(near)
    twice = SensorModel(detection=DetectionProbabilityModel(factors=[
        *radar.detection.factors, radar.detection.factors[0]]), clutter=radar.clutter)
    fig = coverage_plots._figure_coverage({"coast": twice}, (0.0, 0.0, 0.0), extents=(1000.0,),
                                          resolution=20)
    (curves,) = [ax for ax in fig.axes if ax.get_xlabel() == "range (m)"]
    assert "the first of its 2 radar equations" in curves.get_title()
    # without a radar equation or a horizon: neither
    fig = coverage_plots._figure_coverage({"lidar": _air_radar()}, (0.0, 0.0, 0.0),
                                          extents=(1000.0,), resolution=20)
    assert not [ax for ax in fig.axes if ax.get_xlabel() == "range (m)"]


def _air_radar():
    from ctxmodels import (ClutterDensityModel, DetectionProbabilityModel, ElevationSector,
                           Mounting, RadarHorizon, RangeBands, SensorModel)
    return SensorModel(detection=DetectionProbabilityModel(factors=[
        0.9, RangeBands(edges=(60_000,), values=(1, 0)),
        ElevationSector(lower=math.radians(-1), upper=math.radians(30)),
        RadarHorizon(antenna_height=25, target_height=None)]),
        clutter=ClutterDensityModel(factors=[1e-9]), position_mapping=(0, 2, 4),
        mounting=Mounting(up=25))


def test_a_3d_models_section_is_its_pd_against_range_and_height():
    """The section along the heading: P_D at (range, height) as the model gives it for a
    target there (the beam's 30° edge, the slant range, the horizon of a low target)."""
    ranges, heights, grids = coverage_plots.section_grid({"air": _air_radar()},
                                                         (0.0, 0.0, 0.0), 70_000.0, 8_000.0, 141)
    grid = grids["air"]
    at = lambda r, h: grid[np.argmin(np.abs(heights - h)), np.argmin(np.abs(ranges - r))]  # noqa: E731
    assert at(20_000, 2_000) == 0.9
    assert at(2_000, 4_000) == 0.0  # above the beam: elevation 63°
    assert at(65_000, 4_000) == 0.0  # slant range beyond 60 km
    assert at(40_000, 0) == 0.0  # a target on the sea beyond the 20.6 km horizon
    assert at(10_000, 0) == 0.9


def test_a_3d_model_adds_its_section_row(tmp_path):
    from ctxmodels.experiment.sensors import paper_sensor_models
    models = {"air": _air_radar(), "lidar": paper_sensor_models()["lidar"]}
    fig = coverage_plots._figure_coverage(models, (0.0, 0.0, 0.0), extents=(70_000.0,),
                                          resolution=30, height=200.0)
    maps = [ax for ax in fig.axes if ax.images]
    assert len(maps) == 6  # (plan, section) × (air, lidar, any sensor)
    assert [ax.get_ylabel() for ax in maps[3:]] == ["height (m)"] * 3
    assert "targets 200 m up" in maps[0].get_title()
    path = tmp_path / "air.png"
    coverage_plots.plot_coverage(path, models, (0.0, 0.0, 0.0), extents=(70_000.0,),
                                 resolution=30, ceiling=5_000.0)
    assert_png(path)


# --- plot_summary ----------------------------------------------------------------------

NAN3 = [np.nan] * 3


def summary_inputs():
    return dict(tracker_labels=["JPDA", "GM-PHD context", "GM-PHD sight"],
                hota=np.array([[40, 37, 43], [63, 61, 65], NAN3]),
                gospa=np.array([[120, 110, 130], [72, 69, 76], NAN3]),
                finding_labels=["context − P_D-aware", "radar+lidar − radar", "n/a one"],
                hota_diff=np.array([[5, 3, 7], [1, -2, 4], NAN3]),
                gospa_diff=np.array([[-8, -11, -5], [np.nan, np.nan, np.nan], NAN3]),
                verdicts=["reproduced", "inconclusive", "not reproduced"])


def test_summary_panels_units_directions_and_verdict_legend():
    fig = summary_plots._figure_summary(**summary_inputs(), title="islands")
    hota, gospa, d_hota, d_gospa = fig.axes
    assert "(%)" in hota.get_xlabel() and "(m)" in gospa.get_xlabel()
    assert "percentage points" in d_hota.get_xlabel() and "(m)" in d_gospa.get_xlabel()
    assert "higher is better" in hota.get_title() and "lower is better" in gospa.get_title()
    assert "A better" in d_hota.get_title() and "A better" in d_gospa.get_title()
    texts = legend_texts(fig)
    for verdict in ("reproduced", "not reproduced", "inconclusive", "95 % interval"):
        assert verdict in texts
    # NaN rows are skipped (no point drawn) and said to be n/a.
    points = [len(ax.containers) for ax in (hota, gospa, d_hota, d_gospa)]  # errorbars
    assert points == [2, 2, 2, 1]
    assert sum("n/a" in t.get_text() for t in d_gospa.texts) == 2
    assert any(abs(x) < 1e-12 for line in d_hota.lines for x in line.get_xdata()[:1]
               if len(line.get_xdata()) == 2)  # the zero line


def test_summary_all_nan_and_shape_errors(tmp_path):
    inputs = summary_inputs()
    for key in ("hota", "gospa", "hota_diff", "gospa_diff"):
        inputs[key] = np.full((3, 3), np.nan)
    path = tmp_path / "summary.png"
    summary_plots.plot_summary(path, **inputs)
    assert_png(path)
    with pytest.raises(ValueError, match="hota"):
        summary_plots.plot_summary(path, **{**inputs, "hota": np.zeros((2, 3))})
    with pytest.raises(ValueError, match="verdicts"):
        summary_plots.plot_summary(path, **{**inputs, "verdicts": ["reproduced"]})


def test_summary_track_management_row_per_tracker(tmp_path):
    inputs = summary_inputs()
    fig = summary_plots._figure_summary(**inputs, false_tracks=[2.13, 0.37, np.nan],
                                        tracked=[77.2, 83.8, np.nan])
    titles = [ax.get_title() for ax in fig.axes]
    assert any(t.startswith("False tracks per radar scan") for t in titles)
    assert any(t.startswith("Vessel time tracked") for t in titles)
    assert len(fig.axes) == 6  # scores, track management, differences
    ax = next(ax for ax in fig.axes if ax.get_title().startswith("False tracks"))
    assert [t.get_text() for t in ax.get_yticklabels()] == inputs["tracker_labels"]
    notes = [t.get_text() for t in ax.texts]
    assert any("n/a" in n for n in notes)  # the tracker without a value
    with pytest.raises(ValueError, match="tracked"):
        summary_plots._figure_summary(**inputs, tracked=[1.0, 2.0])
    path = tmp_path / "summary.png"
    summary_plots.plot_summary(path, **inputs, false_tracks=[1, 2, 3], tracked=[4, 5, 6])
    assert_png(path)


def test_summary_without_findings_draws_the_scores_only(tmp_path):
    inputs = summary_inputs()
    fig = summary_plots._figure_summary(
        inputs["tracker_labels"], inputs["hota"], inputs["gospa"], [], np.zeros((0, 3)),
        np.zeros((0, 3)), [], title="Scenario 2")
    assert len(fig.axes) == 2  # no empty difference panels
    assert not fig.legends  # no verdict legend for no verdicts
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert "no data" not in texts
    assert [ax.get_xlabel() for ax in fig.axes] == ["HOTA (%)", "GOSPA (m)"]


# --- plot_sensitivity ------------------------------------------------------------------


def marked_cells(fig):
    return {patch.get_gid(): patch.get_linestyle() for ax in fig.axes for patch in ax.patches
            if (patch.get_gid() or "").startswith("excludes-zero:")}


def test_sensitivity_marks_exactly_the_cells_whose_interval_excludes_zero():
    diff = np.array([[0.5, 2.0, -3.0], [np.nan, 1.0, 0.0]])
    low = np.array([[-0.5, 1.0, -4.0], [np.nan, 0.0, -1.0]])  # 0.0: touches 0, not excluded
    high = np.array([[1.5, 3.0, -2.0], [np.nan, 2.0, 1.0]])
    fig = summary_plots._figure_sensitivity("A − B", "clutter", [1, 2, 4], "bearing std (°)",
                                            [0.5, 1.0], diff, low, high, "HOTA (pp)")
    cells = marked_cells(fig)
    assert set(cells) == {"excludes-zero:0,1", "excludes-zero:0,2"}
    assert cells["excludes-zero:0,1"] == "-"  # favours (higher is better)
    assert cells["excludes-zero:0,2"] != "-"  # against: dashed
    ax = fig.axes[0]
    assert sum(t.get_text() == "n/a" for t in ax.texts) == 1
    bold = [t.get_text().split("\n")[0] for t in ax.texts if t.get_fontweight() == "bold"]
    assert sorted(bold) == ["+2", "-3"]
    assert ax.get_xlabel() == "clutter" and ax.get_ylabel() == "bearing std (°)"
    colourbar = fig.axes[1]
    assert colourbar.get_ylabel() == "HOTA (pp) difference"
    vmin, vmax = ax.images[0].get_clim()
    assert vmin == -vmax  # centred at 0
    texts = legend_texts(fig)
    assert "excludes 0" in texts and "n/a" in texts


def test_sensitivity_title_stays_inside_a_narrow_figure():
    label = ("closest other − uniform: the uniform GM-PHD is the worst of the paper's five "
             "(margin to the closest)")
    fig = summary_plots._figure_sensitivity(label, "radar bearing σ (°)", [0.5, 1.0], "", [0.0],
                                            np.array([[23.4, 14.6]]), np.array([[23.0, 13.1]]),
                                            np.array([[23.8, 16.0]]), "ΔHOTA (pp)")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    title = fig.axes[0].title.get_window_extent(canvas.get_renderer())
    assert title.x0 >= 0 and title.x1 <= fig.bbox.width, (title, fig.bbox)


def test_sensitivity_lower_is_better_flips_what_favours():
    fig = summary_plots._figure_sensitivity("A − B", "clutter", [1, 2], "", [0],
                                            [-2.0, 2.0], [-3.0, 1.0], [-1.0, 3.0], "GOSPA (m)",
                                            better="lower")
    cells = marked_cells(fig)
    assert cells["excludes-zero:0,0"] == "-" and cells["excludes-zero:0,1"] != "-"
    assert fig.axes[0].get_yticks().size == 0  # one row, no y setting to name


def test_plot_sensitivity_writes_png_and_checks_shapes(tmp_path):
    path = tmp_path / "sensitivity.png"
    grid = np.full((1, 3), np.nan)
    summary_plots.plot_sensitivity(path, "A − B", "x", [1, 2, 3], "y", [7], grid, grid, grid,
                                   "HOTA (pp)")
    assert_png(path)
    with pytest.raises(ValueError, match="diff"):
        summary_plots.plot_sensitivity(path, "A − B", "x", [1, 2], "y", [7], grid, grid, grid,
                                       "HOTA (pp)")
