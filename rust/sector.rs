//! Angular sectors in the sensor's body frame, e.g. a radar's blind sector astern.
//!
//! A sector is centred on body-frame bearing `centre` with total `width` (radians, in
//! (0, 2π]); a point is inside when the angle between its direction and the centre is at
//! most width/2 — boundary included. The test uses a dot product against the centre
//! direction (no atan2), which handles the ±π wrap-around without special cases:
//! inside ⇔ d·c ≥ |d| cos(width/2). The sensor's own position (|d| = 0) counts as inside.

use crate::error::{ModelError, Result};
use crate::pose::SensorFrame;
use crate::range_bands::select;
use crate::simd::Lanes;
use std::f64::consts::{PI, TAU};

#[derive(Debug, Clone, PartialEq)]
pub struct AngularSector {
    centre: f64,
    width: f64,
    inside: f64,
    outside: f64,
    cos_half: f64,
}

impl AngularSector {
    pub fn new(centre: f64, width: f64, inside: f64, outside: f64) -> Result<Self> {
        if !centre.is_finite() || centre.abs() > 2.0 * TAU {
            return Err(ModelError::invalid(
                "centre",
                format!(
                    "must be a finite angle in radians within ±4π, got {centre} (pass degrees through math.radians)"
                ),
            ));
        }
        if !(width > 0.0 && width <= TAU) {
            return Err(ModelError::invalid(
                "width",
                format!("must be in (0, 2π] radians, got {width} (pass degrees through math.radians)"),
            ));
        }
        for (name, v) in [("inside", inside), ("outside", outside)] {
            if !v.is_finite() {
                return Err(ModelError::invalid(name, format!("must be finite, got {v}")));
            }
        }
        // A full circle must be inside everywhere: cos(π) = -1 exactly keeps it so.
        let cos_half = if width >= TAU {
            -1.0
        } else {
            (width / 2.0).min(PI).cos()
        };
        Ok(AngularSector {
            centre,
            width,
            inside,
            outside,
            cos_half,
        })
    }

    pub fn values(&self) -> [f64; 2] {
        [self.inside, self.outside]
    }

    /// The per-scan form: the sector's centre direction turned into the world frame.
    /// The sector in the sensor's own frame (bearings from its boresight): for offsets
    /// already turned into that frame (a pitched or rolled pose's).
    pub fn in_sensor_frame(&self) -> FramedSector {
        let (sin, cos) = self.centre.sin_cos();
        FramedSector {
            centre: [cos, sin],
            cos_half: self.cos_half,
            inside: self.inside,
            outside: self.outside,
        }
    }

    pub fn in_frame(&self, frame: &SensorFrame) -> FramedSector {
        FramedSector {
            centre: frame.world_direction(self.centre),
            cos_half: self.cos_half,
            inside: self.inside,
            outside: self.outside,
        }
    }
}

/// An [`AngularSector`] for one pose; `at` takes the world-frame offset from the sensor.
#[derive(Debug, Clone, Copy)]
pub struct FramedSector {
    centre: [f64; 2],
    cos_half: f64,
    inside: f64,
    outside: f64,
}

impl FramedSector {
    /// Inside test on the squared range r² (no square root): with c = cos(width/2),
    /// d·u ≥ r c ⇔ (d·u ≥ 0 and (d·u)² ≥ r² c²) when c ≥ 0, and
    /// (d·u ≥ 0 or (d·u)² ≤ r² c²) when c < 0. A full circle is inside everywhere.
    #[inline(always)]
    pub fn at_squared(&self, dx: f64, dy: f64, r2: f64) -> f64 {
        let along = dx * self.centre[0] + dy * self.centre[1];
        let bound = r2 * self.cos_half * self.cos_half;
        let ahead = along >= 0.0;
        let narrow = self.cos_half >= 0.0;
        let inside = (narrow & ahead & (along * along >= bound))
            | (!narrow & (ahead | (along * along <= bound) | (self.cos_half <= -1.0)));
        select(inside, self.inside, self.outside)
    }

    /// [`Self::at_squared`] for four offsets, the same bits. Which of the two tests applies
    /// is a property of the sector, so it is chosen once, outside the lanes.
    #[inline(always)]
    pub(crate) fn lanes_at_squared<L: Lanes>(&self, dx: L, dy: L, r2: L) -> L {
        if self.is_narrow() {
            return self.lanes_narrow(dx, dy, r2);
        }
        if self.cos_half <= -1.0 {
            return L::splat(self.inside); // a full circle
        }
        let along = dx * L::splat(self.centre[0]) + dy * L::splat(self.centre[1]);
        let bound = r2 * L::splat(self.cos_half) * L::splat(self.cos_half);
        let inside = L::or(along.ge(L::splat(0.0)), (along * along).le(bound));
        L::select(inside, L::splat(self.inside), L::splat(self.outside))
    }

