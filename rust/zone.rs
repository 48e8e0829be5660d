//! A zone: a factor that is `inside` within a set of polygons and `outside` elsewhere —
//! harbour mouths and anchorages where births and clutter are likelier, land where they
//! are not. The polygons are a [`LandMask`] (its validation, containment index and
//! boundary rule: a point on a polygon's boundary is inside).

use crate::error::{ModelError, Result};
use crate::land::LandMask;
use std::sync::Arc;

#[derive(Debug, Clone)]
pub struct Zone {
    polygons: Arc<LandMask>,
    inside: f64,
    outside: f64,
}

impl Zone {
    /// `inside` and `outside` finite and ≥ 0 (a model that takes the zone may ask more:
    /// λ needs them > 0).
    pub fn new(polygons: Arc<LandMask>, inside: f64, outside: f64) -> Result<Self> {
        for (argument, value) in [("inside", inside), ("outside", outside)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ModelError::invalid(
                    argument,
                    format!("must be finite and >= 0, got {value}"),
                ));
            }
        }
        Ok(Zone {
            polygons,
            inside,
            outside,
        })
    }

    pub fn inside(&self) -> f64 {
        self.inside
    }

    pub fn outside(&self) -> f64 {
        self.outside
    }

    /// The factor at (x, y): NaN when the point is not finite.
    #[inline]
    pub fn value_at(&self, x: f64, y: f64) -> f64 {
        if !(x.is_finite() && y.is_finite()) {
            f64::NAN
        } else if self.polygons.contains([x, y]) {
            self.inside
        } else {
            self.outside
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::land::Polygon;

    #[test]
    fn inside_on_the_boundary_outside_beyond() {
        let square = LandMask::new(vec![Polygon {
            shell: vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]],
            holes: vec![],
        }])
        .unwrap();
        let zone = Zone::new(Arc::new(square), 5.0, 0.5).unwrap();
        assert_eq!(zone.value_at(5.0, 5.0), 5.0);
        assert_eq!(zone.value_at(10.0, 3.0), 5.0);
        assert_eq!(zone.value_at(10.5, 3.0), 0.5);
        assert!(zone.value_at(f64::NAN, 3.0).is_nan());
        let bad = Zone::new(zone.polygons.clone(), -1.0, 1.0).unwrap_err();
        assert_eq!(bad.argument(), "inside");
        assert_eq!(
            Zone::new(zone.polygons.clone(), 1.0, f64::INFINITY)
                .unwrap_err()
                .argument(),
            "outside"
        );
    }
}
