//! The lane kernels against the scalar reference [`ScanDetection::at_point`], bit for bit,
//! on every backend this CPU can run (AVX2 and portable on x86-64 with AVX2).
//!
//! One file, though long: every kernel is held to the same reference on the same backends
//! and models, set up once below.

use super::lanes::{expected_reference, AtStates, Expected, Gaussians};
use super::*;
use crate::batch::{Columns, CvRows, Positions, Rows};
use crate::cubature::cholesky2;
use crate::land::Polygon;
use crate::simd::{run_on, Backend};
use std::f64::consts::PI;

/// Every build this CPU runs: the AVX2 one only where the CPU has AVX2 (elsewhere these
/// tests check the portable build alone; tests/core/test_simd_dispatch.py checks that a CPU
/// with AVX2 runs the AVX2 build). Shared by the detection kernels' test files.
/// The integration rules the expected-P_D tests run: each kind, Gauss–Hermite of order 3.
pub(super) fn rules() -> [Rule; 4] {
    [
        Rule::mean(),
        Rule::cubature(),
        Rule::unscented(),
        Rule::gauss_hermite(3).unwrap(),
    ]
}

pub(super) fn backends() -> Vec<Backend> {
    [Backend::Portable, Backend::Avx2]
        .into_iter()
        .filter(|b| b.available())
        .collect()
}

/// A radar whose SNR is 10 dB at 300 m (P_D falls over the test rows' ranges).
fn radar(case: u8, pulses: u64) -> DetectionFactor {
    let swerling = crate::radar::Swerling::from_case(case).unwrap();
    DetectionFactor::Radar(crate::radar::RadarEquation::new(10.0, 300.0, 0.0, 1e-6, swerling, pulses).unwrap())
}

fn bands(edges: &[f64], values: &[f64], upper_owns: &[bool]) -> DetectionFactor {
    DetectionFactor::Range(RangeBands::new(edges.to_vec(), values.to_vec(), upper_owns.to_vec()).unwrap())
}

/// The paper's radar and lidar, a wide sector (cos(w/2) < 0), a full circle, many bands
/// (the square-root path), an island with land and line of sight, and products whose bits
/// depend on the factor order.
fn models() -> Vec<DetectionModel> {
    let island = Arc::new(
        LandMask::new(vec![Polygon {
            shell: vec![[300.0, -200.0], [600.0, -200.0], [600.0, 200.0], [300.0, 200.0]],
            holes: vec![],
        }])
        .unwrap(),
    );
    let sector = |centre: f64, width: f64, inside: f64, outside: f64| {
        DetectionFactor::Sector(AngularSector::new(centre, width, inside, outside).unwrap())
    };
    [
        vec![
            bands(&[50.0, 1612.0], &[0.0, 0.4, 0.0], &[false, true]),
            sector(PI, 65f64.to_radians(), 0.0, 1.0),
        ],
        vec![bands(&[50.0, 80.0], &[0.95, 0.2, 0.0], &[true, true])],
        vec![
            DetectionFactor::Constant(0.9),
            sector(1.0, 300f64.to_radians(), 0.7, 0.1),
            sector(-2.0, 2.0 * PI, 0.3, 0.0),
        ],
        vec![bands(
            &[100.0, 200.0, 300.0, 400.0, 500.0, 600.0],
            &[0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3],
            &[true, false, true, false, true, false],
        )],
        vec![
            DetectionFactor::Constant(0.9),
            DetectionFactor::Land(island.clone()),
            bands(&[700.0], &[0.93, 0.11], &[true]),
            DetectionFactor::Sight(Arc::new(LineOfSight::new(island.clone()).unwrap())),
        ],
        vec![
            DetectionFactor::Constant(0.3),
            sector(0.4, 2.5, 0.7, 0.9),
            bands(&[10.0, 1e3], &[0.7, 0.9, 0.1], &[false, false]),
        ],
        // Every specialised step sequence of the kernels (lanes::with_fixed_steps, and the
        // lone factors of P_D at points) is here:
        // none, one sector, bands then a narrow or a wide sector, sector then bands, one set
        // of bands, one edge (its edge owned by either side), a one-pulse radar equation of
        // either form.
        vec![DetectionFactor::Constant(0.6)],
        vec![sector(2.0, 1.0, 0.2, 0.8)],
        vec![bands(&[700.0], &[0.93, 0.11], &[true])],
        vec![bands(&[80.0], &[0.2, 0.7], &[false])],
        vec![radar(1, 1)],
        vec![radar(3, 1)],
        // the radar equation between other factors, and alone
        vec![
            bands(&[50.0, 80.0], &[0.95, 0.2, 0.0], &[true, true]),
            radar(0, 3),
            sector(PI, 65f64.to_radians(), 0.0, 1.0),
            DetectionFactor::Land(island.clone()),
        ],
        vec![radar(4, 5)],
        vec![radar(1, 1), radar(3, 4), radar(2, 2)],
        // bands then a sector wider than a half-plane (the radar's is narrower)
        vec![
            bands(&[50.0, 1612.0], &[0.0, 0.4, 0.0], &[false, true]),
            sector(0.5, 250f64.to_radians(), 0.3, 0.9),
        ],
    ]
    .into_iter()
    .map(|f| DetectionModel::new(f).unwrap())
    .collect()
}

