//! Elevation sectors: limits on a target's angle above the sensor's horizontal plane, e.g.
//! a surveillance radar's beam from −2° to +30°.
//!
//! A target at offset (dx, dy, dz) from the sensor has elevation ε = atan2(dz, √(dx²+dy²))
//! in [−π/2, π/2]. It is inside [lower, upper] (boundary included) when
//! r sin(lower) ≤ dz ≤ r sin(upper), r = √(dx²+dy²+dz²) the slant range: sin is increasing
//! on [−π/2, π/2] and dz = r sin ε, so no arctangent is needed — nor a square root: with
//! s = sin(limit) and r² the squared slant range, dz ≥ r s ⇔ (dz ≥ 0 and dz² ≥ r² s²) when
//! s ≥ 0, and (dz ≥ 0 or dz² ≤ r² s²) when s < 0; dz ≤ r s mirrors it. A lower limit at
//! −π/2 or an upper one at +π/2 bounds nothing and is not tested (so a target straight
//! below or above is inside it whatever the rounding). The sensor's own position (r = 0)
//! is inside. Offsets beyond about 1e150 m (whose squares overflow) or below 1e-150 m
//! (whose squares underflow) are decided to no stated accuracy.

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
    below: Limit,
    above: Limit,
}

/// How one limit is tested: not at all (±π/2), or against sin²(limit) on the side its
/// sign says.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Limit {
    Open,
    /// sin(limit) ≥ 0, and its square.
    NonNegative(f64),
    /// sin(limit) < 0, and its square.
    Negative(f64),
}

impl Limit {
    /// The test of a limit at `angle`; `open` when the limit bounds nothing (a lower one at
    /// −π/2, an upper one at +π/2).
    fn of(angle: f64, open: bool) -> Limit {
        if open {
            return Limit::Open;
        }
        let s = angle.sin();
        if s >= 0.0 {
            Limit::NonNegative(s * s)
        } else {
            Limit::Negative(s * s)
        }
    }
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
            below: Limit::of(lower, lower <= -FRAC_PI_2),
            above: Limit::of(upper, upper >= FRAC_PI_2),
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
        let dz2 = dz * dz;
        // dz ≥ r sin(lower)
        let above = match self.below {
            Limit::Open => true,
            Limit::NonNegative(s2) => dz >= 0.0 && dz2 >= r2 * s2,
            Limit::Negative(s2) => dz >= 0.0 || dz2 <= r2 * s2,
        };
        // dz ≤ r sin(upper)
        let below = match self.above {
            Limit::Open => true,
            Limit::NonNegative(s2) => dz <= 0.0 || dz2 <= r2 * s2,
            Limit::Negative(s2) => dz <= 0.0 && dz2 >= r2 * s2,
        };
        select(above & below, self.inside, self.outside)
    }

    /// [`Self::at`] for four targets, the same bits. Which test applies to each limit is a
    /// property of the sector, chosen outside the lanes.
    #[inline(always)]
    pub(crate) fn lanes_at<L: Lanes>(&self, dz: L, r2: L) -> L {
        let (zero, dz2) = (L::splat(0.0), dz * dz);
        let above = match self.below {
            Limit::Open => None,
            Limit::NonNegative(s2) => Some(L::and(dz.ge(zero), dz2.ge(r2 * L::splat(s2)))),
            Limit::Negative(s2) => Some(L::or(dz.ge(zero), dz2.le(r2 * L::splat(s2)))),
        };
        let below = match self.above {
            Limit::Open => None,
            Limit::NonNegative(s2) => Some(L::or(dz.le(zero), dz2.le(r2 * L::splat(s2)))),
            Limit::Negative(s2) => Some(L::and(dz.le(zero), dz2.ge(r2 * L::splat(s2)))),
        };
        let inside = match (above, below) {
            (None, None) => return L::splat(self.inside),
            (Some(m), None) | (None, Some(m)) => m,
            (Some(a), Some(b)) => L::and(a, b),
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
        // on a limit, to rounding: dz = r sin(upper) with r the slant range
        let up = 30f64.to_radians();
        assert_eq!(s.at(500.0 * up.sin() * (1.0 - 1e-12), 500.0 * 500.0), 1.0);
        assert_eq!(s.at(500.0 * up.sin() * (1.0 + 1e-12), 500.0 * 500.0), 0.0);
        // negative limits: below −2° is outside, between them inside, for either sign of dz
        let (lo, hi) = (-2f64.to_radians(), -1f64.to_radians());
        let neg = ElevationSector::new(lo, hi, 1.0, 0.0).unwrap();
        for (deg, want) in [(-2.5, 0.0), (-1.5, 1.0), (-0.5, 0.0), (0.5, 0.0)] {
            assert_eq!(value_at(&neg, f64::to_radians(deg)), want, "{deg}°");
        }
        let pos = ElevationSector::new(1f64.to_radians(), 2f64.to_radians(), 1.0, 0.0).unwrap();
        for (deg, want) in [(0.5, 0.0), (1.5, 1.0), (2.5, 0.0), (-1.5, 0.0)] {
            assert_eq!(value_at(&pos, f64::to_radians(deg)), want, "{deg}°");
        }
    }

    #[test]
    fn a_limit_at_the_zenith_bounds_nothing() {
        let s = ElevationSector::new(0.0, FRAC_PI_2, 1.0, 0.0).unwrap();
        assert_eq!(s.at(1e-200, 0.0), 1.0, "straight up, its square underflowed");
        assert_eq!(s.at(-1.0, 1.0), 0.0);
        let all = ElevationSector::new(-FRAC_PI_2, FRAC_PI_2, 0.5, 0.0).unwrap();
        assert_eq!(all.at(-7.0, 49.0), 0.5);
        // a lower limit at the zenith bounds: straight up only
        let zenith = ElevationSector::new(FRAC_PI_2, FRAC_PI_2, 1.0, 0.0).unwrap();
        assert_eq!(zenith.at(10.0, 100.0), 1.0);
        assert_eq!(zenith.at(0.0, 100.0), 0.0);
        assert_eq!(zenith.at(-10.0, 100.0), 0.0);
        let nadir = ElevationSector::new(-FRAC_PI_2, -FRAC_PI_2, 1.0, 0.0).unwrap();
        assert_eq!(nadir.at(-10.0, 100.0), 1.0);
        assert_eq!(nadir.at(1.0, 2.0), 0.0);
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
