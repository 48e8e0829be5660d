//! Property-based fuzzing of the core's public surface: every constructor and evaluator,
//! fed random and hostile input (degenerate, duplicate and collinear vertices, huge and tiny
//! coordinates, NaN, ±inf, mismatched shapes), returns `Ok` or `Err` and never panics —
//! a panic here would otherwise reach the Python binding. When it returns `Ok`, P_D lies in
//! [0, 1] and λ is finite and > 0.
//!
//! The case count per property is proptest's: 256 by default (keeps `cargo test` fast);
//! set `PROPTEST_CASES=20000 cargo test --release fuzz` for a long run.
//!
//! One file, though long: the properties share the input strategies below (which
//! `detection/column_tests.rs` uses too), and what the whole public surface promises is
//! read in one place.

use crate::batch::PositionMapping;
use crate::clutter::{ClutterFactor, ClutterModel, MetadataThreshold};
use crate::cubature::{cholesky2, Rule};
use crate::detection::{DetectionFactor, DetectionModel};
use crate::land::{LandMask, Polygon};
use crate::pose::{Mounting, Pose};
use crate::range_bands::RangeBands;
use crate::sector::AngularSector;
use crate::sight::LineOfSight;
use proptest::prelude::*;
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

/// Any float, weighted towards the values that break geometry code.
fn wild() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -2000.0..2000.0f64,
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(f64::MAX),
        1 => Just(f64::MIN_POSITIVE),
        1 => Just(5e-324),
        1 => prop_oneof![Just(1e300), Just(-1e300), Just(1e-300), Just(1e154), Just(-1e154)],
        1 => any::<f64>(),
        1 => (-20i32..20).prop_map(f64::from),
    ]
}

/// Mostly finite, moderate coordinates (so that constructors succeed often enough to test
/// the evaluators), sometimes wild.
fn coord() -> impl Strategy<Value = f64> {
    prop_oneof![8 => -1000.0..1000.0f64, 2 => (-50i32..50).prop_map(f64::from), 1 => wild()]
}

fn probability() -> impl Strategy<Value = f64> {
    prop_oneof![6 => 0.0..=1.0f64, 1 => Just(0.0), 1 => Just(1.0), 1 => wild()]
}

fn density() -> impl Strategy<Value = f64> {
    prop_oneof![6 => 1e-6..10.0f64, 1 => Just(1e-300), 1 => Just(1e300), 1 => Just(5e-324), 1 => wild()]
}

fn angle() -> impl Strategy<Value = f64> {
    prop_oneof![6 => -TAU..TAU, 1 => Just(PI), 1 => Just(TAU), 1 => Just(0.0), 1 => wild()]
}

/// Star-shaped ring around a centre: random radii at sorted random angles (spiky when the
/// radii vary a lot), optionally with duplicated and collinear (mid-edge) vertices and scaled
/// to huge or tiny size.
fn star_ring() -> impl Strategy<Value = Vec<[f64; 2]>> {
    (
        (coord(), coord()),
        prop::collection::vec((0.0..TAU, 0.0..100.0f64), 3..40),
        prop_oneof![4 => Just(1.0), 1 => Just(1e-9), 1 => Just(1e9), 1 => Just(1e150), 1 => Just(1e-150)],
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(|((cx, cy), mut spokes, scale, duplicate, collinear, close)| {
            spokes.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut ring: Vec<[f64; 2]> = spokes
                .iter()
                .map(|&(t, r)| [cx + scale * r * t.cos(), cy + scale * r * t.sin()])
                .collect();
            if duplicate {
                let p = ring[ring.len() / 2];
                ring.insert(ring.len() / 2, p);
            }
            if collinear {
                let (a, b) = (ring[0], ring[1]);
                ring.insert(1, [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]);
            }
            if close {
                ring.push(ring[0]);
            }
            ring
        })
}

/// Integer-grid rings: exercise exact vertex-on-walk and collinear-edge cases.
fn grid_ring() -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop::collection::vec((-8i32..8, -8i32..8), 0..10)
        .prop_map(|v| v.into_iter().map(|(x, y)| [f64::from(x), f64::from(y)]).collect())
}

/// Arbitrary vertex soup (self-intersecting, degenerate, non-finite).
fn soup_ring() -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop::collection::vec([coord(), coord()], 0..12)
}

fn ring() -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop_oneof![4 => star_ring(), 2 => grid_ring(), 2 => soup_ring()]
}

fn polygons() -> impl Strategy<Value = Vec<Polygon>> {
    prop::collection::vec(
        (ring(), prop::collection::vec(ring(), 0..2)).prop_map(|(shell, holes)| Polygon { shell, holes }),
        0..3,
    )
}