/// (n, ncols) rows around the sensor at the origin, with some positions exactly on the
/// band edges (r² = e² in floating point) and a few far away.
fn rows(n: usize, ncols: usize, mapping: PositionMapping) -> Vec<f64> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let edges = [50.0, 80.0, 100.0, 600.0, 700.0, 1612.0];
    let mut data: Vec<f64> = (0..n * ncols).map(|_| uniform() * 3600.0 - 1800.0).collect();
    for i in (0..n).step_by(3) {
        let edge = edges[i % edges.len()];
        let (x, y) = if i % 2 == 0 { (edge, 0.0) } else { (0.0, -edge) };
        data[i * ncols + mapping.x] = x;
        data[i * ncols + mapping.y] = y;
    }
    if n > 7 {
        data[7 * ncols + mapping.x] = 1e300; // r² overflows to infinity
    }
    data
}

fn reference(scan: &ScanDetection, positions: impl Positions, n: usize) -> Vec<u64> {
    (0..n)
        .map(|i| {
            let [x, y] = positions.one(i);
            scan.at_point(x, y).to_bits()
        })
        .collect()
}

fn lanes(
    scan: &ScanDetection,
    backend: Backend,
    positions: impl Positions,
    first: usize,
    n: usize,
) -> (Vec<u64>, Option<usize>) {
    kernel_bits(
        scan,
        backend,
        positions,
        crate::batch::Planar,
        crate::batch::Still,
        first,
        n,
    )
}

/// The P_D kernel on `backend` over `n` states from `first`: its outputs' bits and the
/// first bad state it reports. Shared by the detection kernels' test files.
pub(super) fn kernel_bits<P: Positions, H: crate::batch::Heights, V: crate::batch::Velocities>(
    scan: &ScanDetection,
    backend: Backend,
    positions: P,
    heights: H,
    velocities: V,
    first: usize,
    n: usize,
) -> (Vec<u64>, Option<usize>) {
    let mut out = vec![f64::NAN; n];
    let bad = run_on(
        backend,
        AtStates {
            scan,
            positions,
            heights,
            velocities,
            first,
            out: &mut out,
        },
    );
    (out.into_iter().map(f64::to_bits).collect(), bad)
}

#[test]
fn every_layout_and_backend_gives_the_reference_bits() {
    let pose = Pose::new(0.0, 0.0, 0.3).unwrap();
    for model in models() {
        let scan = model.at_pose(&pose);
        for n in [1, 2, 3, 4, 5, 7, 8, 9, 1027] {
            let default = PositionMapping::default();
            let cv = rows(n, 4, default);
            let other = PositionMapping::new(4, 1).unwrap();
            let wide = rows(n, 6, other);
            let columns: Vec<f64> = (0..2)
                .flat_map(|j| (0..n).map(move |i| (i, j)))
                .map(|(i, j)| cv[i * 4 + 2 * j])
                .collect();
            let cols = Columns {
                xs: &columns[..n],
                ys: &columns[n..],
            };
            for backend in backends() {
                assert_eq!(
                    lanes(&scan, backend, CvRows(&cv), 0, n),
                    (reference(&scan, CvRows(&cv), n), None),
                    "{backend:?} n={n}"
                );
                let wide_rows = Rows {
                    data: &wide,
                    ncols: 6,
                    mapping: other,
                };
                assert_eq!(
                    lanes(&scan, backend, wide_rows, 0, n),
                    (reference(&scan, wide_rows, n), None),
                    "{backend:?} n={n}"
                );
                assert_eq!(
                    lanes(&scan, backend, cols, 0, n),
                    (reference(&scan, cols, n), None),
                    "{backend:?} n={n}"
                );
            }
        }
    }
}

