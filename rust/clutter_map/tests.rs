//! Unit tests of the clutter map: the posterior, gates, weights, pools, rescaling and
//! restoring, finiteness, errors.
//!
//! One file, as each module's unit tests are; long because each part of the map's maths
//! (see the parent module's docs) has cases of its own.

use super::*;

fn radar() -> ClutterMap {
    let bearings: Vec<f64> = (0..=8).map(|i| -PI + i as f64 * PI / 4.0).collect();
    ClutterMap::new(
        MapSpace::BearingRange,
        [bearings, vec![0.0, 500.0, 1000.0]],
        1e-3,
        5.0,
        0.9,
    )
    .unwrap()
}

#[test]
fn the_scale_constants_are_the_powers_of_two_they_claim() {
    assert_eq!(LARGE, 2f64.powi(256));
    assert_eq!(RESCALE, 2f64.powi(-256));
}

#[test]
fn a_fresh_map_is_the_prior_and_outside_is_the_prior() {
    let map = radar();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    assert!(map.intensities().unwrap().iter().all(|v| *v == 1e-3));
    assert_eq!(map.value_at(&pose, 5000.0, 0.0, f64::NAN), 1e-3);
    assert!(map.value_at(&pose, f64::NAN, 0.0, f64::NAN).is_nan());
}

#[test]
fn the_posterior_mean_follows_the_discounted_counts() {
    let mut map = radar();
    let pose = Pose::new(10.0, 0.0, PI / 2.0).unwrap();
    // straight ahead (bearing 0, in cell [0, π/4)), 100 m: cell (4, 0)
    let ahead = [10.0, 100.0];
    map.update(&pose, &ahead, None, &[]).unwrap();
    map.update(&pose, &[], None, &[]).unwrap();
    map.update(&pose, &[ahead, ahead].concat(), None, &[]).unwrap();
    // N = 1·γ² + 0·γ + 2, S = γ² + γ + 1, V = π/4 · 500
    let (g, v) = (0.9f64, PI / 4.0 * 500.0);
    let expected = (1e-3 * 5.0 + (g * g + 2.0) / v) / (5.0 + g * g + g + 1.0);
    let got = map.value_at(&pose, 10.0, 100.0, f64::NAN);
    assert!((got - expected).abs() <= 1e-15 * expected, "{got} vs {expected}");
    // the other cells only saw exposure
    let quiet = 1e-3 * 5.0 / (5.0 + g * g + g + 1.0);
    let behind = map.value_at(&pose, 10.0, -100.0, f64::NAN);
    assert!((behind - quiet).abs() <= 1e-15 * quiet);
}

#[test]
fn a_measured_range_decides_the_range_cell() {
    let mut map = radar();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    // the position says 499.9 m, the measurement 500 m (an edge: the upper cell owns it)
    map.update(&pose, &[499.9, 1.0], Some(&[500.0]), &[]).unwrap();
    let near = map.value_at(&pose, 100.0, 1.0, f64::NAN);
    let far = map.value_at(&pose, 700.0, 1.0, f64::NAN);
    assert!(far > near);
}

#[test]
fn a_gate_takes_its_detections_and_its_area_out() {
    let mut map = ClutterMap::new(
        MapSpace::WorldXY,
        [vec![0.0, 10.0, 20.0], vec![0.0, 10.0]],
        0.01,
        2.0,
        1.0,
    )
    .unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    // a track at (5, 5) with a 2 m gate, its detection at (5.5, 5) and clutter at (1, 1)
    // and (15, 5); a second gate of the same cell and one outside the grid
    let gates = [5.0, 5.0, 2.0, 8.0, 8.0, 1.0, 50.0, 50.0, 3.0];
    map.update(&pose, &[5.5, 5.0, 1.0, 1.0, 15.0, 5.0], None, &gates)
        .unwrap();
    let fraction = (PI * 4.0 + PI) / 100.0;
    let (counts, deficit, exposure, _) = map.state();
    assert_eq!(counts, [1.0, 1.0]);
    assert_eq!(deficit, [fraction, 0.0]);
    assert_eq!(exposure, 1.0);
    let expected = (0.01 * 2.0 + 1.0 / 100.0) / (2.0 + 1.0 - fraction);
    assert_eq!(map.intensities().unwrap()[0], expected);
    // a cell gated whole every scan learns nothing: the prior
    let mut covered = ClutterMap::new(MapSpace::WorldXY, [vec![0.0, 1.0], vec![0.0, 1.0]], 0.01, 2.0, 0.9).unwrap();
    for _ in 0..50 {
        covered
            .update(&pose, &[0.2, 0.2, 0.9, 0.9], None, &[0.5, 0.5, 3.0])
            .unwrap();
    }
    assert_eq!(covered.intensities().unwrap()[0], 0.01);
}

