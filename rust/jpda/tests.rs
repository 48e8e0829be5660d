//! Unit tests of the JPDA core: marginals against enumeration, tree budgets, the scan, the
//! measurement model.
//!
//! One file, as each module's unit tests are; long because beside the scan and the
//! prediction it tests the marginals with their tree budgets and the births, which have no
//! test file of their own.

use super::marginals::{joint_marginals_within, TreeLimits};
use super::*;
use crate::kalman::Jacobian;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;

fn random_problem(rng: &mut StdRng, tracks: usize, dets: usize, density: f64) -> (Vec<f64>, Vec<bool>) {
    let valid: Vec<bool> = (0..tracks * dets).map(|_| rng.random::<f64>() < density).collect();
    let weights: Vec<f64> = (0..tracks * (dets + 1))
        .map(|_| rng.random::<f64>().powi(3) * 10.0 + 1e-12)
        .collect();
    (weights, valid)
}

#[test]
fn marginals_equal_brute_force_enumeration() {
    let mut rng = StdRng::seed_from_u64(7);
    for case in 0..300 {
        let tracks = 1 + case % 7;
        let dets = case % 9;
        let density = [0.2, 0.5, 0.9][case % 3];
        let (weights, valid) = random_problem(&mut rng, tracks, dets, density);
        let ehm = joint_marginals(&weights, &valid, tracks, dets).unwrap();
        let brute = brute_force_marginals(&weights, &valid, tracks, dets).unwrap();
        for (a, b) in ehm.iter().zip(&brute) {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1e-300) + 1e-15,
                "case {case}: {a} vs {b}"
            );
        }
        for t in 0..tracks {
            let row: f64 = ehm[t * (dets + 1)..(t + 1) * (dets + 1)].iter().sum();
            assert!((row - 1.0).abs() < 1e-12);
        }
    }
}

#[test]
fn marginals_survive_weights_that_would_underflow_a_product() {
    // 40 tracks in one chain, each with weights around 1e-20: the product of one event
    // is 1e-800, far below f64; the per-level rescaling keeps every node representable.
    let (tracks, dets) = (40, 41);
    let mut weights = vec![0.0; tracks * (dets + 1)];
    let mut valid = vec![false; tracks * dets];
    for t in 0..tracks {
        weights[t * (dets + 1)] = 1e-20;
        for j in [t, t + 1] {
            valid[t * dets + j] = true;
            weights[t * (dets + 1) + 1 + j] = 3e-20 * (1.0 + j as f64 / 10.0);
        }
    }
    let marginals = joint_marginals(&weights, &valid, tracks, dets).unwrap();
    assert!(marginals.iter().all(|m| m.is_finite()));
    for t in 0..tracks {
        let row: f64 = marginals[t * (dets + 1)..(t + 1) * (dets + 1)].iter().sum();
        assert!((row - 1.0).abs() < 1e-12);
    }
    // Scaling every weight by one constant changes no marginal.
    let scaled: Vec<f64> = weights.iter().map(|w| w * 1e20).collect();
    let reference = joint_marginals(&scaled, &valid, tracks, dets).unwrap();
    for (a, b) in marginals.iter().zip(&reference) {
        assert!((a - b).abs() <= 1e-12);
    }
}

#[test]
fn impossible_cluster_is_an_error_naming_the_weights() {
    // Two tracks, no missed-detection mass, one shared detection: no valid joint event.
    let weights = vec![0.0, 1.0, 0.0, 1.0];
    let valid = vec![true, true];
    let err = joint_marginals(&weights, &valid, 2, 1).unwrap_err();
    assert_eq!(err.argument(), "weights");
    assert_eq!(
        brute_force_marginals(&weights, &valid, 2, 1).unwrap_err().argument(),
        "weights"
    );
}

/// `tracks` tracks each gating every one of `dets` detections: one cluster whose exact
/// tree is the subsets of detections used so far (Σ_k C(M, k) nodes per level).
fn dense_cluster(tracks: usize, dets: usize) -> (Vec<f64>, Vec<bool>) {
    let weights: Vec<f64> = (0..tracks * (dets + 1)).map(|i| 1.0 + (i % 7) as f64 / 10.0).collect();
    (weights, vec![true; tracks * dets])
}

