//! Criterion benchmarks of the Rust core: P_D over 10³…10⁷ states (the paper's radar) and
//! per call for 1, 10 and 100 states,
//! land-mask containment and line of sight on deterministic coastlines of 10²…10⁵ vertices
//! (smooth and jagged), expected P_D (cubature rules) against P_D at the mean, and clutter
//! density with metadata rules.
//!
//! Run `cargo bench --bench core` (a few minutes on 2 cores); narrow it with a filter, e.g.
//! `cargo bench --bench core -- land`. Throughput is reported per state / point / target.
//! The NumPy and Shapely comparison lives in `benches/compare.py`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode, Throughput};
use ctxmodels::{
    AngularSector, ClutterFactor, ClutterModel, DetectionFactor, DetectionModel, LandMask, LineOfSight,
    MetadataThreshold, Polygon, Pose, PositionMapping, RangeBands, Rule,
};
use std::f64::consts::{PI, TAU};
use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

/// SplitMix64: a tiny deterministic generator, so the inputs never change with a crate
/// version.
struct SplitMix(u64);

impl SplitMix {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

const COAST_RADIUS: f64 = 1000.0;
/// Queries are drawn uniformly over this square around the island (centred on the origin).
const QUERY_HALF_WIDTH: f64 = 1600.0;
/// The sensor for line of sight: at sea, west of the island.
const SENSOR: [f64; 2] = [-1500.0, 250.0];

/// A star-shaped island of `n` vertices (always a simple polygon): a smooth lobed outline,
/// or the same outline with quasi-random radial spikes of up to 10 % of the radius at every
/// vertex — long thin edges that cross many index cells (the hard case for a grid). Same
/// formula as `coastline()` in benches/compare.py.
fn coastline(n: usize, jagged: bool) -> Vec<[f64; 2]> {
    const GOLDEN: f64 = 0.618_033_988_749_894_9;
    (0..n)
        .map(|k| {
            let t = TAU * k as f64 / n as f64;
            let mut r = COAST_RADIUS * (1.0 + 0.3 * (3.0 * t).sin() + 0.1 * (7.0 * t + 0.5).cos());
            if jagged {
                r *= 1.0 - 0.1 * ((k as f64 * GOLDEN) % 1.0);
            }
            [r * t.cos(), r * t.sin()]
        })
        .collect()
}

fn land(n: usize, jagged: bool) -> Arc<LandMask> {
    Arc::new(
        LandMask::new(vec![Polygon {
            shell: coastline(n, jagged),
            holes: vec![],
        }])
        .expect("a star-shaped ring is valid"),
    )
}

fn query_points(n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = SplitMix(seed);
    (0..n)
        .map(|_| {
            [
                rng.uniform(-QUERY_HALF_WIDTH, QUERY_HALF_WIDTH),
                rng.uniform(-QUERY_HALF_WIDTH, QUERY_HALF_WIDTH),
            ]
        })
        .collect()
}

/// The paper's radar: 0.4 between 50 m (exclusive) and 1612 m (exclusive), blind astern
/// over 65° (π ± 32.5°).
fn radar_factors() -> Vec<DetectionFactor> {
    vec![
        DetectionFactor::Range(RangeBands::new(vec![50.0, 1612.0], vec![0.0, 0.4, 0.0], vec![false, true]).unwrap()),
        DetectionFactor::Sector(AngularSector::new(PI, 65f64.to_radians(), 0.0, 1.0).unwrap()),
    ]
}

/// (N, 4) constant-velocity states [x, vx, y, vy] within 2 km of the sensor.
fn states(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix(seed);
    let mut s = Vec::with_capacity(4 * n);
    for _ in 0..n {
        s.extend([
            rng.uniform(-2000.0, 2000.0),
            rng.uniform(-10.0, 10.0),
            rng.uniform(-2000.0, 2000.0),
            rng.uniform(-10.0, 10.0),
        ]);
    }
    s
}

fn covariances(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix(seed);
    let mut c = vec![0.0; 16 * n];
    for i in 0..n {
        let (sx, sy, rho) = (rng.uniform(5.0, 60.0), rng.uniform(5.0, 60.0), rng.uniform(-0.8, 0.8));
        let block = &mut c[16 * i..16 * (i + 1)];
        block[0] = sx * sx;
        block[2] = rho * sx * sy;
        block[8] = rho * sx * sy;
        block[10] = sy * sy;
        block[5] = 1.0;
        block[15] = 1.0;
    }
    c
}

fn pose() -> Pose {
    Pose::new(SENSOR[0], SENSOR[1], 0.3).unwrap()
}

fn pd_radar(c: &mut Criterion) {
    let model = DetectionModel::new(radar_factors()).unwrap();
    let pose = Pose::new(0.0, 0.0, 0.3).unwrap();
    let scan = model.at_pose(&pose);
    let mut group = c.benchmark_group("pd_radar");
    group.sampling_mode(SamplingMode::Flat);
    for exp in 3..=7u32 {
        let n = 10usize.pow(exp);
        if n >= 1_000_000 {
            group.sample_size(10).measurement_time(Duration::from_secs(3));
        }
        let s = states(n, 1);
        let mut out = vec![0.0; n];
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(format!("1e{exp}")), &s, |b, s| {
            b.iter(|| {
                scan.at_states(black_box(s), 4, PositionMapping::default(), &mut out)
                    .unwrap()
            })
        });
    }
    group.finish();
}