#[test]
fn a_chunk_starting_mid_array_reads_its_own_rows() {
    let scan = models().remove(0).at_pose(&Pose::new(10.0, -4.0, 2.0).unwrap());
    let cv = rows(40, 4, PositionMapping::default());
    for backend in backends() {
        assert_eq!(
            lanes(&scan, backend, CvRows(&cv), 13, 27),
            (reference(&scan, CvRows(&cv[13 * 4..]), 27), None)
        );
    }
}

#[test]
fn the_first_non_finite_position_is_found_in_any_lane() {
    let scan = models().remove(0).at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    for n in [1, 6, 9, 64] {
        for bad in 0..n {
            for value in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let mut cv = rows(n, 4, PositionMapping::default());
                cv[bad * 4 + 2 * (bad % 2)] = value;
                if bad + 2 < n {
                    cv[(bad + 2) * 4] = f64::NAN; // a later one is not reported
                }
                // The same states as (n, 6) rows with the position in columns (4, 1), and as
                // (2, n) columns.
                let other = PositionMapping::new(4, 1).unwrap();
                let mut wide = vec![0.0; 6 * n];
                let mut columns = vec![0.0; 2 * n];
                for i in 0..n {
                    [wide[6 * i + 4], wide[6 * i + 1]] = [cv[4 * i], cv[4 * i + 2]];
                    [columns[i], columns[n + i]] = [cv[4 * i], cv[4 * i + 2]];
                }
                let wide_rows = Rows {
                    data: &wide,
                    ncols: 6,
                    mapping: other,
                };
                let cols = Columns {
                    xs: &columns[..n],
                    ys: &columns[n..],
                };
                for backend in backends() {
                    assert_eq!(
                        lanes(&scan, backend, CvRows(&cv), 0, n).1,
                        Some(bad),
                        "{backend:?} n={n} bad={bad} {value}"
                    );
                    assert_eq!(
                        lanes(&scan, backend, wide_rows, 0, n).1,
                        Some(bad),
                        "{backend:?} rows n={n} bad={bad} {value}"
                    );
                    assert_eq!(
                        lanes(&scan, backend, cols, 0, n).1,
                        Some(bad),
                        "{backend:?} columns n={n} bad={bad} {value}"
                    );
                }
            }
        }
    }
}