/// A land mask that validated, or a small fixed one (star with a hole) when the random one did not.
fn land() -> impl Strategy<Value = Arc<LandMask>> {
    polygons().prop_map(|p| {
        Arc::new(LandMask::new(p).unwrap_or_else(|_| {
            LandMask::new(vec![Polygon {
                shell: vec![[-100.0, -100.0], [100.0, -100.0], [100.0, 100.0], [-100.0, 100.0]],
                holes: vec![vec![[-10.0, -10.0], [10.0, -10.0], [0.0, 10.0]]],
            }])
            .unwrap()
        }))
    })
}

fn points() -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop::collection::vec([coord(), coord()], 0..64)
}

fn range_bands_args() -> impl Strategy<Value = (Vec<f64>, Vec<f64>, Vec<bool>)> {
    prop_oneof![
        // well-formed: sorted distinct edges, n + 1 values
        4 => prop::collection::vec(0.0..3000.0f64, 0..5).prop_flat_map(|mut e| {
            e.sort_by(f64::total_cmp);
            e.dedup();
            let n = e.len();
            (Just(e), prop::collection::vec(probability(), n + 1), prop::collection::vec(any::<bool>(), n))
        }),
        // anything
        1 => (prop::collection::vec(wild(), 0..5), prop::collection::vec(wild(), 0..6), prop::collection::vec(any::<bool>(), 0..5)),
    ]
}

pub(crate) fn detection_factor() -> impl Strategy<Value = Option<DetectionFactor>> {
    prop_oneof![
        2 => probability().prop_map(|v| Some(DetectionFactor::Constant(v))),
        3 => range_bands_args().prop_map(|(e, v, u)| RangeBands::new(e, v, u).ok().map(DetectionFactor::Range)),
        3 => (angle(), prop_oneof![3 => 0.0..=TAU, 1 => wild()], probability(), probability())
            .prop_map(|(c, w, i, o)| AngularSector::new(c, w, i, o).ok().map(DetectionFactor::Sector)),
        1 => land().prop_map(|l| Some(DetectionFactor::Land(l))),
        1 => land().prop_map(|l| Some(DetectionFactor::Sight(Arc::new(LineOfSight::new(l).unwrap())))),
        2 => (prop_oneof![3 => -20.0..40.0f64, 1 => wild()], prop_oneof![3 => 1.0..5e3f64, 1 => wild()],
              prop_oneof![3 => 1e-12..0.5f64, 1 => wild()], 0u8..6, 0u64..40)
            .prop_map(|(snr, range, pfa, case, pulses)| {
                let swerling = crate::radar::Swerling::from_case(case).ok()?;
                crate::radar::RadarEquation::new(snr, range, 1.0, pfa, swerling, pulses).ok().map(DetectionFactor::Radar)
            }),
        2 => (prop_oneof![3 => -1.6..1.6f64, 1 => wild()], prop_oneof![3 => -1.6..1.6f64, 1 => wild()], probability(), probability())
            .prop_map(|(lo, hi, i, o)| crate::elevation::ElevationSector::new(lo, hi, i, o).ok().map(DetectionFactor::Elevation)),
        1 => (prop_oneof![3 => 0.0..1e5f64, 1 => wild()], prop_oneof![3 => 1.0..2e7f64, 1 => wild()])
            .prop_map(|(a, s)| crate::horizon::Horizon::new(a, s).ok().map(DetectionFactor::Horizon)),
    ]
}

fn clutter_factor() -> impl Strategy<Value = Option<ClutterFactor>> {
    prop_oneof![
        2 => density().prop_map(|v| Some(ClutterFactor::Constant(v))),
        2 => range_bands_args().prop_flat_map(|(e, v, u)| {
            let n = v.len();
            (Just(e), prop::collection::vec(density(), n), Just(u))
        }).prop_map(|(e, v, u)| RangeBands::new(e, v, u).ok().map(ClutterFactor::Range)),
        3 => (0usize..4, wild(), density(), density(), prop::option::of(density())).prop_map(|(column, threshold, below, at_or_above, missing)| {
            Some(ClutterFactor::Metadata(MetadataThreshold { column, threshold, below, at_or_above, missing }))
        }),
        1 => (land(), 0.0..200.0f64, density(), any::<bool>())
            .prop_map(|(l, w, v, seen)| crate::coast::CoastalBand::new(l, w, v, seen).ok().map(|b| ClutterFactor::Coast(Arc::new(b)))),
        1 => (land(), density(), density())
            .prop_map(|(l, i, o)| crate::zone::Zone::new(l, i, o).ok().map(|z| ClutterFactor::Zone(Arc::new(z)))),
        1 => (-2.0..2.0f64, -2.0..2.0f64, density(), density())
            .prop_map(|(lo, hi, i, o)| crate::elevation::ElevationSector::new(lo, hi, i, o).ok().map(ClutterFactor::Elevation)),
    ]
}

