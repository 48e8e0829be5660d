//! Coastal clutter: a clutter factor that is `inside` within `width` of a coastline the
//! sensor sees, and 1 elsewhere.
//!
//! A radar's returns from a shore are measured with the radar's noise, so they fall in a
//! band along the coastline. The band here is the set of points whose nearest coastline
//! point q (over every ring of a [`LandMask`], shells and holes) is within `width`, on
//! either side of the coast. With `seen_only`, q must also be seen from the sensor: the
//! sight line from the sensor to q, stopped [`SHORT`] before it, crosses no land — the
//! shore that faces the sensor, not the far side of an island. Distances are exact
//! (point–segment); a bounding-volume hierarchy over the coastline's segments keeps a
//! query to the segments near the point.

use crate::error::{ModelError, Result};
use crate::land::LandMask;
use crate::memory;
use crate::sight::LineOfSight;
use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::Vector;
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy};
use std::sync::Arc;

/// How far short of a coastline point its sight line stops (m): the point itself is on
/// the coast, which would count as land.
pub const SHORT: f64 = 1.0;

#[derive(Debug, Clone)]
pub struct CoastalBand {
    width: f64,
    inside: f64,
    segments: Vec<[[f64; 2]; 2]>,
    bvh: Bvh,
    /// Some: only coast the sensor sees.
    sight: Option<Arc<LineOfSight>>,
}

/// The point of segment [a, b] nearest to p.
#[inline]
fn nearest_on_segment([a, b]: [[f64; 2]; 2], p: [f64; 2]) -> [f64; 2] {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let length2 = dx * dx + dy * dy;
    let t = if length2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    [a[0] + t * dx, a[1] + t * dy]
}

impl CoastalBand {
    /// `width` (m, finite, ≥ 0); `inside`: the factor in the band (finite, > 0: λ is a
    /// density trackers divide by); `seen_only`: only coast seen from the sensor.
    pub fn new(land: Arc<LandMask>, width: f64, inside: f64, seen_only: bool) -> Result<Self> {
        if !(width.is_finite() && width >= 0.0) {
            return Err(ModelError::invalid(
                "width",
                format!("must be finite and >= 0, got {width}"),
            ));
        }
        if !(inside.is_finite() && inside > 0.0) {
            return Err(ModelError::invalid(
                "inside",
                format!("must be finite and > 0, got {inside}"),
            ));
        }
        let count = land
            .polygons()
            .iter()
            .map(|p| p.shell.len() + p.holes.iter().map(Vec::len).sum::<usize>())
            .sum();
        let mut segments = memory::with_room("land", count)?;
        for polygon in land.polygons() {
            for ring in std::iter::once(&polygon.shell).chain(&polygon.holes) {
                for k in 0..ring.len() {
                    segments.push([ring[k], ring[(k + 1) % ring.len()]]);
                }
            }
        }
        let boxes: Vec<Aabb> = memory::collected(
            "land",
            segments.iter().map(|[a, b]| {
                Aabb::new(
                    Vector::new(a[0].min(b[0]), a[1].min(b[1])),
                    Vector::new(a[0].max(b[0]), a[1].max(b[1])),
                )
            }),
        )?;
        // (parry's tree allocates infallibly: about as large as the boxes just allocated)
        let bvh = Bvh::from_leaves(BvhBuildStrategy::default(), &boxes);
        let sight = if seen_only {
            Some(Arc::new(LineOfSight::new(land)?))
        } else {
            None
        };
        Ok(CoastalBand {
            width,
            inside,
            segments,
            bvh,
            sight,
        })
    }

    /// The factor in the band.
    pub fn inside(&self) -> f64 {
        self.inside
    }

    /// The coastline point nearest to `p` if it is within the band's width.
    pub fn nearest_coast(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        let w = self.width;
        let (lo, hi) = ([p[0] - w, p[1] - w], [p[0] + w, p[1] + w]);
        let mut best: Option<([f64; 2], f64)> = None;
        for k in self.bvh.leaves(|node| {
            let (mins, maxs) = (node.mins(), node.maxs());
            mins.x <= hi[0] && maxs.x >= lo[0] && mins.y <= hi[1] && maxs.y >= lo[1]
        }) {
            let q = nearest_on_segment(self.segments[k as usize], p);
            let d2 = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
            // ties: the first segment in ring order, so the answer never depends on the tree
            if d2 <= w * w && best.is_none_or(|(nearest, b)| d2 < b || (d2 == b && q < nearest)) {
                best = Some((q, d2));
            }
        }
        best.map(|(q, _)| q)
    }