#[test]
fn intractable_cluster_is_an_error_naming_its_size() {
    // 60 tracks sharing 60 detections: C(60, 30) ≈ 1.2e17 used-detection sets; the link
    // budget stops the tree after a few hundred thousand nodes (< 0.2 GB, under a second).
    let (tracks, dets) = (60, 60);
    let (weights, valid) = dense_cluster(tracks, dets);
    let err = joint_marginals(&weights, &valid, tracks, dets).unwrap_err();
    assert_eq!(err.argument(), "weights");
    let message = err.to_string();
    assert!(message.contains("cluster of 60 tracks and 60 detections"), "{message}");
    assert!(message.contains("intractable"), "{message}");
    // A tractable cluster next to it in the same call is not the one named.
    let mut w = weights.clone();
    let mut v = valid.clone();
    w.extend([0.5, 0.0].iter().cycle().take(dets + 1));
    v.extend(std::iter::repeat_n(false, dets));
    let err = joint_marginals(&w, &v, tracks + 1, dets).unwrap_err();
    assert!(err.to_string().contains("cluster of 60 tracks and 60 detections"));
}

#[test]
fn each_tree_budget_is_enforced_and_a_cluster_within_it_is_exact() {
    let (tracks, dets) = (6, 5);
    let (weights, valid) = dense_cluster(tracks, dets);
    // Nodes per level: 1, 6, 16, 26, 31, 32 (used sets of ≤ l of 5 detections): 112.
    let exact = brute_force_marginals(&weights, &valid, tracks, dets).unwrap();
    let ample = TreeLimits {
        nodes: 112,
        edges: 112 * 6,
    };
    let within = joint_marginals_within(ample, &weights, &valid, tracks, dets).unwrap();
    for (a, b) in within.iter().zip(&exact) {
        assert!((a - b).abs() <= 1e-12, "{a} vs {b}");
    }
    let nodes = joint_marginals_within(TreeLimits { nodes: 111, ..ample }, &weights, &valid, tracks, dets).unwrap_err();
    assert!(
        nodes.to_string().contains("cluster of 6 tracks and 5 detections"),
        "{nodes}"
    );
    assert!(nodes.to_string().contains("more than 111 nodes"), "{nodes}");
    // Links: each level's nodes × 6 hypotheses × 1 child, the last level none: 80 × 6.
    let edges = joint_marginals_within(
        TreeLimits {
            edges: 80 * 6 - 1,
            ..ample
        },
        &weights,
        &valid,
        tracks,
        dets,
    )
    .unwrap_err();
    assert!(edges.to_string().contains("more than 479 node links"), "{edges}");
    assert!(joint_marginals_within(TreeLimits { edges: 80 * 6, ..ample }, &weights, &valid, tracks, dets).is_ok());
}

#[test]
fn scan_of_an_intractable_cluster_is_an_error_not_an_abort() {
    // 40 tracks at one place, 40 detections around it, an open gate: one cluster of all.
    let model = linear_model();
    let (tracks, dets) = (40, 40);
    let means = vec![0.0; tracks * 4];
    let covars: Vec<f64> = (0..tracks * 16)
        .map(|k| if k % 16 % 5 == 0 { 100.0 } else { 0.0 })
        .collect();
    let detections: Vec<f64> = (0..dets * 2).map(|k| (k as f64 * 0.37).sin()).collect();
    let prob_detect = vec![0.9; tracks];
    let clutter = vec![1e-3; dets];
    let input = ScanInput {
        dim: 4,
        means: &means,
        covars: &covars,
        detections: &detections,
        prob_detect: &prob_detect,
        clutter: &clutter,
        prob_gate: 0.95,
        gate_threshold: f64::INFINITY,
        include_all: false,
        force_symmetric: false,
    };
    let err = scan(&model, &input).unwrap_err();
    assert_eq!(err.argument(), "weights");
    assert!(
        err.to_string().contains("cluster of 40 tracks and 40 detections"),
        "{err}"
    );
}

fn bearing_range(jacobian: Jacobian) -> MeasurementModel {
    let h: f64 = 0.7;
    let rotation = [h.cos(), h.sin(), 0.0, -h.sin(), h.cos(), 0.0, 0.0, 0.0, 1.0];
    MeasurementModel::bearing_range([0, 2], [10.0, -5.0], &rotation, &[1e-4, 0.0, 0.0, 25.0], jacobian).unwrap()
}

fn linear_model() -> MeasurementModel {
    MeasurementModel::linear(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], 2, 4, &[0.75, 0.0, 0.0, 0.75]).unwrap()
}