pub(crate) fn pose() -> impl Strategy<Value = (f64, f64, f64)> {
    (coord(), coord(), prop_oneof![4 => angle(), 1 => wild()])
}

/// State rows: usually a consistent (N, ncols) block, sometimes a ragged length.
pub(crate) fn states() -> impl Strategy<Value = (Vec<f64>, usize, usize)> {
    (0usize..7, 0usize..80, any::<bool>()).prop_flat_map(|(ncols, n, ragged)| {
        let len = n * ncols + usize::from(ragged && ncols > 1);
        (
            prop::collection::vec(prop_oneof![9 => coord(), 1 => wild()], len),
            Just(ncols),
            Just(n),
        )
    })
}

/// (x, y) and, about every third time, a height column.
pub(crate) fn mapping() -> impl Strategy<Value = (usize, usize, Option<usize>)> {
    prop_oneof![
        4 => Just((0, 2, None)),
        2 => Just((0, 2, Some(4))),
        1 => (0usize..7, 0usize..7, prop::option::of(0usize..7))
    ]
}

pub(crate) fn mapping_of((x, y, z): (usize, usize, Option<usize>)) -> Option<PositionMapping> {
    match z {
        None => PositionMapping::new(x, y).ok(),
        Some(z) => PositionMapping::raised(x, y, z).ok(),
    }
}

fn rule() -> impl Strategy<Value = Option<Rule>> {
    prop_oneof![
        Just(Some(Rule::mean())),
        Just(Some(Rule::cubature())),
        Just(Some(Rule::unscented())),
        (0usize..8).prop_map(|k| Rule::gauss_hermite(k).ok()),
    ]
}

