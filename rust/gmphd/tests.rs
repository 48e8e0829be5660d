use super::*;
use crate::kalman::MeasurementModel;

fn cv(dt: f64) -> (Vec<f64>, Vec<f64>) {
    // constant velocity on [x, vx, y, vy], q = 1
    let mut f = vec![0.0; 16];
    let mut q = vec![0.0; 16];
    for b in [0, 2] {
        f[b * 4 + b] = 1.0;
        f[b * 4 + b + 1] = dt;
        f[(b + 1) * 4 + b + 1] = 1.0;
        q[b * 4 + b] = dt.powi(3) / 3.0;
        q[b * 4 + b + 1] = dt.powi(2) / 2.0;
        q[(b + 1) * 4 + b] = dt.powi(2) / 2.0;
        q[(b + 1) * 4 + b + 1] = dt;
    }
    (f, q)
}

fn diagonal(values: [f64; 4]) -> Vec<f64> {
    let mut m = vec![0.0; 16];
    for (i, v) in values.iter().enumerate() {
        m[i * 4 + i] = *v;
    }
    m
}

fn position_model() -> MeasurementModel {
    MeasurementModel::linear(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], 2, 4, &[1.0, 0.0, 0.0, 1.0]).unwrap()
}

fn params() -> UpdateParams {
    UpdateParams {
        prob_survival: 1.0,
        gate: 3.0,
        squared: false,
        include_all: false,
        normalise: true,
        skip_undetectable: true,
        time: 7,
        force_symmetric: false,
    }
}

#[test]
fn prediction_is_f_x_and_f_p_ft_plus_q() {
    let mut mixture = Mixture::new(4);
    mixture
        .extend(&[1.0, 2.0, 3.0, -1.0], &diagonal([1.0; 4]), &[0.5], &[BIRTH], &[0])
        .unwrap();
    let (f, q) = cv(2.0);
    mixture.predict(&[0], &f, &q).unwrap();
    assert_eq!(mixture.mean(0), &[5.0, 2.0, 1.0, -1.0]);
    // var(x) = 1 + dt² + dt³/3
    assert!((mixture.covar(0)[0] - (1.0 + 4.0 + 8.0 / 3.0)).abs() < 1e-12);
}

#[test]
fn one_detection_gives_the_kalman_update_and_the_phd_weights() {
    let mut mixture = Mixture::new(4);
    let tag = mixture.reserve_tags(1);
    mixture
        .extend(&[0.0, 0.0, 0.0, 0.0], &diagonal([1.0; 4]), &[0.8], &[tag], &[0])
        .unwrap();
    let clutter_probability = mixture
        .update(&position_model(), &[1.0, 0.0], &[0.5], &[0.1], &params())
        .unwrap();
    assert_eq!(mixture.len(), 2);
    // S = 2 I, K = diag-ish 1/2 on positions: posterior x = 0.5, var 0.5
    assert!((mixture.mean(0)[0] - 0.5).abs() < 1e-15);
    assert!((mixture.covar(0)[0] - 0.5).abs() < 1e-15);
    let q = (-0.25f64).exp() / (2.0 * std::f64::consts::PI * 2.0);
    let detected = 0.5 * 0.8 * q;
    assert!((mixture.weights[0] - detected / (detected + 0.1)).abs() < 1e-15);
    // the detection is clutter with the rest of its probability
    assert_eq!(clutter_probability.len(), 1);
    assert!((clutter_probability[0] - 0.1 / (detected + 0.1)).abs() < 1e-15);
    assert!((mixture.weights[1] - 0.4).abs() < 1e-15);
    assert_eq!(mixture.tags, vec![tag, tag]);
    assert_eq!(mixture.times, vec![7, 7]);
}

#[test]
fn births_get_fresh_tags_and_no_missed_term() {
    let mut mixture = Mixture::new(4);
    mixture
        .extend(&[0.0; 4], &diagonal([1.0; 4]), &[1e-4], &[BIRTH], &[0])
        .unwrap();
    let clutter_probability = mixture
        .update(
            &position_model(),
            &[0.5, 0.5, 50.0, 50.0],
            &[1.0],
            &[1e-3, 1e-3],
            &params(),
        )
        .unwrap();
    assert_eq!(
        mixture.len(),
        1,
        "the far detection is not gated; the missed birth is dropped"
    );
    assert!(clutter_probability[0] > 0.0 && clutter_probability[0] < 1.0);
    assert_eq!(clutter_probability[1], 1.0, "nothing explains the far detection");
    assert_ne!(mixture.tags[0], BIRTH);
}