#[test]
fn rescaling_keeps_the_estimate() {
    let mut map = ClutterMap::new(MapSpace::WorldXY, [vec![0.0, 1.0], vec![0.0, 1.0]], 0.5, 1.0, 0.5).unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    for _ in 0..300 {
        map.update(&pose, &[0.5, 0.5], None, &[]).unwrap();
    }
    assert!(map.scale <= LARGE);
    // N → 1/(1 − γ) = 2 = S: λ = (0.5 + 2) / (1 + 2)
    assert!((map.intensities().unwrap()[0] - 2.5 / 3.0).abs() < 1e-12);
}

#[test]
fn a_ring_pools_its_cells_and_a_cell_shrinks_towards_its_ring() {
    let (g, s0, sp) = (0.9f64, 5.0, 3.0);
    let mut map = radar().with_pooling(Pooling::Range, Some(sp)).unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    // two points ~100 m ahead, just to port (cell (4, 0)), one at 700 m port (cell (6, 1)), then an
    // empty scan
    map.update(&pose, &[100.0, 1.0, 100.0, 2.0, 0.0, 700.0], None, &[])
        .unwrap();
    map.update(&pose, &[], None, &[]).unwrap();
    let (v, big) = (PI / 4.0 * 500.0, 2.0 * PI * 500.0);
    let exposure = g + 1.0;
    let ring = |n: f64| (1e-3 * s0 * big + n) / (s0 * big + big * exposure);
    let cell = |ring: f64, n: f64| (ring * sp + n / v) / (sp + exposure);
    let grid = map.intensities().unwrap(); // rows: 8 bearings, columns: 2 ranges
    let near = ring(2.0 * g);
    assert!((grid[4 * 2] - cell(near, 2.0 * g)).abs() <= 1e-15 * grid[8]);
    assert!(
        (grid[0] - cell(near, 0.0)).abs() <= 1e-15 * grid[0],
        "a quiet cell follows its ring"
    );
    let far = ring(g);
    assert!((grid[6 * 2 + 1] - cell(far, g)).abs() <= 1e-15 * grid[13]);
    assert!((grid[1] - cell(far, 0.0)).abs() <= 1e-15 * grid[1]);
    // the whole grid as one pool
    let mut whole = radar().with_pooling(Pooling::Grid, Some(sp)).unwrap();
    whole
        .update(&pose, &[100.0, 1.0, 100.0, 2.0, 0.0, 700.0], None, &[])
        .unwrap();
    whole.update(&pose, &[], None, &[]).unwrap();
    let level = (1e-3 * s0 * 2.0 * big + 3.0 * g) / (2.0 * s0 * big + 2.0 * big * exposure);
    assert!((whole.intensities().unwrap()[1] - cell(level, 0.0)).abs() <= 1e-15 * level);
}