proptest! {
    #[test]
    fn land_mask_never_panics_and_agrees_with_its_own_rings(polygons in polygons(), pts in points()) {
        if let Ok(mask) = LandMask::new(polygons) {
            prop_assert!(mask.vertex_count() >= 3);
            for p in pts.iter().chain([[f64::NAN, 0.0], [f64::INFINITY, f64::NEG_INFINITY], [f64::MAX, -f64::MAX]].iter()) {
                let _ = mask.contains(*p);
            }
            // Every validated vertex is on the boundary, which counts as land.
            for poly in mask.polygons() {
                for v in poly.shell.iter().chain(poly.holes.iter().flatten()) {
                    prop_assert!(mask.contains(*v), "vertex {:?} of a validated mask is not on land", v);
                }
            }
        }
    }

    #[test]
    fn line_of_sight_never_panics(land in land(), sensor in [coord(), coord()], pts in points(),
                                  clearance in prop_oneof![Just(0.0), 0.0..50.0f64, Just(1e308)]) {
        let sight = LineOfSight::with_clearance(land.clone(), clearance).unwrap();
        for t in &pts {
            let _ = sight.visible(sensor, *t);
        }
        if sensor[0].is_finite() && sensor[1].is_finite() {
            let index = sight.from_point(sensor);
            for t in &pts {
                let fast = index.visible(*t);
                // Beyond ~1e300 the sensor→target difference overflows: a pinned known issue
                // (`known_issue_sight_of_overflowing_segment`).
                let sane = |p: [f64; 2]| p[0].abs() < 1e300 && p[1].abs() < 1e300;
                if sane(*t) && sane(sensor) {
                    prop_assert_eq!(fast, sight.visible(sensor, *t), "index and ray cast disagree for {:?} -> {:?}", sensor, t);
                }
            }
        }
    }

    #[test]
    fn range_bands_never_panic_and_return_one_of_their_values((e, v, u) in range_bands_args(), r in wild()) {
        if let Ok(bands) = RangeBands::new(e.clone(), v, u) {
            let value = bands.at(r.abs());
            prop_assert!(value.is_nan() || bands.values().contains(&value) || r.is_nan());
            if let Some(sq) = bands.squared() {
                let r = r.abs();
                // Squares of edges or ranges outside ~[1e-150, 1e150] round to 0 or inf: a
                // pinned known issue (`known_issue_squared_bands_with_subnormal_squares`).
                let normal = |v: f64| v == 0.0 || (1e-150..1e150).contains(&v.abs());
                if normal(r) && e.iter().all(|&e| normal(e)) {
                    prop_assert_eq!(sq.at_squared(r * r).to_bits(), bands.at(r).to_bits());
                }
            }
        }
    }

    #[test]
    fn poses_and_mountings_never_panic(p in (wild(), wild(), wild()), m in (wild(), wild(), wild())) {
        let pose = Pose::new(p.0, p.1, p.2);
        prop_assert_eq!(pose.is_ok(), p.0.is_finite() && p.1.is_finite() && p.2.is_finite());
        let mounting = Mounting::new(m.0, m.1, m.2);
        prop_assert_eq!(mounting.is_ok(), m.0.is_finite() && m.1.is_finite() && m.2.is_finite());
        if let (Ok(pose), Ok(mounting)) = (pose, mounting) {
            let mounted = pose.mount(&mounting);
            if let Ok(sensor) = mounted {
                prop_assert!(sensor.x.is_finite() && sensor.y.is_finite() && sensor.heading.is_finite());
                let _ = sensor.frame();
            }
        }
    }

    #[test]
    fn cholesky_never_panics(a in wild(), b in wild(), bt in wild(), c in wild()) {
        if let Some(l) = cholesky2(a, b, bt, c) {
            prop_assert!(l.iter().all(|v| v.is_finite() || !v.is_nan()));
        }
    }

    #[test]
    fn detection_model_never_panics_and_pd_is_a_probability(
        factors in prop::collection::vec(detection_factor(), 0..5),
        p in pose(),
        (states, ncols, n) in states(),
        m in mapping(),
        height in prop_oneof![3 => Just(0.0), 1 => coord()],
        tilt in prop_oneof![3 => Just((0.0, 0.0)), 2 => (angle(), angle()), 1 => (wild(), wild())],
        out_len_delta in prop_oneof![8 => Just(0i64), 1 => Just(-1i64), 1 => Just(1i64)],
    ) {
        let factors: Vec<DetectionFactor> = factors.into_iter().flatten().collect();
        let Ok(model) = DetectionModel::new(factors) else { return Ok(()); };
        let Ok(pose) = Pose::raised(p.0, p.1, p.2, height).and_then(|p| p.tilted(tilt.0, tilt.1)) else { return Ok(()); };
        let Some(mapping) = mapping_of(m) else { return Ok(()); };
        let scan = model.at_pose(&pose);
        let mut out = vec![-7.0; (n as i64 + out_len_delta).max(0) as usize];
        if scan.at_states(&states, ncols, mapping, &mut out).is_ok() {
            for (i, v) in out.iter().enumerate() {
                prop_assert!((0.0..=1.0).contains(v), "row {}: P_D {} outside [0, 1]", i, v);
            }
        }
    }

    #[test]
    fn expected_pd_never_panics_and_is_a_probability(
        factors in prop::collection::vec(detection_factor(), 0..4),
        p in pose(),
        (means, ncols, n) in states(),
        covar_kind in 0u8..5,
        wild_entry in wild(),
        rule in rule(),
        raised in any::<bool>(),
    ) {
        let factors: Vec<DetectionFactor> = factors.into_iter().flatten().collect();
        let Ok(model) = DetectionModel::new(factors) else { return Ok(()); };
        let Ok(pose) = Pose::new(p.0, p.1, p.2) else { return Ok(()); };
        let Some(rule) = rule else { return Ok(()); };
        // Covariances: identity × scale, huge, zero, indefinite, or with one wild entry.
        let mut covars = vec![0.0; n * ncols * ncols];
        for i in 0..n {
            for d in 0..ncols {
                covars[i * ncols * ncols + d * ncols + d] = match covar_kind {
                    0 => 100.0,
                    1 => 1e300,
                    2 => 0.0,
                    3 if d == 0 => -1.0,
                    _ => 1.0,
                };
            }
            if covar_kind == 4 && ncols > 0 {
                covars[i * ncols * ncols + (i % (ncols * ncols))] = wild_entry;
            }
        }
        let mut out = vec![-7.0; n];
        let scan = model.at_pose(&pose);
        let mapping = if raised { PositionMapping::raised(0, 2, 4).unwrap() } else { PositionMapping::default() };
        if scan.expected_at_gaussians(&means, &covars, ncols, mapping, &rule, &mut out).is_ok() {
            for (i, v) in out.iter().enumerate() {
                prop_assert!((0.0..=1.0).contains(v), "row {}: expected P_D {} outside [0, 1]", i, v);
            }
        }
        // A covariance array of the wrong length is an error, not a panic.
        let _ = scan.expected_at_gaussians(&means, &covars[..covars.len().saturating_sub(1)], ncols, mapping, &rule, &mut out);
    }

    #[test]
    fn clutter_model_never_panics_and_lambda_is_positive(
        factors in prop::collection::vec(clutter_factor(), 0..5),
        p in pose(),
        m in 0usize..50,
        values in prop::collection::vec(prop_oneof![6 => coord(), 1 => wild(), 1 => Just(f64::NAN)], 0..400),
        ragged in any::<bool>(),
    ) {
        let factors: Vec<ClutterFactor> = factors.into_iter().flatten().collect();
        // Whether some product of the factors' values leaves the normal f64 range: then λ
        // can round to 0 or overflow (then evaluate must refuse: `lambda_that_underflows_is_an_error`).
        let (mut lo, mut hi) = (1.0f64, 1.0f64);
        for f in &factors {
            let values: Vec<f64> = match f {
                ClutterFactor::Constant(v) => vec![*v],
                ClutterFactor::Range(b) => b.values().to_vec(),
                ClutterFactor::Metadata(r) => [r.below, r.at_or_above].into_iter().chain(r.missing).collect(),
                ClutterFactor::Map(m) => {
                    let map = crate::clutter::read_map(m);
                    map.intensities().unwrap().into_iter().chain([map.prior_intensity()]).collect()
                }
                ClutterFactor::Coast(band) => vec![band.inside(), 1.0],
                ClutterFactor::Zone(zone) => vec![zone.inside(), zone.outside()],
                ClutterFactor::Elevation(e) => e.values().to_vec(),
            };
            lo *= values.iter().fold(f64::INFINITY, |a, v| a.min(v.abs()));
            hi *= values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        }
        let extreme = lo < 1e-290 || hi > 1e290;
        let Ok(model) = ClutterModel::new(factors) else { return Ok(()); };
        let Ok(pose) = Pose::new(p.0, p.1, p.2) else { return Ok(()); };
        let k = model.metadata_columns();
        let take = |len: usize, offset: usize| -> Vec<f64> { (0..len).map(|i| values.get(i + offset).copied().unwrap_or(1.0)).collect() };
        let positions = take(2 * m + usize::from(ragged), 0);
        let metadata = take(k * m, 2 * m);
        let mut out = vec![-7.0; m];
        // rows with heights when the model reads them (and sometimes when it does not)
        let ncols = if model.uses_height() || ragged { 3 } else { 2 };
        let positions = if ncols == 3 { take(3 * m + usize::from(ragged), 0) } else { positions };
        if model.evaluate_rows(&pose, &positions, ncols, &metadata, None, &mut out).is_ok() {
            for (i, v) in out.iter().enumerate() {
                prop_assert!(v.is_finite() && (*v > 0.0 || extreme), "row {}: λ = {} is not finite and > 0", i, v);
            }
        }
    }
}

