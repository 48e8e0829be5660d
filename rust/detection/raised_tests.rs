//! States with heights: the raised lane kernels against the scalar reference
//! [`ScanDetection::at_raised`], bit for bit on every backend, and the planar evaluation as
//! the raised one at the sensor's height.

use super::lane_tests::{backends, kernel_bits, rules};
use super::lanes::{expected_raised_reference, ExpectedRaised, Gaussians};
use super::*;
use crate::batch::{ColumnHeights, Columns, Cv3Rows, Positions, RowHeights, Rows};
use crate::cubature::cholesky3;
use crate::land::Polygon;
use crate::simd::{run_on, Backend};
use std::f64::consts::PI;

fn elevation(lower_deg: f64, upper_deg: f64, inside: f64, outside: f64) -> DetectionFactor {
    DetectionFactor::Elevation(
        ElevationSector::new(lower_deg.to_radians(), upper_deg.to_radians(), inside, outside).unwrap(),
    )
}

/// A horizon for an antenna 40 m up (√(2kR·40) ≈ 26 km shrunk to the test's scale by a
/// small sphere, so that targets fall on both sides).
fn horizon() -> DetectionFactor {
    let scale = 2.0 * 2_000.0;
    DetectionFactor::Horizon(Horizon::new((scale * 40.0f64).sqrt(), scale).unwrap())
}

/// 3-D models: an elevation beam with slant-range bands and a blind sector, each kind of
/// elevation limit, the horizon, the radar equation on slant range, land below the target.
fn models() -> Vec<DetectionModel> {
    let island = Arc::new(
        LandMask::new(vec![Polygon {
            shell: vec![[300.0, -200.0], [600.0, -200.0], [600.0, 200.0], [300.0, 200.0]],
            holes: vec![],
        }])
        .unwrap(),
    );
    let bands = |edges: &[f64], values: &[f64], owns: &[bool]| {
        DetectionFactor::Range(RangeBands::new(edges.to_vec(), values.to_vec(), owns.to_vec()).unwrap())
    };
    let radar =
        crate::radar::RadarEquation::new(10.0, 300.0, 0.0, 1e-6, crate::radar::Swerling::from_case(1).unwrap(), 1)
            .unwrap();
    [
        vec![
            bands(&[50.0, 1612.0], &[0.0, 0.9, 0.0], &[false, true]),
            elevation(-2.0, 30.0, 1.0, 0.0),
            DetectionFactor::Sector(AngularSector::new(PI, 65f64.to_radians(), 0.0, 1.0).unwrap()),
        ],
        vec![elevation(-90.0, 10.0, 0.8, 0.1)],
        vec![elevation(5.0, 90.0, 0.7, 0.2), horizon()],
        vec![DetectionFactor::Constant(0.9), horizon(), DetectionFactor::Radar(radar)],
        vec![
            elevation(-10.0, 45.0, 1.0, 0.0),
            DetectionFactor::Land(island.clone()),
            DetectionFactor::Sight(Arc::new(LineOfSight::new(island).unwrap())),
        ],
        // planar factors alone: ranges become slant ranges
        vec![bands(&[100.0, 700.0], &[0.9, 0.5, 0.1], &[true, false])],
        // a surveillance beam (its kernels are specialised): slant band, elevation, horizon
        vec![
            bands(&[1612.0], &[0.9, 0.0], &[false]),
            elevation(-2.0, 30.0, 1.0, 0.0),
            horizon(),
        ],
    ]
    .into_iter()
    .map(|f| DetectionModel::new(f).unwrap())
    .collect()
}

/// (n, 6) rows [x, vx, y, vy, z, vz] around the origin, heights −200…1200 m, some on the
/// elevation limits of the first model and a few not finite when asked.
fn rows(n: usize) -> Vec<f64> {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut data: Vec<f64> = (0..n * 6).map(|_| uniform() * 3600.0 - 1800.0).collect();
    for i in 0..n {
        data[6 * i + 4] = uniform() * 1400.0 - 200.0;
        if i % 5 == 0 {
            // exactly on the +30° or −2° limit of a sensor at height 25 (within rounding)
            let e = if i % 2 == 0 { 30f64 } else { -2f64 }.to_radians();
            let (h, x) = (500.0 + i as f64, data[6 * i]);
            data[6 * i + 2] = (h * h - x * x).max(0.0).sqrt();
            data[6 * i + 4] = 25.0 + (data[6 * i] * data[6 * i] + data[6 * i + 2] * data[6 * i + 2]).sqrt() * e.tan();
        }
    }
    data
}

