//! Line of sight: a target is shadowed when the straight segment from the sensor to it
//! meets land (the radar shade behind islands). Grazing a coastline counts as blocked.
//!
//! The segment test is a ray cast through parry's BVH over the coastline edges, so one
//! target costs O(log E). The sensor is assumed to be at sea: from a sensor on land every
//! ray meets its own coastline and every target is shadowed.

use crate::land::LandMask;
use parry2d_f64::math::Vector;
use parry2d_f64::query::{Ray, RayCast};
use parry2d_f64::shape::Polyline;
use std::sync::Arc;

#[derive(Debug, Clone)]
pub struct LineOfSight {
    land: Arc<LandMask>,
    coast: Polyline,
}

impl LineOfSight {
    pub fn new(land: Arc<LandMask>) -> Self {
        let mut vertices = Vec::with_capacity(land.vertex_count() * 2);
        let mut indices = Vec::with_capacity(land.vertex_count());
        for e in land.edges() {
            let k = vertices.len() as u32;
            vertices.push(Vector::new(e.a[0], e.a[1]));
            vertices.push(Vector::new(e.b[0], e.b[1]));
            indices.push([k, k + 1]);
        }
        LineOfSight { land, coast: Polyline::new(vertices, Some(indices)) }
    }

    pub fn land(&self) -> &Arc<LandMask> {
        &self.land
    }

    /// Whether the segment sensor → target is free of land.
    #[inline]
    pub fn visible(&self, sensor: [f64; 2], target: [f64; 2]) -> bool {
        let dir = Vector::new(target[0] - sensor[0], target[1] - sensor[1]);
        if dir.x == 0.0 && dir.y == 0.0 {
            return !self.land.contains(target);
        }
        let ray = Ray::new(Vector::new(sensor[0], sensor[1]), dir);
        // The cast excludes a hit exactly at the end (time 1); a target on the coastline is
        // on land, so check the end point as well.
        !self.coast.intersects_local_ray(&ray, 1.0) && !self.land.contains(target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::land::Polygon;

    fn island() -> LineOfSight {
        let shell = vec![[100.0, -10.0], [120.0, -10.0], [120.0, 10.0], [100.0, 10.0]];
        LineOfSight::new(Arc::new(LandMask::new(vec![Polygon { shell, holes: vec![] }]).unwrap()))
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
    }
}
