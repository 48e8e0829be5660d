//! Unit tests of line of sight: shadows, and the visibility index against the BVH walk and brute force.

use super::*;
use crate::land::Polygon;

fn island() -> LineOfSight {
    let shell = vec![[100.0, -10.0], [120.0, -10.0], [120.0, 10.0], [100.0, 10.0]];
    LineOfSight::new(Arc::new(LandMask::new(vec![Polygon { shell, holes: vec![] }]).unwrap())).unwrap()
}

#[test]
fn tiny_island_shadows_like_a_large_one() {
    // The island above shrunk by 1e-202: validated and cast in a scaled frame.
    let k = 1e-202;
    let shell = vec![
        [100.0 * k, -10.0 * k],
        [120.0 * k, -10.0 * k],
        [120.0 * k, 10.0 * k],
        [100.0 * k, 10.0 * k],
    ];
    let sight = LineOfSight::new(Arc::new(LandMask::new(vec![Polygon { shell, holes: vec![] }]).unwrap())).unwrap();
    let sensor = [0.0, 0.0];
    let index = sight.from_point(sensor);
    assert_eq!(index.sensor(), sensor);
    for (target, visible) in [
        ([200.0, 0.0], false),
        ([200.0, 30.0], true),
        ([110.0, 0.0], false),
        ([90.0, 0.0], true),
        ([-200.0, 0.0], true),
    ] {
        let t = [target[0] * k, target[1] * k];
        assert_eq!(sight.visible(sensor, t), visible, "{target:?}");
        assert_eq!(index.visible(t), visible, "{target:?}");
    }
}

#[test]
fn shadow_behind_island() {
    let sight = island();
    assert!(!sight.visible([0.0, 0.0], [200.0, 0.0]));
    assert!(sight.visible([0.0, 0.0], [50.0, 0.0]));
    assert!(sight.visible([0.0, 0.0], [200.0, 40.0]));
    assert!(!sight.visible([0.0, 0.0], [110.0, 0.0]), "on land is not visible");
    assert!(!sight.visible([0.0, 0.0], [100.0, 0.0]), "on the coast is not visible");
    // Grazing the corner: the segment passes exactly through (100, 10).
    assert!(!sight.visible([0.0, 0.0], [200.0, 20.0]));
    // Sliding along the top edge's line, beyond the island: grazing blocks.
    assert!(!sight.visible([0.0, 10.0], [200.0, 10.0]));
    // Ending exactly before the coast.
    assert!(sight.visible([0.0, 0.0], [99.999, 0.0]));
}

#[test]
fn index_agrees_on_the_island() {
    let sight = island();
    let index = sight.from_point([0.0, 0.0]);
    for t in [
        [200.0, 0.0],
        [50.0, 0.0],
        [200.0, 40.0],
        [110.0, 0.0],
        [100.0, 0.0],
        [200.0, 20.0],
        [99.999, 0.0],
        [0.0, 0.0],
        [-50.0, 3.0],
    ] {
        assert_eq!(index.visible(t), sight.visible([0.0, 0.0], t), "target {t:?}");
    }
    assert!(!sight.from_point([0.0, 10.0]).visible([200.0, 10.0]));
}

#[test]
fn sensor_on_the_coast_or_on_land_sees_nothing() {
    let sight = island();
    for sensor in [[100.0, 0.0], [100.0, 10.0], [110.0, 0.0]] {
        let index = sight.from_point(sensor);
        for t in [[0.0, 0.0], [200.0, 50.0], [110.0, 5.0], [-30.0, -30.0]] {
            assert!(!sight.visible(sensor, t), "{sensor:?} → {t:?}");
            assert!(!index.visible(t), "{sensor:?} → {t:?}");
        }
    }
}

