//! Unit tests of the M-of-N initiator's scan: a contested detection, a wrapped bearing, the counts, errors.

use super::*;

const IDENTITY4: [f64; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

fn linear() -> MeasurementModel {
    MeasurementModel::linear(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], 2, 4, &[1.0, 0.0, 0.0, 1.0]).unwrap()
}

fn input<'a>(
    means: &'a [f64],
    covars: &'a [f64],
    dets: &'a [f64],
    index: &'a [usize],
    model_index: &'a [usize],
    counts: &'a [i64],
    new_time: &'a [bool],
) -> InitiatorInput<'a> {
    InitiatorInput {
        dim: 4,
        means,
        covars,
        transition_index: index,
        matrices: &IDENTITY4,
        noises: &[0.0; 16],
        detections: dets,
        model_index,
        missed_distance: 3.0,
        squared: false,
        include_all: false,
        force_symmetric: false,
        points: counts,
        since: counts,
        new_time,
        updates_only: false,
        min_points: 3,
    }
}

#[test]
fn the_nearer_row_takes_a_contested_detection_and_is_updated() {
    // rows at x = 0 and x = 1 (P = I, so S = 2I), one detection at x = 0.9
    let means = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
    let covars: Vec<f64> = IDENTITY4.iter().chain(IDENTITY4.iter()).copied().collect();
    let out = initiator_scan(
        &[linear()],
        &input(&means, &covars, &[0.9, 0.0], &[0, 0], &[0], &[1, 2], &[true, true]),
    )
    .unwrap();
    assert_eq!(out.assigned, vec![-1, 0]);
    assert!((out.distances[0] - (0.01f64 / 2.0).sqrt()).abs() < 1e-15);
    // K = ½ on the measured rows: x = 1 + ½(0.9 − 1), P₀₀ = 1 − ½
    assert!((out.means[4] - 0.95).abs() < 1e-15 && (out.covars[16] - 0.5).abs() < 1e-15);
    assert_eq!(out.means[..4], means[..4]); // the missed row keeps its prediction
    assert_eq!(out.points, vec![2, 3]);
    assert_eq!(out.since, vec![2, 1]);
    assert_eq!(out.released, vec![false, true]);
}

#[test]
fn counts_follow_updates_only_and_new_times() {
    let means = [0.0; 4];
    let mut probe = input(&means, &IDENTITY4, &[], &[0], &[], &[2], &[true]);
    let out = initiator_scan(&[linear()], &probe).unwrap();
    assert_eq!((out.points[0], out.since[0], out.released[0]), (3, 3, true));
    probe.updates_only = true;
    let out = initiator_scan(&[linear()], &probe).unwrap();
    assert_eq!((out.points[0], out.since[0], out.released[0]), (2, 3, false));
    probe.new_time = &[false]; // the same time again: no new step
    let out = initiator_scan(&[linear()], &probe).unwrap();
    assert_eq!(out.since[0], 2);
}

#[test]
fn a_bearing_innovation_is_wrapped() {
    // a target north of a sensor at the origin; a detection across the ±π wrap
    let model = MeasurementModel::bearing_range(
        [0, 2],
        [0.0, 0.0],
        &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        &[1e-2, 0.0, 0.0, 1.0],
        Jacobian::Analytic,
    )
    .unwrap();
    let means = [-100.0, 0.0, 1e-9, 0.0]; // bearing ≈ π
    let out = initiator_scan(
        &[model],
        &input(
            &means,
            &IDENTITY4,
            &[-std::f64::consts::PI + 0.001, 100.0],
            &[0],
            &[0],
            &[1],
            &[true],
        ),
    )
    .unwrap();
    assert_eq!(out.assigned, vec![0]);
    assert!(out.distances[0] < 0.1);
}

#[test]
fn bad_inputs_are_errors_naming_the_argument() {
    let means = [0.0; 4];
    let run = |i: &InitiatorInput| initiator_scan(&[linear()], i).unwrap_err().argument();
    assert_eq!(
        run(&input(&means, &IDENTITY4[..15], &[], &[0], &[], &[1], &[true])),
        "covars"
    );
    assert_eq!(
        run(&input(&means, &IDENTITY4, &[0.0, 0.0], &[0], &[1], &[1], &[true])),
        "model_index"
    );
    assert_eq!(
        run(&input(&means, &IDENTITY4, &[0.0], &[0], &[0], &[1], &[true])),
        "detections"
    );
    assert_eq!(run(&input(&means, &IDENTITY4, &[], &[0], &[], &[1], &[])), "since");
    let mut nan = input(&means, &IDENTITY4, &[], &[0], &[], &[1], &[true]);
    nan.missed_distance = f64::NAN;
    assert_eq!(run(&nan), "missed_distance");
    // a singular innovation covariance (P = 0, R = 0)
    let zero = MeasurementModel::linear(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], 2, 4, &[0.0; 4]).unwrap();
    let err = initiator_scan(
        &[zero],
        &input(&means, &[0.0; 16], &[0.0, 0.0], &[0], &[0], &[1], &[true]),
    )
    .unwrap_err();
    assert_eq!(err.argument(), "covars");
}
