//! States with velocities (a range-rate notch): the kernels against the scalar reference
//! [`ScanDetection::at_state`], bit for bit on every backend and layout, planar and raised.

use super::lane_tests::{backends, kernel_bits};
use super::lanes::{Expected, Gaussians};
use super::*;
use crate::batch::{ColumnHeights, ColumnVelocities, Columns, RowHeights, RowVelocities, Rows, VelocityMapping};
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
            let mapping = if raised {
                PositionMapping::raised(0, 2, 4).unwrap()
            } else {
                PositionMapping::new(0, 2).unwrap()
            }
            .with_velocity(velocity(raised))
            .unwrap();
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
    let mapping = PositionMapping::new(0, 2)
        .unwrap()
        .with_velocity(velocity(false))
        .unwrap();
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
    let mapping = PositionMapping::new(0, 2)
        .unwrap()
        .with_velocity(velocity(false))
        .unwrap();
    let mut out = [0.0; 5];
    scan.at_states(&data, 6, mapping, &mut out).unwrap();
    assert_eq!(out, [0.5; 5]);
}

#[test]
fn expected_pd_reads_the_velocity_at_the_mean() {
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap().moving([0.0, 0.0, 0.0]).unwrap();
    let scan = models().remove(1).at_pose(&pose);
    let n = 17;
    let data = rows(n);
    let mut covars = vec![0.0; 36 * n];
    for i in 0..n {
        covars[36 * i] = 400.0;
        covars[36 * i + 14] = 900.0;
    }
    let mapping = PositionMapping::new(0, 2)
        .unwrap()
        .with_velocity(velocity(false))
        .unwrap();
    let rule = Rule::cubature();
    let mut out = vec![0.0; n];
    scan.expected_at_gaussians(&data, &covars, 6, mapping, &rule, &mut out)
        .unwrap();
    for i in 0..n {
        let r = &data[6 * i..];
        let (sx, sy) = (20.0, 30.0);
        let want: f64 = rule
            .points()
            .iter()
            .zip(rule.weights())
            .map(|(u, w)| w * scan.at_state(r[0] + sx * u[0], r[2] + sy * u[1], None, Some([r[1], r[3], r[5]])))
            .sum::<f64>()
            .clamp(0.0, 1.0);
        assert_eq!(out[i].to_bits(), want.to_bits(), "row {i}");
    }
    for backend in backends() {
        let mut lanes = vec![f64::NAN; n];
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
            mapping: velocity(false),
        };
        let bad = run_on(
            backend,
            Expected {
                scan: &scan,
                gaussians,
                velocities,
                rule: &rule,
                first: 0,
                out: &mut lanes,
            },
        );
        assert_eq!(bad, None);
        assert_eq!(lanes, out, "{backend:?}");
    }
}