#[test]
fn scan_of_one_track_is_the_pda_update() {
    // One track, two detections: marginals are the normalised PDA weights, and the
    // posterior the mixture of the missed prediction and the two Kalman updates.
    let model = linear_model();
    let means = [0.0, 1.0, 0.0, 1.0];
    let covars = [
        1.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 1.5, 0.0, 0.0, 0.0, 0.0, 0.5,
    ];
    let detections = [0.5, -0.3, 1.2, 0.4];
    let input = ScanInput {
        dim: 4,
        means: &means,
        covars: &covars,
        detections: &detections,
        prob_detect: &[0.9],
        clutter: &[0.125, 0.125],
        prob_gate: 0.95,
        gate_threshold: 5.991464547107979,
        include_all: false,
        force_symmetric: false,
    };
    let out = scan(&model, &input).unwrap();
    assert_eq!(out.gated, vec![true, true]);
    for (w, m) in out.weights.iter().zip(&out.marginals) {
        assert!((w - m).abs() < 1e-14);
    }
    // By hand: S = P_xy + R = 2.25 I.
    let s = 2.25_f64;
    let lik = |dx: f64, dy: f64| (-(dx * dx + dy * dy) / (2.0 * s)).exp() / (2.0 * PI * s);
    let w = [
        1.0 - 0.9 * 0.95,
        0.9 * lik(0.5, -0.3) / 0.125,
        0.9 * lik(1.2, 0.4) / 0.125,
    ];
    let total: f64 = w.iter().sum();
    for (k, wk) in w.iter().enumerate() {
        assert!((out.weights[k] - wk / total).abs() < 1e-14);
    }
    let gain = 1.5 / s;
    let x0 = w[1] / total * gain * 0.5 + w[2] / total * gain * 1.2;
    assert!((out.means[0] - x0).abs() < 1e-14);
    assert!(out.is_update[0]);
    let taken: Vec<bool> = (0..2).map(|j| w[1 + j] > w[0]).collect();
    assert_eq!(out.taken, taken);
}

#[test]
fn scan_without_detections_keeps_the_prediction() {
    let model = linear_model();
    let means = [1.0, 2.0, 3.0, 4.0];
    let covars: Vec<f64> = (0..16).map(|k| if k % 5 == 0 { 2.0 } else { 0.0 }).collect();
    let input = ScanInput {
        dim: 4,
        means: &means,
        covars: &covars,
        detections: &[],
        prob_detect: &[0.4],
        clutter: &[],
        prob_gate: 0.95,
        gate_threshold: 6.0,
        include_all: false,
        force_symmetric: false,
    };
    let out = scan(&model, &input).unwrap();
    assert_eq!(out.means, means.to_vec());
    assert_eq!(out.covars, covars);
    assert!(!out.is_update[0]);
}

#[test]
fn bad_inputs_name_their_argument() {
    let model = linear_model();
    let means = [0.0; 4];
    let covars: Vec<f64> = (0..16).map(|k| if k % 5 == 0 { 1.0 } else { 0.0 }).collect();
    let base = ScanInput {
        dim: 4,
        means: &means,
        covars: &covars,
        detections: &[0.0, 0.0],
        prob_detect: &[0.5],
        clutter: &[1.0],
        prob_gate: 0.95,
        gate_threshold: 6.0,
        include_all: false,
        force_symmetric: false,
    };
    let cases: Vec<(ScanInput, &str)> = vec![
        (
            ScanInput {
                prob_detect: &[1.5],
                ..base
            },
            "prob_detect",
        ),
        (
            ScanInput {
                clutter: &[0.0],
                ..base
            },
            "clutter_density",
        ),
        (
            ScanInput {
                detections: &[f64::NAN, 0.0],
                ..base
            },
            "detections",
        ),
        (
            ScanInput {
                detections: &[0.0],
                ..base
            },
            "detections",
        ),
        (
            ScanInput {
                means: &[0.0, 0.0, f64::INFINITY, 0.0],
                ..base
            },
            "means",
        ),
        (
            ScanInput {
                covars: &covars[..15],
                ..base
            },
            "covars",
        ),
        (
            ScanInput {
                prob_gate: -0.1,
                ..base
            },
            "prob_gate",
        ),
        (
            ScanInput {
                gate_threshold: f64::NAN,
                ..base
            },
            "gate_threshold",
        ),
        (
            ScanInput {
                dim: 3,
                means: &[0.0; 3],
                covars: &[0.0; 9],
                ..base
            },
            "model",
        ),
    ];
    for (input, argument) in cases {
        assert_eq!(scan(&model, &input).unwrap_err().argument(), argument);
    }
    let singular = vec![0.0; 16];
    let zero_noise = MeasurementModel::linear(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], 2, 4, &[0.0; 4]).unwrap();
    assert_eq!(
        scan(
            &zero_noise,
            &ScanInput {
                covars: &singular,
                ..base
            }
        )
        .unwrap_err()
        .argument(),
        "covars"
    );
    assert_eq!(
        MeasurementModel::linear(&[1.0], 2, 4, &[0.0; 4])
            .unwrap_err()
            .argument(),
        "matrix"
    );
    assert_eq!(
        MeasurementModel::bearing_range([0, 0], [0.0; 2], &[0.0; 9], &[0.0; 4], Jacobian::Analytic)
            .unwrap_err()
            .argument(),
        "mapping"
    );
    assert_eq!(
        predict(4, &means, &covars, &[1], &covars, &covars)
            .unwrap_err()
            .argument(),
        "transition_index"
    );
}