#[test]
fn undetectable_components_keep_their_weight() {
    let mut mixture = Mixture::new(4);
    let tag = mixture.reserve_tags(1);
    mixture
        .extend(&[0.0; 4], &diagonal([1.0; 4]), &[0.9], &[tag], &[0])
        .unwrap();
    let clutter_probability = mixture
        .update(&position_model(), &[0.1, 0.1], &[0.0], &[1e-3], &params())
        .unwrap();
    assert_eq!(mixture.weights, vec![0.9]);
    assert_eq!(
        clutter_probability,
        vec![1.0],
        "a component that cannot be detected explains nothing"
    );
}

#[test]
fn reduce_prunes_merges_and_renames_shared_tags() {
    let mut mixture = Mixture::new(4);
    let tag = mixture.reserve_tags(2);
    let means = [
        0.0, 0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 100.0, 0.0, 0.0, 0.0, 200.0, 0.0, 0.0, 0.0,
    ];
    let mut covars = diagonal([1.0; 4]);
    for _ in 0..3 {
        covars.extend(diagonal([1.0; 4]));
    }
    mixture
        .extend(
            &means,
            &covars,
            &[0.6, 0.3, 0.2, 1e-9],
            &[tag, tag, tag, tag + 1],
            &[0; 4],
        )
        .unwrap();
    let params = ReduceParams {
        pruning: true,
        prune_threshold: 1e-6,
        merging: true,
        merge_threshold: 16.0,
        truncating: true,
        max_components: usize::MAX,
        max_distance: None,
    };
    mixture.reduce(&params).unwrap();
    assert_eq!(mixture.len(), 2);
    let share = 1e-9 / 3.0;
    assert!((mixture.weights[0] - (0.9 + 2.0 * share)).abs() < 1e-15);
    assert!((mixture.mean(0)[0] - 0.1 * (0.3 + share) / (0.9 + 2.0 * share)).abs() < 1e-15);
    assert_eq!(mixture.tags[0], tag);
    assert!(
        mixture.tags[1] > tag + 1,
        "the lighter component sharing the tag gets a fresh one"
    );
}

#[test]
fn truncate_keeps_the_heaviest() {
    let mut mixture = Mixture::new(1);
    let tag = mixture.reserve_tags(3);
    mixture
        .extend(
            &[0.0, 10.0, 20.0],
            &[1.0, 1.0, 1.0],
            &[0.2, 0.5, 0.3],
            &[tag, tag + 1, tag + 2],
            &[0; 3],
        )
        .unwrap();
    let params = ReduceParams {
        pruning: false,
        prune_threshold: 0.0,
        merging: false,
        merge_threshold: 16.0,
        truncating: true,
        max_components: 2,
        max_distance: None,
    };
    mixture.reduce(&params).unwrap();
    assert_eq!(mixture.tags, vec![tag + 1, tag + 2]);
    assert!((mixture.weights[0] - 0.6).abs() < 1e-15);
}

#[test]
fn bad_inputs_name_the_argument() {
    let mut mixture = Mixture::new(4);
    mixture
        .extend(&[0.0; 4], &diagonal([1.0; 4]), &[0.5], &[BIRTH], &[0])
        .unwrap();
    let err = mixture
        .update(&position_model(), &[0.0, 0.0], &[1.5], &[0.1], &params())
        .unwrap_err();
    assert_eq!(err.argument(), "prob_detection");
    let err = mixture
        .update(&position_model(), &[0.0, f64::NAN], &[0.5], &[0.1], &params())
        .unwrap_err();
    assert_eq!(err.argument(), "detections");
    let err = mixture
        .extend(&[f64::NAN; 4], &diagonal([1.0; 4]), &[0.5], &[BIRTH], &[0])
        .unwrap_err();
    assert_eq!(err.argument(), "means");
    let err = mixture.predict(&[1], &cv(1.0).0, &cv(1.0).1).unwrap_err();
    assert_eq!(err.argument(), "group");
}

#[test]
fn a_scan_without_detections_keeps_only_missed_terms() {
    let mut mixture = Mixture::new(4);
    let tag = mixture.reserve_tags(1);
    mixture
        .extend(
            &[0.0; 8],
            &[diagonal([1.0; 4]), diagonal([1.0; 4])].concat(),
            &[0.5, 1e-4],
            &[tag, BIRTH],
            &[0, 0],
        )
        .unwrap();
    let empty = MeasurementModel::linear(&[0.0; 4], 1, 4, &[1.0]).unwrap();
    mixture.update(&empty, &[], &[0.4, 0.4], &[], &params()).unwrap();
    assert_eq!(mixture.tags, vec![tag]);
    assert!((mixture.weights[0] - 0.3).abs() < 1e-15);
}