#[test]
fn an_estimated_pool_weight_follows_the_spread_of_its_cells() {
    let (g, s0) = (0.9f64, 5.0);
    let mut map = radar().with_pooling(Pooling::Range, None).unwrap();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    assert_eq!(
        map.intensities().unwrap(),
        vec![1e-3; 16],
        "no evidence: the prior everywhere"
    );
    // the near ring: four points a scan in cell (4, 0), two in (5, 0); the far ring: one
    // point in cell (6, 1), then one in (2, 1), beside a gate of radius 0 (no area, so no
    // deficit)
    let near_points = [100.0, 1.0, 100.0, 2.0, 110.0, 3.0, 120.0, 1.0, 60.0, 80.0, 50.0, 85.0];
    map.update(&pose, &[&near_points[..], &[0.0, 700.0]].concat(), None, &[])
        .unwrap();
    map.update(
        &pose,
        &[&near_points[..], &[0.0, -700.0]].concat(),
        None,
        &[0.0, -600.0, 0.0],
    )
    .unwrap();
    let (v, big) = (PI / 4.0 * 500.0, 2.0 * PI * 500.0);
    let total = g + 1.0;
    let squares = (1.0 - (1.0 - total * (1.0 - g)).powi(2)) / (1.0 - g * g); // g² + 1
    assert!((squares - (g * g + 1.0)).abs() < 1e-12);
    // near ring: every cell fully exposed; counts 4 (g + 1) in cell 4, 2 (g + 1) in cell 5
    let (n4, n5, e) = (4.0 * total, 2.0 * total, v * total);
    // cell 4 leaves the ring (its divergence from the level of all 8 cells, in effective
    // counts, beyond ln(8 / APART)); cell 5 stays
    let all = (1e-3 * s0 * big + n4 + n5) / (s0 * big + big * total);
    let divergence = |n: f64| {
        let (n, mu) = (n * total / squares, all * e * total / squares);
        n * (n / mu).ln() - n + mu
    };
    let threshold = (8.0 / APART).ln();
    assert!(divergence(n4) > threshold && divergence(n5) < threshold);
    // the ring's level and spread over its other 7 cells
    let near = (1e-3 * s0 * big + n5) / (s0 * big + 7.0 * e);
    let excess = (n5 - near * e).powi(2) + 6.0 * (near * e).powi(2) - 7.0 * near * v * squares;
    let tau = excess / (7.0 * e * e);
    assert!(tau > 0.0);
    let weight = near / (tau * v);
    let grid = map.intensities().unwrap();
    let cell = |n: f64| (near * weight + n / v) / (weight + total);
    assert!(
        (grid[8] - (1e-3 * s0 + n4 / v) / (s0 + total)).abs() <= 1e-12 * grid[8],
        "alone"
    );
    assert!((grid[10] - cell(n5)).abs() <= 1e-12 * grid[10]);
    assert!((grid[0] - cell(0.0)).abs() <= 1e-12 * grid[0]);
    // far ring: one point per cell in two cells, one scan apart
    let far = (1e-3 * s0 * big + g + 1.0) / (s0 * big + big * total);
    let excess = (g - far * e).powi(2) + (1.0 - far * e).powi(2) + 6.0 * (far * e).powi(2) - 8.0 * far * v * squares;
    let tau = (excess / (8.0 * e * e)).max(0.0);
    let expected = if tau == 0.0 {
        far
    } else {
        (far * far / (tau * v) + g / v) / (far / (tau * v) + total)
    };
    assert!((grid[6 * 2 + 1] - expected).abs() <= 1e-12 * expected);
}