fn mapping() -> PositionMapping {
    PositionMapping::raised(0, 2, 4).unwrap()
}

fn kernel<P: Positions, H: crate::batch::Heights>(
    scan: &ScanDetection,
    backend: Backend,
    positions: P,
    heights: H,
    n: usize,
) -> (Vec<u64>, Option<usize>) {
    kernel_bits(scan, backend, positions, heights, crate::batch::Still, 0, n)
}

#[test]
fn raised_rows_and_columns_give_the_reference_bits() {
    let level = Pose::raised(-30.0, 12.0, 0.4, 25.0).unwrap();
    // pitched up 0.2 rad and rolled −0.3 rad: sectors and elevations read in its frame
    let tilted = level.tilted(0.2, -0.3).unwrap();
    for (pose, model) in [level, tilted]
        .into_iter()
        .flat_map(|p| models().into_iter().map(move |m| (p, m)))
    {
        let scan = model.at_pose(&pose);
        for n in [1, 3, 4, 5, 9, 130] {
            let data = rows(n);
            let want: Vec<u64> = (0..n)
                .map(|i| scan.at_raised(data[6 * i], data[6 * i + 2], data[6 * i + 4]).to_bits())
                .collect();
            let columns: Vec<f64> = [0, 2, 4]
                .iter()
                .flat_map(|&c| (0..n).map(move |i| (i, c)))
                .map(|(i, c)| data[6 * i + c])
                .collect();
            let rows = Rows {
                data: &data,
                ncols: 6,
                mapping: mapping(),
            };
            let heights = RowHeights {
                data: &data,
                ncols: 6,
                z: 4,
            };
            let cols = Columns {
                xs: &columns[..n],
                ys: &columns[n..2 * n],
            };
            for backend in backends() {
                assert_eq!(
                    kernel(&scan, backend, rows, heights, n),
                    (want.clone(), None),
                    "{backend:?} rows n={n}"
                );
                assert_eq!(
                    kernel(&scan, backend, Cv3Rows(&data), Cv3Rows(&data), n),
                    (want.clone(), None),
                    "{backend:?} 3-D CV rows n={n}"
                );
                assert_eq!(
                    kernel(&scan, backend, cols, ColumnHeights(&columns[2 * n..]), n),
                    (want.clone(), None),
                    "{backend:?} columns n={n}"
                );
            }
            // the public entry points: rows and both particle orders
            let mut out = vec![0.0; n];
            scan.at_states(&data, 6, mapping(), &mut out).unwrap();
            assert_eq!(out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want);
            let mut particles = vec![0.0; 6 * n];
            for i in 0..n {
                for c in 0..6 {
                    particles[c * n + i] = data[6 * i + c];
                }
            }
            scan.at_particles(&particles, 6, MemoryOrder::C, mapping(), &mut out)
                .unwrap();
            assert_eq!(out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want);
            scan.at_particles(&data, 6, MemoryOrder::F, mapping(), &mut out)
                .unwrap();
            assert_eq!(out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want);
        }
    }
}

#[test]
fn planar_states_are_raised_ones_at_the_sensors_height() {
    let pose = Pose::raised(5.0, -8.0, 2.0, 25.0).unwrap();
    for model in models()
        .into_iter()
        .filter(|m| !m.factors().iter().any(|f| matches!(f, DetectionFactor::Horizon(_))))
    {
        let scan = model.at_pose(&pose);
        let mut data = rows(64);
        for i in 0..64 {
            data[6 * i + 4] = 25.0;
        }
        let (mut planar, mut raised) = (vec![0.0; 64], vec![0.0; 64]);
        scan.at_states(&data, 6, PositionMapping::new(0, 2).unwrap(), &mut planar)
            .unwrap();
        scan.at_states(&data, 6, mapping(), &mut raised).unwrap();
        assert_eq!(planar, raised);
    }
}

#[test]
fn the_first_non_finite_height_is_reported() {
    let scan = models().remove(0).at_pose(&Pose::raised(0.0, 0.0, 0.0, 10.0).unwrap());
    for n in [1, 6, 9] {
        for bad in 0..n {
            let mut data = rows(n);
            data[6 * bad + 4] = f64::NAN;
            let heights = RowHeights {
                data: &data,
                ncols: 6,
                z: 4,
            };
            let rows = Rows {
                data: &data,
                ncols: 6,
                mapping: mapping(),
            };
            for backend in backends() {
                assert_eq!(kernel(&scan, backend, Cv3Rows(&data), Cv3Rows(&data), n).1, Some(bad));
                assert_eq!(
                    kernel(&scan, backend, rows, heights, n).1,
                    Some(bad),
                    "{backend:?} n={n}"
                );
            }
            let err = scan.at_states(&data, 6, mapping(), &mut vec![0.0; n]).unwrap_err();
            assert_eq!(err.argument(), "states");
        }
    }
}