    /// The factor at each of the world `positions` (M, 2, row-major) for a sensor at
    /// `sensor`; a position that is not finite is an error naming its row.
    pub fn evaluate(&self, sensor: [f64; 2], positions: &[f64]) -> Result<Vec<f64>> {
        if !positions.len().is_multiple_of(2) {
            return Err(ModelError::shape("positions", "must be (M, 2)"));
        }
        if let Some(row) = positions
            .chunks_exact(2)
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(ModelError::non_finite("positions", row, "position is NaN or infinite"));
        }
        memory::collected(
            "positions",
            positions.chunks_exact(2).map(|p| self.value_at(sensor, p[0], p[1])),
        )
    }

    /// The factor at world (x, y) for a sensor at `sensor`: `inside` in the band, else 1
    /// (NaN for a position that is not finite).
    pub fn value_at(&self, sensor: [f64; 2], x: f64, y: f64) -> f64 {
        if !(x.is_finite() && y.is_finite()) {
            return f64::NAN;
        }
        let Some(q) = self.nearest_coast([x, y]) else {
            return 1.0;
        };
        let seen = match &self.sight {
            None => true,
            Some(sight) => {
                let (dx, dy) = (sensor[0] - q[0], sensor[1] - q[1]);
                let range = dx.hypot(dy);
                // a sensor on the coast point sees it
                range <= SHORT || sight.visible(sensor, [q[0] + dx / range * SHORT, q[1] + dy / range * SHORT])
            }
        };
        if seen {
            self.inside
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::land::Polygon;

    /// A 100 m square island with its west shore at x = 1000.
    fn island() -> Arc<LandMask> {
        let shell = vec![[1000.0, -50.0], [1100.0, -50.0], [1100.0, 50.0], [1000.0, 50.0]];
        Arc::new(LandMask::new(vec![Polygon { shell, holes: vec![] }]).unwrap())
    }

    #[test]
    fn band_on_both_sides_of_the_coast() {
        let band = CoastalBand::new(island(), 20.0, 7.0, false).unwrap();
        let origin = [0.0, 0.0];
        assert_eq!(band.value_at(origin, 980.0, 0.0), 7.0); // 20 m off the west shore
        assert_eq!(band.value_at(origin, 979.9, 0.0), 1.0);
        assert_eq!(band.value_at(origin, 1015.0, 0.0), 7.0); // 15 m inland
        assert_eq!(band.value_at(origin, 1050.0, 0.0), 1.0); // 50 m from every shore
        assert_eq!(band.value_at(origin, 1110.0, 0.0), 7.0); // off the far shore: not checked
        assert_eq!(band.value_at(origin, 990.0, 60.0), 7.0); // near the corner: √(10² + 10²) < 20
        assert_eq!(band.value_at(origin, 985.0, 65.0), 1.0); // √(15² + 15²) > 20
        assert!(band.value_at(origin, f64::NAN, 0.0).is_nan());
        assert_eq!(band.evaluate(origin, &[980.0, 0.0, 979.9, 0.0]).unwrap(), [7.0, 1.0]);
        for bad in [f64::NAN, f64::INFINITY] {
            let err = band.evaluate(origin, &[980.0, 0.0, bad, 0.0]).unwrap_err();
            assert_eq!(
                err,
                ModelError::non_finite("positions", 1, "position is NaN or infinite")
            );
        }
    }

    #[test]
    fn seen_only_leaves_out_the_far_shore() {
        let band = CoastalBand::new(island(), 20.0, 7.0, true).unwrap();
        let origin = [0.0, 0.0];
        assert_eq!(band.value_at(origin, 990.0, 0.0), 7.0); // the shore that faces the sensor
        assert_eq!(band.value_at(origin, 1110.0, 0.0), 1.0); // behind the island
        assert_eq!(band.value_at([2000.0, 0.0], 1110.0, 0.0), 7.0); // seen from the east
    }

    #[test]
    fn bad_configuration_names_the_argument() {
        for (width, inside, argument) in [
            (-1.0, 2.0, "width"),
            (f64::NAN, 2.0, "width"),
            (1.0, 0.0, "inside"),
            (1.0, f64::INFINITY, "inside"),
        ] {
            assert!(CoastalBand::new(island(), width, inside, false)
                .unwrap_err()
                .to_string()
                .starts_with(argument));
        }
    }
}