#[test]
fn an_estimated_pool_weight_pools_a_flat_ring_and_sets_a_hot_cell_apart() {
    // 36 bearings × 2 rings; Poisson clutter of 0.5 points a cell a scan in both, and in
    // the far ring one cell with 5 a scan (a coast), from a fixed sequence
    let bearings: Vec<f64> = (0..=36).map(|i| -PI + i as f64 * PI / 18.0).collect();
    let edges = [bearings, vec![500.0, 1000.0, 1500.0]];
    let mut map = ClutterMap::new(MapSpace::BearingRange, edges.clone(), 1e-3, 1.0, 0.99)
        .unwrap()
        .with_pooling(Pooling::Range, None)
        .unwrap();
    let mut alone = ClutterMap::new(MapSpace::BearingRange, edges, 1e-3, 1.0, 0.99).unwrap(); // the same evidence
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    let mut state = 12345u64;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..300 {
        let mut points = Vec::new();
        for (cell, ring) in (0..36).flat_map(|c| [(c, 0), (c, 1)]) {
            let rate: f64 = if (cell, ring) == (9, 1) { 5.0 } else { 0.5 };
            // a Poisson draw by inversion
            let (mut k, mut p, u) = (0, (-rate).exp(), uniform());
            let mut total = p;
            while u > total {
                k += 1;
                p *= rate / k as f64;
                total += p;
            }
            for _ in 0..k {
                let bearing = -PI + (cell as f64 + uniform()) * PI / 18.0;
                let range = 500.0 * (1.0 + ring as f64 + uniform());
                points.extend([range * bearing.cos(), range * bearing.sin()]);
            }
        }
        map.update(&pose, &points, None, &[]).unwrap();
        alone.update(&pose, &points, None, &[]).unwrap();
    }
    let v = PI / 18.0 * 500.0;
    let ring =
        |m: &ClutterMap, r: usize| -> Vec<f64> { m.intensities().unwrap().chunks_exact(2).map(|c| c[r] * v).collect() }; // points a scan
    let spread = |values: &[f64]| {
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        (values.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / values.len() as f64).sqrt()
    };
    // the flat ring: its cells take its level, where alone they scatter by ~±0.07
    let (near, near_alone) = (ring(&map, 0), ring(&alone, 0));
    assert!(
        spread(&near_alone) > 0.04,
        "the cells alone scatter: {}",
        spread(&near_alone)
    );
    assert!(
        spread(&near) < 0.5 * spread(&near_alone),
        "pooled {} vs alone {}",
        spread(&near),
        spread(&near_alone)
    );
    assert!(near.iter().all(|l| (l - 0.5).abs() < 0.1), "{near:?}");
    // the ring with a coast: the hot cell leaves it, and its quiet cells keep the ring's
    // level (of the quiet cells alone: the coast does not lift it) as the flat ring's do
    assert_eq!(
        map.apart.iter().filter(|a| **a).count(),
        1,
        "only the coast's cell leaves"
    );
    assert!(map.apart[9 * 2 + 1]);
    let (far, far_alone) = (ring(&map, 1), ring(&alone, 1));
    assert!(
        (far[9] - 5.0).abs() < 0.5,
        "the hot cell departs from its ring: {}",
        far[9]
    );
    let others = |values: &[f64]| -> Vec<f64> {
        values
            .iter()
            .enumerate()
            .filter(|(c, _)| *c != 9)
            .map(|(_, l)| *l)
            .collect()
    };
    let (quiet, quiet_alone) = (others(&far), others(&far_alone));
    assert!(
        spread(&quiet) < 0.5 * spread(&quiet_alone),
        "pooled {} vs alone {}",
        spread(&quiet),
        spread(&quiet_alone)
    );
    assert!(quiet.iter().all(|l| (l - 0.5).abs() < 0.1), "{quiet:?}");
}