/// Regression (found by the property above): a product of valid tiny densities that
/// underflows to 0 is an error naming `factors`, never λ = 0 (trackers divide by λ).
#[test]
fn lambda_that_underflows_is_an_error() {
    let model = ClutterModel::new(vec![ClutterFactor::Constant(1e-200), ClutterFactor::Constant(1e-200)]).unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    let mut out = [1.0];
    let err = model.evaluate(&pose, &[0.0, 0.0], &[], &mut out).unwrap_err();
    assert_eq!(err.argument(), "factors");
}

/// Known issue, pinned: the ray-cast line of sight treats a segment whose coordinate
/// difference overflows (|x| ~ 1e308) as unobstructed, while the per-scan index blocks it.
#[test]
#[should_panic(expected = "index and ray cast disagree")]
fn known_issue_sight_of_overflowing_segment() {
    let square = Polygon {
        shell: vec![[-100.0, -100.0], [100.0, -100.0], [100.0, 100.0], [-100.0, 100.0]],
        holes: vec![],
    };
    let sight = LineOfSight::new(Arc::new(LandMask::new(vec![square]).unwrap())).unwrap();
    let (sensor, target) = ([-1e300, 0.0], [f64::MAX, 0.0]);
    assert_eq!(
        sight.from_point(sensor).visible(target),
        sight.visible(sensor, target),
        "index and ray cast disagree"
    );
}

/// Known issue, pinned: with an edge whose square underflows (1e-200 m) the squared-range
/// fast path puts r = 5e-324 in the band above the edge; `at` puts it below.
#[test]
#[should_panic(expected = "squared path disagrees")]
fn known_issue_squared_bands_with_subnormal_squares() {
    let bands = RangeBands::new(vec![1e-200], vec![1.0, 0.0], vec![true]).unwrap();
    let r = 5e-324;
    assert_eq!(
        bands.squared().unwrap().at_squared(r * r),
        bands.at(r),
        "squared path disagrees"
    );
}