/// A jagged star-shaped island plus a ring-shaped atoll (a polygon with a hole), seen
/// from several sensors, against targets at random and exactly through vertices.
#[test]
fn index_agrees_with_the_bvh_everywhere() {
    let n = 900;
    let star: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let t = k as f64 / n as f64 * std::f64::consts::TAU;
            let r = 300.0 * (1.0 + 0.2 * (3.0 * t).sin()) * (1.0 - 0.15 * ((k as f64 * 0.618_033_988_75) % 1.0));
            [r * t.cos(), r * t.sin()]
        })
        .collect();
    let ring = |r: f64, cx: f64, cy: f64, m: usize| -> Vec<[f64; 2]> {
        (0..m)
            .map(|k| {
                let t = k as f64 / m as f64 * std::f64::consts::TAU;
                [cx + r * t.cos(), cy + r * t.sin()]
            })
            .collect()
    };
    let land = LandMask::new(vec![
        Polygon {
            shell: star.clone(),
            holes: vec![],
        },
        Polygon {
            shell: ring(120.0, 900.0, 100.0, 64),
            holes: vec![ring(80.0, 900.0, 100.0, 48)],
        },
    ])
    .unwrap();
    let sight = LineOfSight::new(Arc::new(land)).unwrap();
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut uniform = move |lo: f64, hi: f64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
    };
    let mut targets: Vec<[f64; 2]> = (0..20_000)
        .map(|_| [uniform(-1500.0, 1500.0), uniform(-1500.0, 1500.0)])
        .collect();
    for sensor in [[-700.0, 50.0], [900.0, 100.0], [0.0, 900.0], [-650.0, -650.0]] {
        // Targets exactly through vertices (grazing) at twice the vertex's distance.
        let mut extra: Vec<[f64; 2]> = star
            .iter()
            .step_by(7)
            .map(|v| [2.0 * v[0] - sensor[0], 2.0 * v[1] - sensor[1]])
            .collect();
        extra.extend(star.iter().step_by(11).copied());
        targets.extend_from_slice(&extra);
        let index = sight.from_point(sensor);
        assert!(!index.is_dense());
        let (mut seen, mut hidden) = (0, 0);
        for &t in &targets {
            let expect = sight.visible(sensor, t);
            assert_eq!(index.visible(t), expect, "sensor {sensor:?} target {t:?}");
            if expect {
                seen += 1
            } else {
                hidden += 1
            }
        }
        // From inside the lagoon only the lagoon is visible.
        let min_seen = if sensor == [900.0, 100.0] { 10 } else { 1000 };
        assert!(
            seen >= min_seen && hidden > 1000,
            "{sensor:?}: {seen} seen, {hidden} hidden"
        );
        targets.truncate(20_000);
    }
    // Inside the atoll's lagoon: water, but walled in by land on every side.
    let lagoon = sight.from_point([900.0, 100.0]);
    assert!(lagoon.visible([920.0, 130.0]));
    assert!(!lagoon.visible([1200.0, 100.0]));
}

/// parry's own ray cast against the coastline as an independent reference, on random
/// targets (no exact grazing, where the two predicates may round differently).
#[test]
fn agrees_with_parry_ray_cast_on_random_targets() {
    use parry2d_f64::query::{Ray, RayCast};
    use parry2d_f64::shape::Polyline;
    let n = 2000;
    let shell: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let t = k as f64 / n as f64 * std::f64::consts::TAU;
            let r = 1000.0 * (1.0 + 0.3 * (3.0 * t).sin()) * (1.0 - 0.1 * ((k as f64 * 0.618_033_988_75) % 1.0));
            [r * t.cos(), r * t.sin()]
        })
        .collect();
    let sight = LineOfSight::new(Arc::new(LandMask::new(vec![Polygon { shell, holes: vec![] }]).unwrap())).unwrap();
    let vertices: Vec<Vector> = sight
        .edges
        .iter()
        .flat_map(|[a, b]| [Vector::new(a[0], a[1]), Vector::new(b[0], b[1])])
        .collect();
    let indices: Vec<[u32; 2]> = (0..sight.edges.len() as u32).map(|k| [2 * k, 2 * k + 1]).collect();
    let coast = Polyline::new(vertices, Some(indices));
    let sensor = [-1700.0, 300.0];
    let index = sight.from_point(sensor);
    let mut state = 12345u64;
    let mut hidden = 0;
    for _ in 0..20_000 {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let x = ((state >> 11) as f64 / (1u64 << 53) as f64) * 3600.0 - 1800.0;
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let y = ((state >> 11) as f64 / (1u64 << 53) as f64) * 3600.0 - 1800.0;
        let t = [x, y];
        let ray = Ray::new(
            Vector::new(sensor[0], sensor[1]),
            Vector::new(x - sensor[0], y - sensor[1]),
        );
        let reference = !coast.intersects_local_ray(&ray, 1.0) && !sight.land().contains(t);
        assert_eq!(sight.visible(sensor, t), reference, "{t:?}");
        assert_eq!(index.visible(t), reference, "{t:?}");
        hidden += !reference as usize;
    }
    assert!(hidden > 5000 && hidden < 15000, "{hidden}");
}

