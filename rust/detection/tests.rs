//! Unit tests of the detection model: P_D at states, the expected P_D of a Gaussian, errors.

use super::*;
use std::f64::consts::PI;

fn radar() -> DetectionModel {
    DetectionModel::new(vec![
        DetectionFactor::Range(RangeBands::new(vec![50.0, 1612.0], vec![0.0, 0.4, 0.0], vec![false, true]).unwrap()),
        DetectionFactor::Sector(AngularSector::new(PI, 65f64.to_radians(), 0.0, 1.0).unwrap()),
    ])
    .unwrap()
}

#[test]
fn radar_at_states_with_heading() {
    let model = radar();
    let pose = Pose::new(100.0, 0.0, PI / 2.0).unwrap(); // facing +y
    let scan = model.at_pose(&pose);
    // rows [x, vx, y, vy]: ahead 500 m, astern 500 m, abeam 1000 m, 40 m, 1700 m.
    let states = [
        100.0, 0.0, 500.0, 0.0, 100.0, 0.0, -500.0, 0.0, 1100.0, 0.0, 0.0, 0.0, 140.0, 0.0, 0.0, 0.0, 100.0, 0.0,
        1700.0, 0.0,
    ];
    let mut out = [9.0; 5];
    scan.at_states(&states, 4, PositionMapping::default(), &mut out)
        .unwrap();
    assert_eq!(out, [0.4, 0.0, 0.4, 0.0, 0.0]);
}

#[test]
fn many_rows_in_parallel_match_serial() {
    let model = radar();
    let scan = model.at_pose(&Pose::new(3.0, -7.0, 0.7).unwrap());
    let n = 100_003;
    let states: Vec<f64> = (0..n * 4).map(|k| ((k as f64) * 0.618).sin() * 2000.0).collect();
    let mut out = vec![0.0; n];
    scan.at_states(&states, 4, PositionMapping::default(), &mut out)
        .unwrap();
    for i in (0..n).step_by(997) {
        let mut one = [0.0];
        scan.at_states(&states[i * 4..i * 4 + 4], 4, PositionMapping::default(), &mut one)
            .unwrap();
        assert_eq!(one[0], out[i]);
    }
}

#[test]
fn first_bad_row_is_named() {
    let model = radar();
    let scan = model.at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let n = 70_000;
    let mut states = vec![1.0; n * 4];
    states[50_001 * 4 + 2] = f64::NAN;
    states[60_000 * 4] = f64::INFINITY;
    let mut out = vec![0.0; n];
    let err = scan
        .at_states(&states, 4, PositionMapping::default(), &mut out)
        .unwrap_err();
    assert_eq!(
        err,
        ModelError::non_finite("states", 50_001, "position is NaN or infinite")
    );
    let err = scan
        .at_states(&states, 2, PositionMapping::default(), &mut vec![0.0; n * 2])
        .unwrap_err();
    assert_eq!(err.argument(), "states");
}

#[test]
fn probabilities_outside_unit_interval_are_rejected() {
    let err = DetectionModel::new(vec![DetectionFactor::Constant(1.5)]).unwrap_err();
    assert_eq!(err.argument(), "factors");
}

#[test]
fn expected_pd_of_point_mass_is_pd_at_mean() {
    let model = radar();
    let scan = model.at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let means = [300.0, 1.0, 20.0, 1.0];
    let covars = [0.0; 16];
    let mut out = [0.0];
    scan.expected_at_gaussians(
        &means,
        &covars,
        4,
        PositionMapping::default(),
        &Rule::gauss_hermite(5).unwrap(),
        &mut out,
    )
    .unwrap();
    assert!((out[0] - 0.4).abs() < 1e-12);
}

#[test]
fn expected_pd_straddling_an_edge() {
    // Lidar-like bands, Gaussian centred on the 50 m edge with σ = 10 m along range:
    // about half the mass on each side.
    let model = DetectionModel::new(vec![DetectionFactor::Range(
        RangeBands::new(vec![50.0], vec![1.0, 0.0], vec![true]).unwrap(),
    )])
    .unwrap();
    let scan = model.at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
    let means = [50.0, 0.0, 0.0, 0.0];
    let mut covars = [0.0; 16];
    covars[0] = 100.0;
    covars[10] = 1e-6;
    let mut out = [0.0];
    scan.expected_at_gaussians(
        &means,
        &covars,
        4,
        PositionMapping::default(),
        &Rule::gauss_hermite(20).unwrap(),
        &mut out,
    )
    .unwrap();
    assert!((out[0] - 0.5).abs() < 0.05, "{}", out[0]);
    covars[2] = 1e3; // not symmetric
    let err = scan
        .expected_at_gaussians(
            &means,
            &covars,
            4,
            PositionMapping::default(),
            &Rule::cubature(),
            &mut out,
        )
        .unwrap_err();
    assert_eq!(err.argument(), "covars");
}
