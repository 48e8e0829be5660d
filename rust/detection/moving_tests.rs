//! States with velocities (a range-rate notch): the kernels against the scalar reference
//! [`ScanDetection::at_state`], bit for bit on every backend and layout, planar and raised.

use super::lane_tests::{backends, kernel_bits, rules};
use super::lanes::{Expected, ExpectedRaised, Gaussians};
use super::*;
use crate::batch::{
    ColumnHeights, ColumnVelocities, Columns, CvRows, RowHeights, RowVelocities, Rows, VelocityMapping,
};
use crate::cubature::{cholesky2, cholesky3, velocity_at_point, velocity_given_position, Rule};
use crate::range_rate::RangeRateNotch;
use crate::simd::run_on;

fn notch(width: f64, blind: Option<f64>) -> DetectionFactor {
    DetectionFactor::RangeRate(RangeRateNotch::new(width, blind, 3, 0.1, 1.0).unwrap())
}

fn models() -> Vec<DetectionModel> {
    let bands = DetectionFactor::Range(RangeBands::new(vec![800.0], vec![0.9, 0.2], vec![false]).unwrap());
    [
        vec![notch(3.0, None)],
        vec![bands.clone(), notch(2.0, Some(25.0))],
        vec![
            notch(5.0, None),
            DetectionFactor::Sector(AngularSector::new(1.0, 2.0, 0.3, 1.0).unwrap()),
        ],
    ]
    .into_iter()
    .map(|f| DetectionModel::new(f).unwrap())
    .collect()
}

/// (n, 6) rows [x, vx, y, vy, z, vz]: speeds up to 40 m/s, some crossing at right angles,
/// some at the blind speeds.
fn rows(n: usize) -> Vec<f64> {
    let mut state = 0x1234_5678_9abc_def1u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut data = vec![0.0; 6 * n];
    for i in 0..n {
        let r = &mut data[6 * i..6 * i + 6];
        r[0] = uniform() * 2000.0 - 1000.0;
        r[2] = uniform() * 2000.0 - 1000.0;
        r[4] = uniform() * 600.0;
        for c in [1, 3, 5] {
            r[c] = uniform() * 80.0 - 40.0;
        }
        if i % 4 == 0 {
            // moving straight along the line of sight from the sensor at 25 m/s
            let norm = (r[0] * r[0] + r[2] * r[2]).sqrt();
            (r[1], r[3], r[5]) = (25.0 * r[0] / norm, 25.0 * r[2] / norm, 0.0);
        }
    }
    data
}

/// (x, y) with (vx, vy), or (x, y, z) with (vx, vy, vz), of [x, vx, y, vy, z, vz] rows.
fn moving_mapping(raised: bool) -> PositionMapping {
    if raised {
        PositionMapping::raised(0, 2, 4).unwrap()
    } else {
        PositionMapping::new(0, 2).unwrap()
    }
    .with_velocity(velocity(raised))
    .unwrap()
}

fn velocity(raised: bool) -> VelocityMapping {
    VelocityMapping {
        vx: 1,
        vy: 3,
        vz: raised.then_some(5),
    }
}

#[test]
fn moving_states_give_the_reference_bits_on_every_path() {
    let pose = Pose::raised(10.0, -20.0, 0.7, 15.0)
        .unwrap()
        .moving([3.0, -1.5, 0.5])
        .unwrap();
    for model in models() {
        let scan = model.at_pose(&pose);
        for raised in [false, true] {
            let mapping = moving_mapping(raised);
            for n in [1, 3, 4, 9, 130] {
                let data = rows(n);
                let want: Vec<u64> = (0..n)
                    .map(|i| {
                        let r = &data[6 * i..];
                        let z = raised.then_some(r[4]);
                        scan.at_state(r[0], r[2], z, Some([r[1], r[3], r[5]])).to_bits()
                    })
                    .collect();
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let mut out = vec![0.0; n];
                scan.at_states(&data, 6, mapping, &mut out).unwrap();
                assert_eq!(bits(&out), want, "rows raised={raised} n={n}");
                let mut particles = vec![0.0; 6 * n];
                for i in 0..n {
                    for c in 0..6 {
                        particles[c * n + i] = data[6 * i + c];
                    }
                }
                scan.at_particles(&particles, 6, MemoryOrder::C, mapping, &mut out)
                    .unwrap();
                assert_eq!(bits(&out), want, "C particles raised={raised} n={n}");
                scan.at_particles(&data, 6, MemoryOrder::F, mapping, &mut out).unwrap();
                assert_eq!(bits(&out), want, "F particles raised={raised} n={n}");
                for backend in backends() {
                    let rows = Rows {
                        data: &data,
                        ncols: 6,
                        mapping,
                    };
                    let velocities = RowVelocities {
                        data: &data,
                        ncols: 6,
                        mapping: velocity(raised),
                    };
                    let got = if raised {
                        let heights = RowHeights {
                            data: &data,
                            ncols: 6,
                            z: 4,
                        };
                        kernel_bits(&scan, backend, rows, heights, velocities, 0, n)
                    } else {
                        kernel_bits(&scan, backend, rows, crate::batch::Planar, velocities, 0, n)
                    };
                    assert_eq!(got, (want.clone(), None), "{backend:?} raised={raised} n={n}");
                    let column = |c: usize| &particles[c * n..(c + 1) * n];
                    let velocities = ColumnVelocities {
                        vx: column(1),
                        vy: column(3),
                        vz: raised.then(|| column(5)),
                    };
                    let positions = Columns {
                        xs: column(0),
                        ys: column(2),
                    };
                    let got = if raised {
                        kernel_bits(&scan, backend, positions, ColumnHeights(column(4)), velocities, 0, n)
                    } else {
                        kernel_bits(&scan, backend, positions, crate::batch::Planar, velocities, 0, n)
                    };
                    assert_eq!(got, (want.clone(), None), "{backend:?} columns raised={raised} n={n}");
                }
            }
        }
    }
}