#[test]
fn a_horizon_at_the_targets_height_needs_heights() {
    let scan = models().remove(2).at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let err = scan
        .at_states(&rows(3), 6, PositionMapping::new(0, 2).unwrap(), &mut [0.0; 3])
        .unwrap_err();
    assert_eq!(err.argument(), "position_mapping");
    assert!(err.to_string().contains("(x, y, z)"), "{err}");
    let mut out = [0.0; 3];
    scan.at_states(&rows(3), 6, mapping(), &mut out).unwrap();
}

#[test]
fn raised_expected_pd_gives_the_reference_bits() {
    let pose = Pose::raised(-20.0, 35.0, 1.1, 25.0).unwrap();
    let n = 23;
    let means = rows(n);
    let mut covars = vec![0.0; 36 * n];
    for i in 0..n {
        let (sx, sy, sz) = (
            5.0 + (i % 7) as f64 * 9.0,
            3.0 + (i % 5) as f64 * 13.0,
            (i % 4) as f64 * 20.0,
        );
        let c = &mut covars[36 * i..36 * (i + 1)];
        let rho = ((i % 9) as f64 - 4.0) / 5.0;
        [c[0], c[2], c[12], c[14]] = [sx * sx, rho * sx * sy, rho * sx * sy, sy * sy];
        c[4 * 6 + 4] = sz * sz;
        [c[4], c[24]] = [0.1 * sx * sz, 0.1 * sx * sz];
    }
    let gaussians = Gaussians {
        means: Rows {
            data: &means,
            ncols: 6,
            mapping: mapping(),
        },
        covars: &covars,
    };
    for model in models() {
        let scan = model.at_pose(&pose);
        for rule in rules() {
            let spatial = rule.spatial();
            let want: Vec<u64> = (0..n)
                .map(|i| {
                    let c = &covars[36 * i..];
                    let l = cholesky3([c[0], c[2], c[4], c[12], c[14], c[16], c[24], c[26], c[28]]).unwrap();
                    let m = [means[6 * i], means[6 * i + 2], means[6 * i + 4]];
                    expected_raised_reference(&scan, m, l, &spatial).to_bits()
                })
                .collect();
            for backend in backends() {
                let mut out = vec![f64::NAN; n];
                let bad = run_on(
                    backend,
                    ExpectedRaised {
                        scan: &scan,
                        gaussians,
                        heights: RowHeights {
                            data: &means,
                            ncols: 6,
                            z: 4,
                        },
                        velocities: crate::batch::Still,
                        rule: &spatial,
                        first: 0,
                        out: &mut out,
                    },
                );
                assert_eq!(bad, None);
                assert_eq!(
                    out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    want,
                    "{backend:?} {rule:?}"
                );
            }
            let mut out = vec![0.0; n];
            scan.expected_at_gaussians(&means, &covars, 6, mapping(), &rule, &mut out)
                .unwrap();
            assert_eq!(out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want);
        }
    }
    // a covariance whose height block is indefinite is named
    let mut bad = covars.clone();
    bad[36 * 5 + 28] = -100.0;
    let scan = models().remove(0).at_pose(&pose);
    let err = scan
        .expected_at_gaussians(&means, &bad, 6, mapping(), &Rule::cubature(), &mut vec![0.0; n])
        .unwrap_err();
    assert_eq!(err.argument(), "covars");
    assert!(err.to_string().contains("row 5"), "{err}");
}

#[test]
fn an_elevation_limit_at_the_zenith_leaves_targets_straight_above_inside() {
    let model = DetectionModel::new(vec![elevation(0.0, 90.0, 1.0, 0.0)]).unwrap();
    let scan = model.at_pose(&Pose::raised(0.0, 0.0, 0.0, 10.0).unwrap());
    assert_eq!(scan.at_raised(0.0, 0.0, 1000.0), 1.0);
    assert_eq!(scan.at_raised(0.0, 0.0, -1000.0), 0.0);
    assert_eq!(
        scan.at_raised(100.0, 0.0, 10.0),
        1.0,
        "level with the sensor: elevation 0"
    );
}