#[test]
fn a_pooled_state_restores_exactly_through_rescales_and_gates() {
    let pose = Pose::new(3.0, -2.0, 0.4).unwrap();
    for weight in [Some(2.0), None] {
        let fresh = || {
            ClutterMap::new(
                MapSpace::BearingRange,
                [
                    (0..=8).map(|i| -PI + i as f64 * PI / 4.0).collect(),
                    vec![0.0, 500.0, 1000.0],
                ],
                1e-3,
                5.0,
                0.3,
            )
            .unwrap()
            .with_pooling(Pooling::Range, weight)
            .unwrap()
        };
        let mut map = fresh();
        for k in 0..600 {
            let t = k as f64;
            // (a hot cell at (50, 20): three points every scan)
            // (and in the far ring a point in one of three cells in turn: a spread)
            let turn = (k % 3) as f64 * PI / 4.0;
            let points = [
                50.0,
                20.0,
                51.0,
                20.0,
                52.0,
                21.0,
                700.0 * turn.cos(),
                700.0 * turn.sin(),
                800.0 * turn.cos(),
                800.0 * turn.sin(),
                200.0 * t.cos(),
                300.0 * t.sin(),
                600.0 + t % 7.0,
                -40.0 * (t % 3.0),
                50.0,
                20.0,
            ];
            map.update(
                &pose,
                &points[..12 + 2 * (k % 3)],
                None,
                &[600.0 + t % 7.0, -40.0, 30.0],
            )
            .unwrap();
        }
        if weight.is_none() {
            assert!(
                map.pool_spread.iter().any(|t| *t > 0.0),
                "the test exercises a spread: {:?} {:?}",
                map.pool_spread,
                map.apart
            );
            assert!(map.apart.iter().any(|a| *a), "and a cell apart");
        }
        let (counts, deficit, exposure, scale) = map.state();
        let restored = fresh()
            .with_state(counts.to_vec(), deficit.to_vec(), exposure, scale)
            .unwrap();
        assert_eq!(restored.intensities().unwrap(), map.intensities().unwrap());
        assert_eq!(restored, map);
    }
}

#[test]
fn weights_count_fractions_of_a_point_and_ones_change_nothing() {
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    let points = [100.0, 1.0, 100.0, 2.0, 0.0, 700.0];
    let (mut plain, mut ones, mut half) = (radar(), radar(), radar());
    plain.update(&pose, &points, None, &[]).unwrap();
    ones.update_weighted(&pose, &points, None, Some(&[1.0; 3]), &[])
        .unwrap();
    half.update_weighted(&pose, &points, None, Some(&[0.5, 0.0, 0.25]), &[])
        .unwrap();
    assert_eq!(ones, plain);
    let (counts, ..) = half.state();
    let g = 1.0 / 0.9;
    assert_eq!((counts[4 * 2], counts[6 * 2 + 1]), (0.5 * g, 0.25 * g));
    let before = half.clone();
    for bad in [[0.5, 1.5, 0.0], [0.5, f64::NAN, 0.0], [-0.1, 0.0, 0.0]] {
        assert_eq!(
            half.update_weighted(&pose, &points, None, Some(&bad), &[])
                .unwrap_err()
                .argument(),
            "weights"
        );
    }
    assert_eq!(
        half.update_weighted(&pose, &points, None, Some(&[1.0]), &[])
            .unwrap_err()
            .argument(),
        "weights"
    );
    assert_eq!(half, before, "a failed update changes nothing");
}