#[test]
fn the_notch_needs_velocities_and_reports_a_non_finite_one() {
    let scan = models().remove(0).at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let data = rows(9);
    let err = scan
        .at_states(&data, 6, PositionMapping::new(0, 2).unwrap(), &mut [0.0; 9])
        .unwrap_err();
    assert_eq!(err.argument(), "velocity_mapping");
    let mapping = moving_mapping(false);
    for bad in 0..9 {
        let mut data = rows(9);
        data[6 * bad + 3] = f64::NAN;
        let err = scan.at_states(&data, 6, mapping, &mut [0.0; 9]).unwrap_err();
        assert_eq!(err.argument(), "states");
        assert!(err.to_string().contains(&format!("row {bad}")), "{err}");
    }
    // a velocity column beyond the rows, or one shared with the position, is named
    let wide = PositionMapping::new(0, 2)
        .unwrap()
        .with_velocity(VelocityMapping { vx: 1, vy: 7, vz: None })
        .unwrap();
    let err = scan.at_states(&data, 6, wide, &mut [0.0; 9]).unwrap_err();
    assert!(err.to_string().contains("velocity_mapping (1, 7)"), "{err}");
    let shared = PositionMapping::new(0, 2)
        .unwrap()
        .with_velocity(VelocityMapping { vx: 2, vy: 3, vz: None });
    assert_eq!(shared.unwrap_err().argument(), "velocity_mapping");
    let short = PositionMapping::raised(0, 2, 4).unwrap().with_velocity(velocity(false));
    assert_eq!(short.unwrap_err().argument(), "velocity_mapping");
}

#[test]
fn a_model_without_a_notch_reads_no_velocities() {
    let model = DetectionModel::new(vec![DetectionFactor::Constant(0.5)]).unwrap();
    let scan = model.at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let mut data = rows(5);
    data[6 + 1] = f64::NAN; // a velocity nobody reads
    let mapping = moving_mapping(false);
    let mut out = [0.0; 5];
    scan.at_states(&data, 6, mapping, &mut out).unwrap();
    assert_eq!(out, [0.5; 5]);
}

/// (n, 6, 6) covariances A Aᵀ over [x, vx, y, vy, z, vz], A lower triangular with entries
/// drawn per row: positions and velocities correlated; every fifth row has a velocity
/// known exactly (zero velocity rows and columns), which reads the notch at the point.
fn joint_covariances(n: usize) -> Vec<f64> {
    let mut covars = vec![0.0; 36 * n];
    for i in 0..n {
        let mut a = [[0.0; 6]; 6];
        for (r, row) in a.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate().take(r + 1) {
                let scale = if r % 2 == 0 { 40.0 } else { 2.0 }; // metres, m/s
                let k = (i * 31 + r * 7 + c * 3) % 11;
                *v = scale
                    * if r == c {
                        0.3 + k as f64 / 11.0
                    } else {
                        (k as f64 - 5.0) / 15.0
                    };
            }
        }
        if i % 5 == 0 {
            for r in [1, 3, 5] {
                a[r] = [0.0; 6];
            }
        }
        for r in 0..6 {
            for c in 0..6 {
                covars[36 * i + 6 * r + c] = (0..6).map(|k| a[r][k] * a[c][k]).sum();
            }
        }
    }
    covars
}