/// The core's cost per call for the few states a tracker asks about at once: N = 1, 10,
/// 100 rows (one thread, no allocation), and one point through the scalar reference.
fn pd_call(c: &mut Criterion) {
    let model = DetectionModel::new(radar_factors()).unwrap();
    let scan = model.at_pose(&Pose::new(0.0, 0.0, 0.3).unwrap());
    let mut group = c.benchmark_group("pd_call");
    for n in [1usize, 10, 100] {
        let s = states(n, 8);
        let mut out = vec![0.0; n];
        group.bench_function(format!("rows/{n}"), |b| {
            b.iter(|| {
                scan.at_states(black_box(&s), 4, PositionMapping::default(), &mut out)
                    .unwrap()
            })
        });
    }
    group.bench_function("at_point", |b| {
        b.iter(|| scan.at_point(black_box(420.0), black_box(-75.0)))
    });
    group.finish();
}

fn expected_pd(c: &mut Criterion) {
    let model = DetectionModel::new(radar_factors()).unwrap();
    let pose = Pose::new(0.0, 0.0, 0.3).unwrap();
    let scan = model.at_pose(&pose);
    let rules = [
        ("mean", Rule::mean()),
        ("cubature", Rule::cubature()),
        ("unscented", Rule::unscented()),
        ("gauss_hermite_3", Rule::gauss_hermite(3).unwrap()),
    ];
    // 10⁴ Gaussians (one thread, in cache) and 10⁵ (two threads; the covariances, 128 B
    // each, come from L3 or memory).
    for exp in [4u32, 5] {
        let n = 10usize.pow(exp);
        let means = states(n, 2);
        let covars = covariances(n, 3);
        let mut out = vec![0.0; n];
        let mut group = c.benchmark_group(format!("expected_pd_1e{exp}"));
        group.throughput(Throughput::Elements(n as u64));
        group.bench_function("at_mean_states", |b| {
            b.iter(|| {
                scan.at_states(black_box(&means), 4, PositionMapping::default(), &mut out)
                    .unwrap()
            })
        });
        for (name, rule) in &rules {
            group.bench_function(*name, |b| {
                b.iter(|| {
                    scan.expected_at_gaussians(
                        black_box(&means),
                        &covars,
                        4,
                        PositionMapping::default(),
                        rule,
                        &mut out,
                    )
                    .unwrap()
                })
            });
        }
        group.finish();
    }
}

const QUERIES: usize = 100_000;

fn land_contains(c: &mut Criterion) {
    let points = query_points(QUERIES, 4);
    let mut group = c.benchmark_group("land_contains");
    group.throughput(Throughput::Elements(QUERIES as u64));
    for jagged in [false, true] {
        for exp in 2..=5u32 {
            let mask = land(10usize.pow(exp), jagged);
            let id = format!("{}/1e{exp}", if jagged { "jagged" } else { "smooth" });
            group.bench_function(id, |b| {
                b.iter(|| black_box(&points).iter().filter(|&&p| mask.contains(p)).count())
            });
        }
    }
    group.finish();
}

fn land_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("land_build");
    group.sample_size(10);
    for jagged in [false, true] {
        for exp in [4u32, 5] {
            let ring = coastline(10usize.pow(exp), jagged);
            let id = format!("{}/1e{exp}", if jagged { "jagged" } else { "smooth" });
            group.bench_function(id, |b| {
                b.iter(|| {
                    LandMask::new(vec![Polygon {
                        shell: black_box(ring.clone()),
                        holes: vec![],
                    }])
                    .unwrap()
                })
            });
        }
    }
    group.finish();
}