#[test]
fn bad_configuration_and_inputs_are_named() {
    let e = || [vec![0.0, 1.0], vec![0.0, 1.0]];
    let argument = |r: Result<ClutterMap>| r.unwrap_err().argument();
    assert_eq!(
        argument(ClutterMap::new(MapSpace::WorldXY, e(), 1.0, 1.0, 0.0)),
        "forgetting"
    );
    assert_eq!(
        argument(ClutterMap::new(MapSpace::WorldXY, e(), 1.0, 1.0, 1.5)),
        "forgetting"
    );
    assert_eq!(
        argument(ClutterMap::new(MapSpace::WorldXY, e(), 0.0, 1.0, 0.9)),
        "prior_intensity"
    );
    assert_eq!(
        argument(ClutterMap::new(MapSpace::WorldXY, e(), 1.0, -1.0, 0.9)),
        "prior_scans"
    );
    assert_eq!(
        argument(ClutterMap::new(
            MapSpace::WorldXY,
            [vec![0.0], vec![0.0, 1.0]],
            1.0,
            1.0,
            0.9
        )),
        "edges"
    );
    assert_eq!(
        argument(ClutterMap::new(
            MapSpace::WorldXY,
            [vec![1.0, 0.0], vec![0.0, 1.0]],
            1.0,
            1.0,
            0.9
        )),
        "edges"
    );
    assert_eq!(
        argument(ClutterMap::new(
            MapSpace::BearingRange,
            [vec![-4.0, 0.0], vec![0.0, 1.0]],
            1.0,
            1.0,
            0.9
        )),
        "edges"
    );
    let fresh = || ClutterMap::new(MapSpace::WorldXY, e(), 1.0, 1.0, 0.9).unwrap();
    assert_eq!(argument(fresh().with_pooling(Pooling::Range, Some(1.0))), "pooling");
    assert_eq!(
        argument(fresh().with_pooling(Pooling::Grid, Some(0.0))),
        "pooling_scans"
    );
    assert_eq!(
        argument(fresh().with_pooling(Pooling::Grid, Some(f64::NAN))),
        "pooling_scans"
    );
    let mut map = ClutterMap::new(MapSpace::WorldXY, e(), 1.0, 1.0, 0.9).unwrap();
    let before = map.clone();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    assert_eq!(
        map.update(&pose, &[0.5, 0.5, f64::NAN, 0.0], None, &[])
            .unwrap_err()
            .argument(),
        "positions"
    );
    assert_eq!(
        map.update(&pose, &[0.5, 0.5], Some(&[f64::INFINITY]), &[])
            .unwrap_err()
            .argument(),
        "ranges"
    );
    assert_eq!(map, before, "a failed update changes nothing");
    assert_eq!(
        map.update(&pose, &[0.5, 0.5], None, &[0.0, 0.0, -1.0])
            .unwrap_err()
            .argument(),
        "gates"
    );
    assert_eq!(
        map.update(&pose, &[0.5, 0.5], None, &[0.0, 0.0])
            .unwrap_err()
            .argument(),
        "gates"
    );
    assert_eq!(map, before, "a failed update changes nothing");
    assert_eq!(
        map.clone()
            .with_state(vec![0.0; 2], vec![0.0], 0.0, 1.0)
            .unwrap_err()
            .argument(),
        "counts"
    );
    assert_eq!(
        map.clone()
            .with_state(vec![-1.0], vec![0.0], 0.0, 1.0)
            .unwrap_err()
            .argument(),
        "counts"
    );
    assert_eq!(
        map.clone()
            .with_state(vec![0.0], vec![2.0], 1.0, 1.0)
            .unwrap_err()
            .argument(),
        "deficit"
    );
    assert_eq!(
        map.with_state(vec![0.0], vec![0.0], 0.0, 0.0).unwrap_err().argument(),
        "scale"
    );
}

#[test]
fn the_scale_bounds_are_the_powers_of_two_they_claim() {
    assert_eq!(MAX_VOLUME, 2f64.powi(702));
    // the pools' sums: the largest grid times the largest scaled exposure stays finite
    assert!((MAX_VOLUME * 2f64.powi(310)).is_finite());
}

#[test]
fn the_measured_cases_stay_finite() {
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    let grid = || [vec![0.0, 10.0, 20.0], vec![0.0, 10.0]];
    // forgetting 1e-150: the running scale overflowed after four empty updates
    let mut map = ClutterMap::new(MapSpace::WorldXY, grid(), 1e-3, 5.0, 1e-150).unwrap();
    for _ in 0..6 {
        map.update(&pose, &[], None, &[]).unwrap();
    }
    assert!(map
        .intensities()
        .unwrap()
        .iter()
        .all(|l| l.is_finite() && *l >= f64::MIN_POSITIVE));
    // λ₀ s₀ overflowing f64
    let mut map = ClutterMap::new(MapSpace::WorldXY, grid(), 1e300, 1e10, 0.9).unwrap();
    map.update(&pose, &[5.0, 5.0], None, &[]).unwrap();
    assert!(
        map.intensities().unwrap().iter().all(|l| l.is_finite() && *l > 0.0),
        "{:?}",
        map.intensities()
    );
    // s₀ V_g overflowing f64
    let mut map = ClutterMap::new(MapSpace::WorldXY, grid(), 1e-3, 1e308, 0.9)
        .unwrap()
        .with_pooling(Pooling::Grid, Some(10.0))
        .unwrap();
    map.update(&pose, &[5.0, 5.0], None, &[]).unwrap();
    assert!(
        map.intensities().unwrap().iter().all(|l| l.is_finite() && *l > 0.0),
        "{:?}",
        map.intensities()
    );
    // a tiny λ₀ against many scans: floored at the smallest normal double
    let mut map = ClutterMap::new(MapSpace::WorldXY, grid(), f64::MIN_POSITIVE, 1e-300, 1.0).unwrap();
    map.update(&pose, &[], None, &[]).unwrap();
    assert_eq!(map.intensities().unwrap(), [f64::MIN_POSITIVE; 2]);
    assert_eq!(
        ClutterMap::new(MapSpace::WorldXY, grid(), 1e-310, 1.0, 1.0)
            .unwrap_err()
            .argument(),
        "prior_intensity"
    );
    assert_eq!(
        ClutterMap::new(MapSpace::WorldXY, [vec![0.0, 1e150], vec![0.0, 1e150]], 1.0, 1.0, 1.0)
            .unwrap_err()
            .argument(),
        "edges"
    );
}