#[test]
fn expected_pd_gives_the_reference_bits() {
    let pose = Pose::new(-20.0, 35.0, 1.1).unwrap();
    let rules = [
        Rule::mean(),
        Rule::cubature(),
        Rule::unscented(),
        Rule::gauss_hermite(4).unwrap(),
    ];
    for model in models() {
        let scan = model.at_pose(&pose);
        // Stone Soup's [x, vx, y, vy] rows (read as vectors) and any other layout.
        for (k, mapping) in [
            (4, PositionMapping::default()),
            (6, PositionMapping::new(3, 1).unwrap()),
        ] {
            for n in [1, 3, 4, 9, 130] {
                let means = rows(n, k, mapping);
                let mut covars = vec![0.0; k * k * n];
                let (ix, iy) = (mapping.x, mapping.y);
                for i in 0..n {
                    let (sx, sy, rho) = (
                        5.0 + (i % 7) as f64 * 9.0,
                        3.0 + (i % 5) as f64 * 13.0,
                        ((i % 9) as f64 - 4.0) / 5.0,
                    );
                    let c = &mut covars[k * k * i..k * k * (i + 1)];
                    [c[ix * k + ix], c[ix * k + iy], c[iy * k + ix], c[iy * k + iy]] =
                        [sx * sx, rho * sx * sy, rho * sx * sy, sy * sy];
                }
                let gaussians = Gaussians {
                    means: Rows {
                        data: &means,
                        ncols: k,
                        mapping,
                    },
                    covars: &covars,
                };
                for rule in &rules {
                    let expected: Vec<u64> = (0..n)
                        .map(|i| {
                            let c = &covars[k * k * i..];
                            let l = cholesky2(c[ix * k + ix], c[ix * k + iy], c[iy * k + ix], c[iy * k + iy]).unwrap();
                            expected_reference(&scan, [means[k * i + ix], means[k * i + iy]], l, rule).to_bits()
                        })
                        .collect();
                    for backend in backends() {
                        let mut out = vec![f64::NAN; n];
                        let bad = run_on(
                            backend,
                            Expected {
                                scan: &scan,
                                gaussians,
                                velocities: crate::batch::Still,
                                rule,
                                first: 0,
                                out: &mut out,
                            },
                        );
                        assert_eq!(bad, None);
                        assert_eq!(
                            out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                            expected,
                            "{backend:?} n={n} k={k}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn cholesky_lanes_match_the_scalar_factor() {
    use crate::cubature::cholesky2_lanes;
    use crate::simd::{LaneKernel, Lanes};
    struct Factors(Vec<[f64; 4]>);
    impl LaneKernel for Factors {
        type Output = Vec<Option<[u64; 3]>>;
        #[inline(always)]
        fn run<L: Lanes>(self) -> Self::Output {
            let mut all = Vec::new();
            for four in self.0.chunks_exact(4) {
                let [a, b, b_t, c] = std::array::from_fn(|j| L::from_array(std::array::from_fn(|i| four[i][j])));
                let (bad, l) = cholesky2_lanes(a, b, b_t, c);
                let bad = L::select(bad, L::splat(1.0), L::splat(0.0)).to_array();
                let l = l.map(L::to_array);
                all.extend((0..4).map(|i| (bad[i] == 0.0).then(|| [l[0][i], l[1][i], l[2][i]].map(f64::to_bits))));
            }
            all
        }
    }
    let values = [
        0.0,
        -0.0,
        1e-300,
        4.0,
        9.0,
        -1e-13,
        -1.0,
        1e300,
        f64::NAN,
        f64::INFINITY,
        2.0 + 1e-10,
        6.0,
    ];
    let matrices: Vec<[f64; 4]> = (0..values.len().pow(3))
        .map(|k| {
            let (a, b, c) = (values[k % 12], values[k / 12 % 12], values[k / 144]);
            // Symmetric most of the time; sometimes a hair or a lot off.
            let b_t = match k % 5 {
                3 => b * (1.0 + 1e-12),
                4 => b + 1.0,
                _ => b,
            };
            [a, b, b_t, c]
        })
        .collect();
    let reference: Vec<Option<[u64; 3]>> = matrices
        .iter()
        .map(|m| cholesky2(m[0], m[1], m[2], m[3]).map(|l| l.map(f64::to_bits)))
        .collect();
    assert!(reference.iter().any(Option::is_some) && reference.iter().any(Option::is_none));
    for backend in backends() {
        assert_eq!(run_on(backend, Factors(matrices.clone())), reference, "{backend:?}");
    }
}

#[test]
fn the_first_bad_gaussian_is_named_with_its_reason() {
    let scan = models().remove(0).at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let n = 11;
    let means = rows(n, 4, PositionMapping::default());
    for (bad, mean_bad) in [(0, true), (5, false), (6, true), (10, false)] {
        let (mut means, mut covars) = (means.clone(), vec![0.0; 16 * n]);
        if mean_bad {
            means[bad * 4 + 2] = f64::NAN;
        } else {
            covars[bad * 16 + 2] = 5.0; // asymmetric position block
        }
        covars[(n - 1) * 16] = -1.0; // a later one is not reported first
        let gaussians = Gaussians {
            means: Rows {
                data: &means,
                ncols: 4,
                mapping: PositionMapping::default(),
            },
            covars: &covars,
        };
        let kind = if mean_bad {
            lanes::BadGaussian::Mean
        } else {
            lanes::BadGaussian::Covar
        };
        for backend in backends() {
            let mut out = vec![0.0; n];
            let found = run_on(
                backend,
                Expected {
                    scan: &scan,
                    gaussians,
                    velocities: crate::batch::Still,
                    rule: &Rule::cubature(),
                    first: 0,
                    out: &mut out,
                },
            );
            assert_eq!(found, Some((bad, kind)), "{backend:?}");
        }
    }
}