fn line_of_sight(c: &mut Criterion) {
    let targets = query_points(QUERIES, 5);
    let mut group = c.benchmark_group("line_of_sight");
    group.sampling_mode(SamplingMode::Flat).sample_size(10);
    group.throughput(Throughput::Elements(QUERIES as u64));
    for jagged in [false, true] {
        for exp in 2..=5u32 {
            let sight = LineOfSight::new(land(10usize.pow(exp), jagged)).unwrap();
            let id = format!("{}/1e{exp}", if jagged { "jagged" } else { "smooth" });
            group.bench_function(format!("pairwise/{id}"), |b| {
                b.iter(|| {
                    black_box(&targets)
                        .iter()
                        .filter(|&&t| sight.visible(SENSOR, t))
                        .count()
                })
            });
            // One scan: build the per-position index, then answer every target.
            group.bench_function(format!("index/{id}"), |b| {
                b.iter(|| {
                    let index = sight.from_point(black_box(SENSOR));
                    black_box(&targets).iter().filter(|&&t| index.visible(t)).count()
                })
            });
        }
    }
    group.finish();
}

fn sight_index_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("sight_index_build");
    for jagged in [false, true] {
        for exp in [4u32, 5] {
            let sight = LineOfSight::new(land(10usize.pow(exp), jagged)).unwrap();
            let id = format!("{}/1e{exp}", if jagged { "jagged" } else { "smooth" });
            group.bench_function(id, |b| b.iter(|| sight.from_point(black_box(SENSOR)).len()));
        }
    }
    group.finish();
}

/// P_D of the radar with land and line of sight, as one scan evaluates it.
fn pd_radar_with_land(c: &mut Criterion) {
    let mut group = c.benchmark_group("pd_radar_land_sight_1e5");
    let n = 100_000;
    let s = states(n, 6);
    let mut out = vec![0.0; n];
    group.throughput(Throughput::Elements(n as u64));
    for jagged in [false, true] {
        let mask = land(10_000, jagged);
        let mut factors = radar_factors();
        factors.push(DetectionFactor::Land(mask.clone()));
        factors.push(DetectionFactor::Sight(Arc::new(LineOfSight::new(mask).unwrap())));
        let model = DetectionModel::new(factors).unwrap();
        let pose = pose();
        let scan = model.at_pose(&pose);
        group.bench_function(if jagged { "jagged_1e4" } else { "smooth_1e4" }, |b| {
            b.iter(|| {
                scan.at_states(black_box(&s), 4, PositionMapping::default(), &mut out)
                    .unwrap()
            })
        });
    }
    group.finish();
}

fn clutter(c: &mut Criterion) {
    // The paper's lidar rule (segment area < 10 → 1e-1, else 1e-3; missing → 1e-2) on top
    // of a radar-like range rule.
    let model = ClutterModel::new(vec![
        ClutterFactor::Range(RangeBands::new(vec![1000.0], vec![1e-3, 1e-2], vec![true]).unwrap()),
        ClutterFactor::Metadata(MetadataThreshold {
            column: 0,
            threshold: 10.0,
            below: 1e-1,
            at_or_above: 1e-3,
            missing: Some(1e-2),
        }),
        ClutterFactor::Metadata(MetadataThreshold {
            column: 1,
            threshold: 0.5,
            below: 2.0,
            at_or_above: 0.5,
            missing: None,
        }),
    ])
    .unwrap();
    let pose = pose();
    let mut group = c.benchmark_group("clutter");
    for exp in [2u32, 4, 6] {
        let m = 10usize.pow(exp);
        let mut rng = SplitMix(7);
        let positions: Vec<f64> = (0..2 * m).map(|_| rng.uniform(-2000.0, 2000.0)).collect();
        let metadata: Vec<f64> = (0..m)
            .flat_map(|i| {
                [
                    if i % 10 == 0 { f64::NAN } else { (i % 37) as f64 },
                    (i % 3) as f64 * 0.4,
                ]
            })
            .collect();
        let mut out = vec![0.0; m];
        group.throughput(Throughput::Elements(m as u64));
        group.bench_function(format!("1e{exp}"), |b| {
            b.iter(|| {
                model
                    .evaluate(&pose, black_box(&positions), &metadata, &mut out)
                    .unwrap()
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    // Short warm-up and measurement keep the full run to a few minutes on 2 cores.
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(20);
    targets = pd_radar, pd_call, expected_pd, land_contains, land_build, line_of_sight, sight_index_build, pd_radar_with_land, clutter
}
criterion_main!(benches);
