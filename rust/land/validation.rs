//! The checks that make a [`LandMask`](super::LandMask)'s rings valid land (see the parent
//! module's docs): each ring cleaned (finite vertices, ≥ 3 distinct, a non-zero finite
//! area), no two edges crossing or touching, holes inside their shell and no polygon on
//! another's land.

use super::{contains_exact, orientation, scale_for, scale_ring, segments_meet, signed_area, Edge, Point, Polygon};
use crate::error::{ring_name, ModelError, Result};
use crate::memory;
use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy};

/// "polygon 2 hole 0": where ring `ring` (0 the shell, `k + 1` hole `k`) of `polygon` is.
fn ring_place(polygon: usize, ring: usize) -> String {
    format!("polygon {polygon} {}", ring_name(ring))
}

/// `ring` without repeated vertices (nor the closing repeat), or the fault of ring `index`
/// (0 the shell, `k + 1` hole `k`) of polygon `polygon`.
pub(super) fn clean_ring(ring: &[Point], polygon: usize, index: usize) -> Result<Vec<Point>> {
    let fault = |message: String| ModelError::invalid_land("polygons", polygon, Some(index), message);
    let mut out: Vec<Point> = memory::with_room("polygons", ring.len())?;
    for (k, p) in ring.iter().enumerate() {
        if !p[0].is_finite() || !p[1].is_finite() {
            return Err(fault(format!("vertex {k} is not finite ({}, {})", p[0], p[1])));
        }
        if out.last() != Some(p) {
            out.push(*p);
        }
    }
    // A closed ring repeats its first vertex at the end: drop the repeat.
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    if out.len() < 3 {
        return Err(fault(format!("needs at least 3 distinct vertices, got {}", out.len())));
    }
    let area = signed_area(&out);
    if area == 0.0 {
        // Exactly 0 is collinear, or a ring so much smaller than the rest of the mask that
        // its area underflows: tell which, from the area at the ring's own scale.
        let own = signed_area(&scale_ring(&out, scale_for(ring_size(&out)))?);
        if own == 0.0 {
            return Err(fault("has zero area (all vertices on a line)".to_string()));
        }
        return Err(fault(
            "is too small next to the rest of the mask (its area underflows at the mask's scale)".to_string(),
        ));
    }
    if !area.is_finite() {
        return Err(fault("its area overflows (coordinates too large)".to_string()));
    }
    Ok(out)
}

/// The largest |coordinate| of a ring.
fn ring_size(ring: &[Point]) -> f64 {
    ring.iter().fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()))
}

/// No two edges may meet, except consecutive edges of one ring at their shared vertex.
/// Candidate pairs come from a parry BVH over the edges' bounding boxes.
pub(super) fn check_no_crossings(edges: &[Edge], rings: &[(usize, usize, usize, usize)]) -> Result<()> {
    let aabbs: Vec<Aabb> = memory::collected("polygons", edges.iter().map(Edge::aabb))?;
    // (parry's tree allocates infallibly, a few nodes per edge: as large as the boxes just
    // allocated, so a mask whose size fails fails above, before it)
    let bvh = Bvh::from_leaves(BvhBuildStrategy::default(), &aabbs);
    // Which ring each edge belongs to, and its position in the ring.
    let mut owner = memory::filled("polygons", edges.len(), (0usize, 0usize, 0usize))?;
    for (ring_id, &(_, _, first, count)) in rings.iter().enumerate() {
        for k in 0..count {
            owner[first + k] = (ring_id, k, count);
        }
    }
    for (i, e) in edges.iter().enumerate() {
        for j in bvh.intersect_aabb(&aabbs[i]) {
            let j = j as usize;
            if j <= i {
                continue;
            }
            let f = &edges[j];
            let (ri, ki, n) = owner[i];
            let (rj, kj, _) = owner[j];
            let neighbours = ri == rj && (kj == (ki + 1) % n || ki == (kj + 1) % n);
            let meets = if neighbours {
                // Neighbours share one vertex; they are wrong only if they fold back over
                // each other (collinear and overlapping beyond the shared vertex).
                let (shared, p, q) = if e.b == f.a { (e.b, e.a, f.b) } else { (e.a, e.b, f.a) };
                orientation(p, shared, q) == 0.0
                    && ((q[0] - shared[0]) * (p[0] - shared[0]) + (q[1] - shared[1]) * (p[1] - shared[1])) > 0.0
            } else {
                segments_meet(e.a, e.b, f.a, f.b)
            };
            if meets {
                let (pi, ringi, _, _) = rings[ri];
                let (pj, ringj, _, _) = rings[rj];
                return Err(ModelError::invalid_land(
                    "polygons",
                    pi,
                    None,
                    format!(
                        "{} edge {} and {} edge {} cross or touch (self-intersecting or touching rings are not valid land)",
                        ring_place(pi, ringi),
                        ki,
                        ring_place(pj, ringj),
                        kj
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn ring_edges(ring: &[Point]) -> Result<Vec<Edge>> {
    memory::collected(
        "polygons",
        (0..ring.len()).map(|k| Edge {
            a: ring[k],
            b: ring[(k + 1) % ring.len()],
        }),
    )
}

/// Holes inside their shell and not inside each other; no polygon on another's land.
/// Rings do not meet (checked before), so one vertex decides where a whole ring lies.
pub(super) fn check_nesting(polygons: &[Polygon]) -> Result<()> {
    let mut land_edges: Vec<Vec<Edge>> = memory::with_room("polygons", polygons.len())?;
    for p in polygons {
        let mut e = ring_edges(&p.shell)?;
        for h in &p.holes {
            e.try_reserve_exact(h.len())
                .map_err(|_| ModelError::memory("polygons", (e.len() + h.len()) as u128 * 32))?;
            e.extend(ring_edges(h)?);
        }
        land_edges.push(e);
    }
    let bounds: Vec<[f64; 4]> = memory::collected("polygons", polygons.iter().map(|p| ring_bounds(&p.shell)))?;
    for (pi, polygon) in polygons.iter().enumerate() {
        let shell_edges = ring_edges(&polygon.shell)?;
        for (hi, hole) in polygon.holes.iter().enumerate() {
            if !contains_exact(&shell_edges, hole[0]) {
                return Err(ModelError::invalid_land(
                    "polygons",
                    pi,
                    None,
                    format!("polygon {pi} hole {hi} lies outside its shell"),
                ));
            }
            for (hj, other) in polygon.holes.iter().enumerate() {
                if hj != hi && contains_exact(&ring_edges(other)?, hole[0]) {
                    return Err(ModelError::invalid_land(
                        "polygons",
                        pi,
                        None,
                        format!("polygon {pi} hole {hi} lies inside hole {hj}"),
                    ));
                }
            }
        }
        let v = polygon.shell[0];
        for (pj, b) in bounds.iter().enumerate() {
            let in_box = v[0] >= b[0] && v[0] <= b[2] && v[1] >= b[1] && v[1] <= b[3];
            if pj != pi && in_box && contains_exact(&land_edges[pj], v) {
                return Err(ModelError::invalid_land(
                    "polygons",
                    pi,
                    None,
                    format!("polygon {pi} lies on the land of polygon {pj} (overlapping polygons: merge them)"),
                ));
            }
        }
    }
    Ok(())
}

fn ring_bounds(ring: &[Point]) -> [f64; 4] {
    let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    for p in ring {
        b[0] = b[0].min(p[0]);
        b[1] = b[1].min(p[1]);
        b[2] = b[2].max(p[0]);
        b[3] = b[3].max(p[1]);
    }
    b
}