/// Clustered components (many within merging distance, varied spreads, some covariances a
/// rounding away from symmetric) from a fixed seed.
fn clustered_mixture(seed: u64, n: usize) -> Mixture {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let centres: Vec<[f64; 2]> = (0..6)
        .map(|_| [rng.random_range(-2000.0..2000.0), rng.random_range(-2000.0..2000.0)])
        .collect();
    let mut mixture = Mixture::new(4);
    for _ in 0..n {
        let c = centres[rng.random_range(0..centres.len())];
        let spread: f64 = 10f64.powf(rng.random_range(0.5..2.5));
        let mean = [
            c[0] + rng.random_range(-1.0..1.0) * spread,
            rng.random_range(-5.0..5.0),
            c[1] + rng.random_range(-1.0..1.0) * spread,
            rng.random_range(-5.0..5.0),
        ];
        let mut covar = diagonal([
            spread * spread,
            25.0,
            spread * spread * rng.random_range(0.5..2.0),
            25.0,
        ]);
        covar[2] = 0.3 * spread * spread;
        covar[8] = 0.3 * spread * spread;
        if rng.random_bool(0.1) {
            covar[8] *= 1.0 + f64::EPSILON; // not symmetric: the index's other bound
        }
        let weight = 10f64.powf(rng.random_range(-6.0..0.0));
        let tag = mixture.reserve_tags(1);
        mixture.extend(&mean, &covar, &[weight], &[tag], &[0]).unwrap();
    }
    mixture
}

#[test]
fn listed_first_candidates_merge_as_the_index_does() {
    let mut merges = 0;
    for seed in 0..40 {
        for max_distance in [None, Some(150.0)] {
            let mixture = clustered_mixture(seed, 300);
            let (mut listed, mut indexed) = (mixture.clone(), mixture.clone());
            listed.merge(16.0, max_distance, true).unwrap();
            indexed.merge(16.0, max_distance, false).unwrap();
            assert_eq!(listed.means, indexed.means, "seed {seed}");
            assert_eq!(listed.covars, indexed.covars, "seed {seed}");
            assert_eq!(listed.weights, indexed.weights, "seed {seed}");
            assert_eq!(listed.tags, indexed.tags, "seed {seed}");
            merges += mixture.len() - listed.len();
        }
    }
    assert!(merges > 1000, "the set-up should merge often, merged {merges}");
}

#[test]
fn births_extend_as_a_fresh_mixture_kept_in_the_circle_and_taken() {
    let means = [
        0.0,
        1.0,
        0.0,
        1.0,
        30.0,
        0.0,
        40.0,
        0.0,
        3.0,
        0.0,
        4.0,
        0.0,
        f64::NAN,
        0.0,
        0.0,
        0.0,
    ];
    let covar = diagonal([4.0, 1.0, 4.0, 1.0]);
    for circle in [None, Some(([0, 2], [0.0, 0.0], 5.0))] {
        let (mut one_call, mut steps) = (Mixture::new(4), Mixture::new(4));
        for mixture in [&mut one_call, &mut steps] {
            mixture.extend(&[9.0; 4], &covar, &[0.25], &[BIRTH], &[1]).unwrap();
        }
        // (the NaN mean is refused by both, before anything changes)
        assert!(one_call.extend_births(&means, &covar, &[0.1; 4], 7, circle).is_err());
        let finite = &means[..12];
        assert_eq!(
            one_call
                .extend_births(finite, &covar, &[0.1; 2], 7, circle)
                .unwrap_err()
                .argument(),
            "weights"
        );
        one_call
            .extend_births(finite, &covar, &[0.1, 0.2, 0.3], 7, circle)
            .unwrap();
        let mut fresh = Mixture::new(4);
        fresh
            .extend(finite, &covar.repeat(3), &[0.1, 0.2, 0.3], &[BIRTH; 3], &[7; 3])
            .unwrap();
        if let Some((position, centre, radius)) = circle {
            fresh.retain_inside_circle(position, centre, radius).unwrap();
        }
        let take = vec![true; fresh.len()];
        steps.take_from(&mut fresh, &take).unwrap();
        assert_eq!(
            (&one_call.means, &one_call.covars, &one_call.weights),
            (&steps.means, &steps.covars, &steps.weights)
        );
        assert_eq!((&one_call.tags, &one_call.times), (&steps.tags, &steps.times));
        assert_eq!(one_call.len(), if circle.is_some() { 3 } else { 4 });
    }
}