#[test]
fn intensity_at_refuses_positions_and_ranges_it_cannot_place() {
    let map = radar();
    let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
    assert_eq!(
        map.intensity_at(&pose, &[100.0, 1.0, 5000.0, 0.0], None).unwrap(),
        [1e-3, 1e-3]
    );
    for bad in [f64::NAN, f64::INFINITY] {
        assert_eq!(
            map.intensity_at(&pose, &[100.0, 1.0, bad, 0.0], None).unwrap_err(),
            ModelError::non_finite("positions", 1, "position is NaN or infinite")
        );
    }
    assert_eq!(
        map.intensity_at(&pose, &[100.0, 1.0], Some(&[-1.0]))
            .unwrap_err()
            .argument(),
        "ranges"
    );
    assert_eq!(
        map.intensity_at(&pose, &[100.0, 1.0], Some(&[f64::NAN])).unwrap(),
        [1e-3]
    );
}

mod finite {
    //! Properties over the whole accepted ranges of the configuration and of updates:
    //! every λ finite and normal, every state value finite, on every SIMD backend.
    use super::*;
    use crate::simd::{on_backend, Backend};
    use proptest::prelude::*;

    /// A positive double from the whole range: the extremes, or 10^e.
    fn anywhere(low: f64, high: f64) -> impl Strategy<Value = f64> {
        let (a, b) = (low.log10().max(-323.0), high.log10().min(308.2));
        prop_oneof![
            Just(low),
            Just(high),
            (a..b).prop_map(move |e| 10f64.powf(e).clamp(low, high))
        ]
    }

    fn forgetting() -> impl Strategy<Value = f64> {
        prop_oneof![
            Just(1.0),
            Just(RESCALE),
            Just(f64::from_bits(1)),
            anywhere(f64::from_bits(1), 1.0),
            (0.5..1.0f64)
        ]
    }

    fn weight() -> impl Strategy<Value = f64> {
        prop_oneof![Just(0.0), Just(1.0), Just(f64::from_bits(1)), (0.0..=1.0f64)]
    }

    #[derive(Debug, Clone)]
    struct Scan {
        /// Points as fractions of the grid's extent (some outside it).
        points: Vec<(f64, f64, f64)>,
        /// Gates: centre as fractions, radius as a fraction of the extent.
        gates: Vec<(f64, f64, f64)>,
        weighted: bool,
    }

    fn scan() -> impl Strategy<Value = Scan> {
        let point = (-0.2..1.2f64, -0.2..1.2f64, weight());
        let gate = (0.0..1.0f64, 0.0..1.0f64, prop_oneof![Just(0.0), (0.0..2.0f64)]);
        (
            prop::collection::vec(point, 0..8),
            prop::collection::vec(gate, 0..3),
            any::<bool>(),
        )
            .prop_map(|(points, gates, weighted)| Scan {
                points,
                gates,
                weighted,
            })
    }