/// A comb of long thin spikes seen side-on: every direction meets hundreds of edges, so
/// the index answers through the BVH — and still agrees.
#[test]
fn folded_coastline_falls_back_to_the_bvh() {
    let n = 6000;
    let shell: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let t = k as f64 / n as f64 * std::f64::consts::TAU;
            let r = if k % 2 == 0 { 1000.0 } else { 500.0 };
            [r * t.cos(), r * t.sin()]
        })
        .collect();
    let sight = LineOfSight::new(Arc::new(LandMask::new(vec![Polygon { shell, holes: vec![] }]).unwrap())).unwrap();
    let sensor = [-1500.0, 100.0];
    let index = sight.from_point(sensor);
    assert!(index.is_dense());
    for i in 0..60 {
        for j in 0..60 {
            let t = [i as f64 * 50.0 - 1500.0, j as f64 * 50.0 - 1500.0];
            assert_eq!(index.visible(t), sight.visible(sensor, t), "{t:?}");
        }
    }
}

#[test]
fn agrees_with_a_brute_force_segment_test() {
    let sight = island();
    let sensor = [3.0, -40.0];
    for i in 0..80 {
        for j in 0..80 {
            let t = [i as f64 * 3.0 - 20.0, j as f64 * 1.0 - 40.0];
            let brute = !sight.edges.iter().any(|&[a, b]| segments_meet(sensor, t, a, b)) && !sight.land.contains(t);
            assert_eq!(sight.visible(sensor, t), brute, "{t:?}");
        }
    }
}

#[test]
fn clearance_from_a_sensor_on_land() {
    let shell = vec![[100.0, -10.0], [120.0, -10.0], [120.0, 10.0], [100.0, 10.0]];
    let land = Arc::new(LandMask::new(vec![Polygon { shell, holes: vec![] }]).unwrap());
    assert!(LineOfSight::with_clearance(land.clone(), -1.0).is_err());
    assert!(LineOfSight::with_clearance(land.clone(), f64::NAN).is_err());
    // On the island's west shore, 2 m inland, with 5 m of clearance.
    let sight = LineOfSight::with_clearance(land, 5.0).unwrap();
    let sensor = [102.0, 0.0];
    let index = sight.from_point(sensor);
    for (target, visible) in [
        ([0.0, 0.0], true),    // out to sea over its own shore
        ([50.0, 30.0], true),  // likewise, off the axis
        ([200.0, 0.0], false), // across the island: its far shore is 18 m away
        ([104.0, 0.0], false), // within the clearance, on land
        ([98.0, 0.0], true),   // within the clearance, at sea
        ([102.0, 0.0], false), // the sensor's own spot is land
    ] {
        assert_eq!(sight.visible(sensor, target), visible, "{target:?}");
        assert_eq!(index.visible(target), visible, "{target:?}");
    }
    assert_eq!(sight.clearance(), 5.0);
}
