//! Elevation sectors: limits on a target's angle above the sensor's horizontal plane, e.g.
//! a surveillance radar's beam from −2° to +30°.
//!
//! A target at offset (dx, dy, dz) from the sensor has elevation ε = atan2(dz, √(dx²+dy²))
//! in [−π/2, π/2]. It is inside [lower, upper] (boundary included) when
//! r sin(lower) ≤ dz ≤ r sin(upper), r = √(dx²+dy²+dz²) the slant range: sin is increasing
//! on [−π/2, π/2] and dz = r sin ε, so no arctangent is needed. A limit at ±π/2 bounds
//! nothing and is not tested (so a target straight above or below is inside it whatever
//! the rounding). The sensor's own position (r = 0) is inside.

use crate::error::{ModelError, Result};
use crate::range_bands::select;
use crate::simd::Lanes;
use std::f64::consts::FRAC_PI_2;

#[derive(Debug, Clone, PartialEq)]
pub struct ElevationSector {
    lower: f64,
    upper: f64,
    inside: f64,
    outside: f64,
    sin_lower: f64,
    sin_upper: f64,
}

impl ElevationSector {
    pub fn new(lower: f64, upper: f64, inside: f64, outside: f64) -> Result<Self> {
        for (name, v) in [("lower", lower), ("upper", upper)] {
            if !(v.is_finite() && v.abs() <= FRAC_PI_2) {
                return Err(ModelError::invalid(
                    name,
                    format!("must be an elevation in [−π/2, π/2] radians, got {v} (pass degrees through math.radians)"),
                ));
            }
        }
        if lower > upper {
            return Err(ModelError::invalid(
                "upper",
                format!("must be at least lower ({lower}), got {upper}"),
            ));
        }
        for (name, v) in [("inside", inside), ("outside", outside)] {
            if !v.is_finite() {
                return Err(ModelError::invalid(name, format!("must be finite, got {v}")));
            }
        }
        Ok(ElevationSector {
            lower,
            upper,
            inside,
            outside,
            sin_lower: lower.sin(),
            sin_upper: upper.sin(),
        })
    }

    pub fn values(&self) -> [f64; 2] {
        [self.inside, self.outside]
    }

    pub fn limits(&self) -> [f64; 2] {
        [self.lower, self.upper]
    }

    /// The value at height offset `dz` and squared slant range `r2`.
    #[inline(always)]
    pub fn at(&self, dz: f64, r2: f64) -> f64 {
        let r = r2.sqrt();
        let above = self.lower <= -FRAC_PI_2 || dz >= r * self.sin_lower;
        let below = self.upper >= FRAC_PI_2 || dz <= r * self.sin_upper;
        select(above & below, self.inside, self.outside)
    }

    /// [`Self::at`] for four targets, the same bits.
    #[inline(always)]
    pub(crate) fn lanes_at<L: Lanes>(&self, dz: L, r2: L) -> L {
        let r = r2.sqrt();
        let inside = match (self.lower <= -FRAC_PI_2, self.upper >= FRAC_PI_2) {
            (true, true) => return L::splat(self.inside),
            (true, false) => dz.le(r * L::splat(self.sin_upper)),
            (false, true) => dz.ge(r * L::splat(self.sin_lower)),
            (false, false) => L::and(dz.ge(r * L::splat(self.sin_lower)), dz.le(r * L::splat(self.sin_upper))),
        };
        L::select(inside, L::splat(self.inside), L::splat(self.outside))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value_at(sector: &ElevationSector, elevation: f64) -> f64 {
        let (dz, h) = (1000.0 * elevation.sin(), 1000.0 * elevation.cos());
        sector.at(dz, h * h + dz * dz)
    }

    #[test]
    fn inside_between_the_limits_boundary_included() {
        let s = ElevationSector::new(-2f64.to_radians(), 30f64.to_radians(), 1.0, 0.0).unwrap();
        for (deg, want) in [
            (-3.0, 0.0),
            (-1.9, 1.0),
            (0.0, 1.0),
            (29.9, 1.0),
            (30.1, 0.0),
            (89.0, 0.0),
        ] {
            assert_eq!(value_at(&s, f64::to_radians(deg)), want, "{deg}°");
        }
        assert_eq!(s.at(0.0, 0.0), 1.0, "the sensor's own position is inside");
        // exactly on a limit: dz = r sin(upper) with r the slant range
        let up = 30f64.to_radians();
        assert_eq!(s.at(500.0 * up.sin(), 500.0 * 500.0), 1.0);
    }

    #[test]
    fn a_limit_at_the_zenith_bounds_nothing() {
        let s = ElevationSector::new(0.0, FRAC_PI_2, 1.0, 0.0).unwrap();
        assert_eq!(s.at(1e-200, 0.0), 1.0, "straight up, its square underflowed");
        assert_eq!(s.at(-1.0, 1.0), 0.0);
        let all = ElevationSector::new(-FRAC_PI_2, FRAC_PI_2, 0.5, 0.0).unwrap();
        assert_eq!(all.at(-7.0, 49.0), 0.5);
    }

    #[test]
    fn degrees_and_reversed_limits_are_rejected() {
        assert_eq!(
            ElevationSector::new(0.0, 30.0, 1.0, 0.0).unwrap_err().argument(),
            "upper"
        );
        assert_eq!(
            ElevationSector::new(-91.0, 0.0, 1.0, 0.0).unwrap_err().argument(),
            "lower"
        );
        assert_eq!(
            ElevationSector::new(0.2, 0.1, 1.0, 0.0).unwrap_err().argument(),
            "upper"
        );
        assert_eq!(
            ElevationSector::new(f64::NAN, 0.1, 1.0, 0.0).unwrap_err().argument(),
            "lower"
        );
        assert_eq!(
            ElevationSector::new(0.0, 0.1, f64::NAN, 0.0).unwrap_err().argument(),
            "inside"
        );
    }
}
