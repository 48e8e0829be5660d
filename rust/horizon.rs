//! The radar horizon for targets whose height is read from their state.
//!
//! Over a sphere of effective radius kR an antenna at height h_a sees a target at height
//! h_t up to the plane distance d(h_t) = √(2kR h_a) + √(2kR max(h_t, 0)) (the sum of the two
//! tangent lengths to first order in h/kR); a target below the sea counts as at it. The
//! factor is 1 where the target's plane distance from the sensor is at most d, 0 beyond:
//! compared squared, h² ≤ d², so no square root of the plane distance is taken. (With the
//! target height fixed the horizon is a range band: see the Python `RadarHorizon`.)

use crate::error::{ModelError, Result};
use crate::range_bands::select;
use crate::simd::Lanes;

#[derive(Debug, Clone, PartialEq)]
pub struct Horizon {
    /// √(2kR h_a), metres.
    antenna_reach: f64,
    /// 2kR, metres.
    scale: f64,
}

impl Horizon {
    /// The horizon of an antenna whose own tangent length is `antenna_reach` = √(2kR h_a),
    /// on a sphere with 2kR = `scale`.
    pub fn new(antenna_reach: f64, scale: f64) -> Result<Self> {
        if !(antenna_reach.is_finite() && antenna_reach >= 0.0) {
            return Err(ModelError::invalid(
                "antenna_reach",
                format!("must be a finite distance ≥ 0, got {antenna_reach}"),
            ));
        }
        if !(scale.is_finite() && scale > 0.0) {
            return Err(ModelError::invalid(
                "scale",
                format!("2kR must be finite and > 0, got {scale}"),
            ));
        }
        Ok(Horizon { antenna_reach, scale })
    }

    pub fn parts(&self) -> [f64; 2] {
        [self.antenna_reach, self.scale]
    }

    /// 1 when a target at height `z` and squared plane distance `h2` is within the
    /// horizon, else 0.
    #[inline(always)]
    pub fn at(&self, h2: f64, z: f64) -> f64 {
        let raised = if z > 0.0 { z } else { 0.0 };
        let reach = self.antenna_reach + (self.scale * raised).sqrt();
        select(h2 <= reach * reach, 1.0, 0.0)
    }

    /// [`Self::at`] for four targets, the same bits. (A NaN height counts as 0 here; the
    /// kernels report such a state as not finite.)
    #[inline(always)]
    pub(crate) fn lanes_at<L: Lanes>(&self, h2: L, z: L) -> L {
        let zero = L::splat(0.0);
        let raised = L::select(z.gt(zero), z, zero);
        let reach = L::splat(self.antenna_reach) + (L::splat(self.scale) * raised).sqrt();
        L::select(h2.le(reach * reach), L::splat(1.0), zero)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_edge_grows_with_the_target_height() {
        let scale = 2.0 * 4.0 / 3.0 * 6_371_000.0;
        let h = Horizon::new((scale * 20.0f64).sqrt(), scale).unwrap();
        let d0 = (scale * 20.0f64).sqrt();
        assert_eq!(h.at(d0 * d0, 0.0), 1.0);
        assert_eq!(h.at((d0 * 1.0001).powi(2), 0.0), 0.0);
        assert_eq!(h.at((d0 * 1.0001).powi(2), -5.0), 0.0, "below the sea counts as at it");
        let d100 = d0 + (scale * 100.0f64).sqrt();
        assert_eq!(h.at((d100 * 0.9999).powi(2), 100.0), 1.0);
        assert_eq!(h.at((d100 * 1.0001).powi(2), 100.0), 0.0);
    }

    #[test]
    fn bad_parts_are_named() {
        assert_eq!(Horizon::new(-1.0, 1.0).unwrap_err().argument(), "antenna_reach");
        assert_eq!(Horizon::new(1.0, 0.0).unwrap_err().argument(), "scale");
        assert_eq!(Horizon::new(1.0, f64::INFINITY).unwrap_err().argument(), "scale");
    }
}