#[test]
fn expected_pd_integrates_the_notch_over_the_velocity_given_the_position() {
    let pose = Pose::raised(10.0, -20.0, 0.7, 15.0)
        .unwrap()
        .moving([3.0, -1.5, 0.5])
        .unwrap();
    let n = 23;
    let (data, covars) = (rows(n), joint_covariances(n));
    for model in models() {
        let scan = model.at_pose(&pose);
        for raised in [false, true] {
            let positions: &[usize] = if raised { &[0, 2, 4] } else { &[0, 2] };
            let mapping = moving_mapping(raised);
            for rule in rules() {
                let spatial = rule.spatial();
                // the reference: each point's P_D with the notch's expectation over the
                // velocity given that point
                let want: Vec<u64> = (0..n)
                    .map(|i| {
                        let (r, c) = (&data[6 * i..6 * i + 6], &covars[36 * i..36 * i + 36]);
                        let at = |a: usize, b: usize| c[6 * a + b];
                        let mut expected = 0.0;
                        if raised {
                            let f = cholesky3([
                                at(0, 0),
                                at(0, 2),
                                at(0, 4),
                                at(2, 0),
                                at(2, 2),
                                at(2, 4),
                                at(4, 0),
                                at(4, 2),
                                at(4, 4),
                            ])
                            .unwrap();
                            let l = [[f[0], 0.0, 0.0], [f[1], f[2], 0.0], [f[3], f[4], f[5]]];
                            let cross = [1, 3, 5].map(|v| [0, 2, 4].map(|p| at(v, p)));
                            let block = [1, 3, 5].map(|v| [1, 3, 5].map(|w| at(v, w)));
                            let (b, left) = velocity_given_position(l, cross, block);
                            for (u, &w) in spatial.points().iter().zip(spatial.weights()) {
                                let x = r[0] + l[0][0] * u[0];
                                let y = r[2] + l[1][0] * u[0] + l[1][1] * u[1];
                                let z = r[4] + l[2][0] * u[0] + l[2][1] * u[1] + l[2][2] * u[2];
                                let v = velocity_at_point([r[1], r[3], r[5]], &b, *u);
                                expected += w * scan.at_state_uncertain(x, y, Some(z), v, &left);
                            }
                        } else {
                            let f = cholesky2(at(0, 0), at(0, 2), at(2, 0), at(2, 2)).unwrap();
                            let l = [[f[0], 0.0], [f[1], f[2]]];
                            let cross = [1, 3].map(|v| [0, 2].map(|p| at(v, p)));
                            let block = [1, 3].map(|v| [1, 3].map(|w| at(v, w)));
                            let (b, left) = velocity_given_position(l, cross, block);
                            for (u, &w) in rule.points().iter().zip(rule.weights()) {
                                let x = r[0] + l[0][0] * u[0];
                                let y = r[2] + l[1][0] * u[0] + l[1][1] * u[1];
                                let v = velocity_at_point([r[1], r[3], 0.0], &b, [u[0], u[1], 0.0]);
                                expected += w * scan.at_state_uncertain(x, y, None, v, &left);
                            }
                        }
                        expected.clamp(0.0, 1.0).to_bits()
                    })
                    .collect();
                // the spread matters: some rows (those near the notch) differ from the same
                // rule with the velocity read at the mean
                let at_mean = {
                    let mut still = covars.clone();
                    for (i, v) in still.iter_mut().enumerate() {
                        if [1, 3, 5].contains(&(i % 6)) || [1, 3, 5].contains(&(i / 6 % 6)) {
                            *v = 0.0;
                        }
                    }
                    let mut out = vec![f64::NAN; n];
                    scan.expected_at_gaussians(&data, &still, 6, mapping, &rule, &mut out)
                        .unwrap();
                    out
                };
                let differ = want.iter().zip(&at_mean).filter(|(a, b)| **a != b.to_bits()).count();
                assert!(differ >= 2, "{differ} rows differ");
                let mut out = vec![f64::NAN; n];
                scan.expected_at_gaussians(&data, &covars, 6, mapping, &rule, &mut out)
                    .unwrap();
                let bits: Vec<u64> = out.iter().map(|v| v.to_bits()).collect();
                assert_eq!(bits, want, "dispatched, raised={raised} {positions:?}");
                let gaussians = Gaussians {
                    means: Rows {
                        data: &data,
                        ncols: 6,
                        mapping,
                    },
                    covars: &covars,
                };
                let velocities = RowVelocities {
                    data: &data,
                    ncols: 6,
                    mapping: velocity(raised),
                };
                for backend in backends() {
                    let mut lanes = vec![f64::NAN; n];
                    let bad = if raised {
                        run_on(
                            backend,
                            ExpectedRaised {
                                scan: &scan,
                                gaussians,
                                heights: RowHeights {
                                    data: &data,
                                    ncols: 6,
                                    z: 4,
                                },
                                velocities,
                                rule: &spatial,
                                first: 0,
                                out: &mut lanes,
                            },
                        )
                    } else {
                        run_on(
                            backend,
                            Expected {
                                scan: &scan,
                                gaussians,
                                velocities,
                                rule: &rule,
                                first: 0,
                                out: &mut lanes,
                            },
                        )
                    };
                    assert_eq!(bad, None);
                    let bits: Vec<u64> = lanes.iter().map(|v| v.to_bits()).collect();
                    assert_eq!(bits, want, "{backend:?} raised={raised}");
                }
            }
        }
    }
}