    fn pooling() -> impl Strategy<Value = (u8, Option<f64>)> {
        (
            0u8..3,
            prop_oneof![Just(None), anywhere(f64::from_bits(1), f64::MAX).prop_map(Some)],
        )
    }

    fn check(map: &ClutterMap, pose: &Pose) -> std::result::Result<(), TestCaseError> {
        for l in map.intensities().unwrap() {
            prop_assert!(l.is_finite() && l >= f64::MIN_POSITIVE, "λ {l:e}");
        }
        let (counts, deficit, exposure, scale) = map.state();
        prop_assert!(
            counts.iter().chain(deficit).all(|v| v.is_finite() && *v >= 0.0),
            "{counts:?} {deficit:?}"
        );
        prop_assert!(
            exposure.is_finite() && scale.is_finite() && scale > 0.0 && scale <= LARGE,
            "{exposure:e} {scale:e}"
        );
        prop_assert!(map.pool_level.iter().chain(&map.pool_spread).all(|v| v.is_finite()));
        let outside = map.value_at(pose, 1e300, 1e300, f64::NAN);
        prop_assert!(outside.is_finite() && outside >= f64::MIN_POSITIVE);
        Ok(())
    }

    proptest! {
        #[test]
        fn every_learned_value_stays_finite(
            prior_intensity in anywhere(f64::MIN_POSITIVE, f64::MAX),
            prior_scans in anywhere(f64::from_bits(1), f64::MAX),
            forgetting in forgetting(),
            (pool, pooled_scans) in pooling(),
            magnitude in -300.0..300.0f64,
            bearing_range in any::<bool>(),
            scans in prop::collection::vec(scan(), 1..40),
        ) {
            let size = 10f64.powf(magnitude / 2.0);
            let (space, edges) = if bearing_range || pool == 1 {
                (MapSpace::BearingRange, [vec![-PI, -1.0, 0.5, PI], (0..4).map(|i| i as f64 * size).collect::<Vec<_>>()])
            } else {
                (MapSpace::WorldXY, [vec![-size, 0.0, size], vec![0.0, size, 3.0 * size]])
            };
            let extent = 3.0 * size;
            let pooling = [Pooling::None, Pooling::Range, Pooling::Grid][pool as usize];
            let built = ClutterMap::new(space, edges, prior_intensity, prior_scans, forgetting).and_then(|m| m.with_pooling(pooling, pooled_scans));
            let fresh = match built {
                Ok(map) => map,
                // only a grid too large (or cells too small) for f64 is refused
                Err(err) => { prop_assert_eq!(err.argument(), "edges"); return Ok(()); }
            };
            let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
            let mut results = Vec::new();
            for backend in [Backend::Portable, Backend::Avx2].into_iter().filter(|b| b.available()) {
                let mut map = fresh.clone();
                on_backend(backend, || -> std::result::Result<(), TestCaseError> {
                    check(&map, &pose)?;
                    for s in &scans {
                        let positions: Vec<f64> = s.points.iter().flat_map(|(u, v, _)| [u * extent - size, v * extent]).collect();
                        let weights: Vec<f64> = s.points.iter().map(|p| p.2).collect();
                        let gates: Vec<f64> = s.gates.iter().flat_map(|(u, v, r)| [u * extent - size, v * extent, r * extent]).collect();
                        map.update_weighted(&pose, &positions, None, s.weighted.then_some(&weights[..]), &gates).unwrap();
                        check(&map, &pose)?;
                    }
                    // the state restores to the same map, bit for bit
                    let (counts, deficit, exposure, scale) = map.state();
                    let restored = fresh.clone().with_state(counts.to_vec(), deficit.to_vec(), exposure, scale).unwrap();
                    prop_assert_eq!(&restored, &map);
                    Ok(())
                })?;
                results.push(map);
            }
            // every backend learns the same bits
            prop_assert!(results.windows(2).all(|w| w[0] == w[1]));
        }
    }
}