    /// Whether the sector is at most a half-plane wide (cos(width/2) ≥ 0): a blind sector
    /// behind a radar, say. Kernels choose [`Self::lanes_narrow`] once for such a sector.
    #[inline(always)]
    pub(crate) fn is_narrow(&self) -> bool {
        self.cos_half >= 0.0
    }

    /// [`Self::lanes_at_squared`] of a sector that [`Self::is_narrow`], without the test.
    #[inline(always)]
    pub(crate) fn lanes_narrow<L: Lanes>(&self, dx: L, dy: L, r2: L) -> L {
        let along = dx * L::splat(self.centre[0]) + dy * L::splat(self.centre[1]);
        let bound = r2 * L::splat(self.cos_half) * L::splat(self.cos_half);
        let inside = L::and(along.ge(L::splat(0.0)), (along * along).ge(bound));
        L::select(inside, L::splat(self.inside), L::splat(self.outside))
    }

    #[inline(always)]
    pub fn at(&self, dx: f64, dy: f64, range: f64) -> f64 {
        let along = dx * self.centre[0] + dy * self.centre[1];
        if along >= range * self.cos_half {
            self.inside
        } else {
            self.outside
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::Pose;

    fn blind_astern() -> AngularSector {
        AngularSector::new(PI, 65f64.to_radians(), 0.0, 1.0).unwrap()
    }

    fn value_at_bearing(sector: &AngularSector, heading: f64, bearing: f64) -> f64 {
        let frame = Pose::new(0.0, 0.0, heading).unwrap().frame();
        let s = sector.in_frame(&frame);
        let (sin, cos) = (heading + bearing).sin_cos();
        s.at(100.0 * cos, 100.0 * sin, 100.0)
    }

    #[test]
    fn blind_sector_astern_across_wrap() {
        let s = blind_astern();
        let half = 32.5f64.to_radians();
        for heading in [0.0, 1.0, -2.5, 3.1] {
            assert_eq!(value_at_bearing(&s, heading, PI), 0.0);
            assert_eq!(value_at_bearing(&s, heading, -PI + half - 1e-6), 0.0);
            assert_eq!(value_at_bearing(&s, heading, PI - half + 1e-6), 0.0);
            assert_eq!(value_at_bearing(&s, heading, PI - half - 1e-6), 1.0);
            assert_eq!(value_at_bearing(&s, heading, 0.0), 1.0);
        }
    }

    #[test]
    fn wide_sectors_and_full_circle() {
        let wide = AngularSector::new(0.0, 300f64.to_radians(), 1.0, 0.0).unwrap();
        assert_eq!(value_at_bearing(&wide, 0.0, 149f64.to_radians()), 1.0);
        assert_eq!(value_at_bearing(&wide, 0.0, 151f64.to_radians()), 0.0);
        let full = AngularSector::new(0.0, TAU, 1.0, 0.0).unwrap();
        assert_eq!(value_at_bearing(&full, 0.0, PI), 1.0);
    }

    #[test]
    fn squared_test_matches_range_test() {
        let frame = Pose::new(0.0, 0.0, 0.4).unwrap().frame();
        for width_deg in [10.0, 65.0, 179.0, 181.0, 300.0, 360.0] {
            let s = AngularSector::new(2.0, f64::to_radians(width_deg), 0.25, 0.75)
                .unwrap()
                .in_frame(&frame);
            for k in 0..3600 {
                let b = k as f64 * 0.1f64.to_radians() + 0.00037;
                let (dx, dy) = (250.0 * b.cos(), 250.0 * b.sin());
                let r2 = dx * dx + dy * dy;
                assert_eq!(
                    s.at_squared(dx, dy, r2),
                    s.at(dx, dy, r2.sqrt()),
                    "width {width_deg} bearing {b}"
                );
            }
            assert_eq!(s.at_squared(0.0, 0.0, 0.0), 0.25, "the sensor's own position is inside");
        }
    }

    #[test]
    fn degrees_are_rejected() {
        assert_eq!(AngularSector::new(PI, 65.0, 0.0, 1.0).unwrap_err().argument(), "width");
        assert_eq!(AngularSector::new(PI, 0.0, 0.0, 1.0).unwrap_err().argument(), "width");
        assert_eq!(
            AngularSector::new(f64::NAN, 1.0, 0.0, 1.0).unwrap_err().argument(),
            "centre"
        );
    }
}