#[test]
fn a_velocity_covariance_that_is_not_one_is_named() {
    let scan = models().remove(0).at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let mapping = moving_mapping(false);
    let (data, good) = (rows(9), joint_covariances(9));
    // row 4's [x, vx, y, vy] block: var(vx) < 0, cov(vx, vy) NaN, asymmetric velocity block
    let single: [&[(usize, f64)]; 3] = [&[(6 + 1, -1.0)], &[(6 + 3, f64::NAN)], &[(6 * 3 + 1, 1e9)]];
    // a velocity block with a negative eigenvalue; a position known exactly (var(x) = 0)
    // that covaries with vx; the position–velocity block asymmetric
    let (vv, xv) = (6 + 1, 1); // (vx, vx), (x, vx) entries
    let joint: [&[(usize, f64)]; 3] = [
        &[(vv, 100.0), (6 * 3 + 3, 100.0), (6 + 3, 500.0), (6 * 3 + 1, 500.0)],
        &[
            (0, 0.0),
            (xv, 10.0),
            (6, 10.0),
            (2, 0.0),
            (12, 0.0),
            (4, 0.0),
            (24, 0.0),
        ],
        &[(xv, 30.0), (6, 0.0)],
    ];
    for changes in single.into_iter().chain(joint) {
        let mut covars = good.clone();
        for &(entry, value) in changes {
            covars[36 * 4 + entry] = value;
        }
        let err = scan
            .expected_at_gaussians(&data, &covars, 6, mapping, &Rule::cubature(), &mut [0.0; 9])
            .unwrap_err();
        assert_eq!(err.argument(), "covars", "{changes:?}");
        assert!(err.to_string().contains("row 4"), "{err}");
    }
    // the velocity's fault is said as the velocity's
    let mut covars = good.clone();
    covars[36 * 4 + vv] = -1.0;
    let err = scan
        .expected_at_gaussians(&data, &covars, 6, mapping, &Rule::cubature(), &mut [0.0; 9])
        .unwrap_err();
    assert!(err.to_string().contains("the position and the velocity"), "{err}");
}

#[test]
fn a_model_holds_one_notch() {
    let err = DetectionModel::new(vec![notch(1.0, None), notch(2.0, None)]).unwrap_err();
    assert_eq!(err.argument(), "factors");
}

#[test]
fn stone_soups_cv_rows_give_the_reference_bits_with_velocities() {
    // [x, vx, y, vy] rows: positions and velocities both read with vector loads
    let pose = Pose::new(10.0, -20.0, 0.7).unwrap().moving([3.0, -1.5, 0.0]).unwrap();
    for model in models() {
        let scan = model.at_pose(&pose);
        for n in [1, 3, 4, 5, 9, 130] {
            let wide = rows(n);
            let data: Vec<f64> = (0..n).flat_map(|i| wide[6 * i..6 * i + 4].to_vec()).collect();
            let want: Vec<u64> = (0..n)
                .map(|i| {
                    let r = &data[4 * i..];
                    scan.at_state(r[0], r[2], None, Some([r[1], r[3], 0.0])).to_bits()
                })
                .collect();
            for backend in backends() {
                let got = kernel_bits(&scan, backend, CvRows(&data), crate::batch::Planar, CvRows(&data), 0, n);
                assert_eq!(got, (want.clone(), None), "{backend:?} n={n}");
            }
            let mapping = moving_mapping(false);
            let mut out = vec![0.0; n];
            scan.at_states(&data, 4, mapping, &mut out).unwrap();
            assert_eq!(out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want);
        }
    }
}