#[test]
fn predict_is_the_kalman_prediction() {
    let f = [1.0, 1.0, 0.0, 1.0];
    let q = [0.25, 0.5, 0.5, 1.0];
    let (x, p) = predict(2, &[1.0, 2.0], &[1.0, 0.0, 0.0, 1.0], &[0], &f, &q).unwrap();
    assert_eq!(x, vec![3.0, 2.0]);
    assert_eq!(p, vec![2.25, 1.5, 1.5, 2.0]);
}

#[test]
fn a_birth_inverts_the_measurement_and_its_covariance_maps_back_to_the_noise() {
    // h(x − x₀') = z (the inverse function), and J P Jᵀ = R where the prior is not mapped
    // (J J⁺ = I for a full-rank J): the birth's spread is the noise carried back to the state.
    let model = bearing_range(Jacobian::Analytic);
    let prior_mean = [1.0, 2.0, 3.0, 4.0];
    let prior_covar: Vec<f64> = (0..16).map(|k| if k % 5 == 0 { 9.0 } else { 0.5 }).collect();
    let detections = [0.3, 120.0, -2.9, 40.0, 3.1, 500.0];
    let prior = BirthPrior {
        mean: &prior_mean,
        covar: &prior_covar,
        diag_load: 0.0,
    };
    let (means, covars) = initiator_births(std::slice::from_ref(&model), &detections, &[0, 0, 0], prior).unwrap();
    for j in 0..3 {
        let mut x = DVector::from_column_slice(&means[4 * j..4 * j + 4]);
        assert_eq!((x[1], x[3]), (2.0, 4.0)); // unmapped: the prior's
        x[1] = 0.0;
        x[3] = 0.0;
        let (z, h) = model.linearised(&x);
        assert!((z[0] - detections[2 * j]).abs() < 1e-12 && (z[1] / detections[2 * j + 1] - 1.0).abs() < 1e-12);
        let p = DMatrix::from_row_slice(4, 4, &covars[16 * j..16 * j + 16]);
        let back = &h * &p * h.transpose();
        let noise = [1e-4, 0.0, 0.0, 25.0];
        for (k, &r) in noise.iter().enumerate() {
            assert!((back[(k / 2, k % 2)] - r).abs() <= 1e-9 * (1.0 + r.abs()), "{back}");
        }
        // the unmapped block is the prior's (rows and columns 1 and 3), the cross terms zero
        // (to the SVD's rounding: J⁺ has no exact zeros)
        for (a, b, want) in [(1, 1, 9.0), (1, 3, 0.5), (3, 3, 9.0), (0, 1, 0.0), (2, 3, 0.0)] {
            assert!((p[(a, b)] - want).abs() <= 1e-12 * p.amax(), "{p}");
        }
    }
}

#[test]
fn a_linear_birth_uses_the_pseudo_inverse_given_or_the_svds() {
    let selection = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let model = MeasurementModel::linear(&selection, 2, 4, &[4.0, 0.0, 0.0, 9.0]).unwrap();
    let prior = BirthPrior {
        mean: &[0.0; 4],
        covar: &[0.0; 16],
        diag_load: 0.5,
    };
    let z = [3.0, -7.0];
    let (svd_mean, svd_covar) = initiator_births(std::slice::from_ref(&model), &z, &[0], prior).unwrap();
    let (given_mean, given_covar) = initiator_births(
        &[model.with_inverse(&[1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0]).unwrap()],
        &z,
        &[0],
        prior,
    )
    .unwrap();
    assert_eq!(given_mean, vec![3.0, 0.0, -7.0, 0.0]);
    assert_eq!(
        given_covar,
        vec![4.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 9.5, 0.0, 0.0, 0.0, 0.0, 0.5]
    );
    for (a, b) in svd_mean
        .iter()
        .zip(&given_mean)
        .chain(svd_covar.iter().zip(&given_covar))
    {
        assert!((a - b).abs() <= 1e-14 * 10.0, "{a} vs {b}");
    }
}
