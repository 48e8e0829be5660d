//! Sensor pose: where the sensor is and where it points at one scan.
//!
//! Angle convention (the whole crate): Stone Soup's. World coordinates are x/y Cartesian
//! metres; headings and bearings are radians measured counter-clockwise from +x. A sensor's
//! body frame has its x axis along the sensor heading (boresight), y to its left, so a
//! body-frame bearing of π is straight astern. Heights (z) are metres up. A pose may also
//! be pitched and rolled, as Stone Soup orients a sensor by [roll, pitch, yaw]: a world
//! offset d is then d_s = M d in the sensor's frame, with
//! M = R_x(−roll) · R_y(pitch) · R_z(−heading) (Stone Soup's `build_rotation_matrix`; a
//! positive pitch tilts the boresight up), and bearings and elevations are d_s's. Without
//! pitch and roll the frame turns about the vertical only and elevations are the world's.

use crate::error::{ModelError, Result};

/// Where a sensor sits on its platform: a lever arm in the platform's body frame
/// (forward, left, up; metres) and a yaw offset of the sensor's boresight (radians).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Mounting {
    pub forward: f64,
    pub left: f64,
    pub yaw: f64,
    pub up: f64,
}

impl Mounting {
    pub fn new(forward: f64, left: f64, yaw: f64) -> Result<Self> {
        Mounting::raised(forward, left, yaw, 0.0)
    }

    /// A mounting `up` metres above the platform's reference point.
    pub fn raised(forward: f64, left: f64, yaw: f64, up: f64) -> Result<Self> {
        for (name, v) in [
            ("mounting.forward", forward),
            ("mounting.left", left),
            ("mounting.yaw", yaw),
            ("mounting.up", up),
        ] {
            if !v.is_finite() {
                return Err(ModelError::invalid(name, format!("must be finite, got {v}")));
            }
        }
        Ok(Mounting { forward, left, yaw, up })
    }
}

/// Position, height, heading and velocity of a platform (or directly of a sensor) in the
/// world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub x: f64,
    pub y: f64,
    pub heading: f64,
    /// Height, metres (0 for a planar pose).
    pub z: f64,
    /// World-frame velocity (x, y, z), m/s: what range rates are relative to.
    pub velocity: [f64; 3],
    /// Pitch (a positive one tilts the boresight up) and roll, radians, Stone Soup's.
    pub pitch: f64,
    pub roll: f64,
}

impl Pose {
    pub fn new(x: f64, y: f64, heading: f64) -> Result<Self> {
        Pose::raised(x, y, heading, 0.0)
    }

    /// A pose at height `z`.
    pub fn raised(x: f64, y: f64, heading: f64, z: f64) -> Result<Self> {
        for (name, v) in [("pose.x", x), ("pose.y", y), ("pose.heading", heading), ("pose.z", z)] {
            if !v.is_finite() {
                return Err(ModelError::invalid(name, format!("must be finite, got {v}")));
            }
        }
        Ok(Pose {
            x,
            y,
            heading,
            z,
            velocity: [0.0; 3],
            pitch: 0.0,
            roll: 0.0,
        })
    }

    /// This pose pitched and rolled (radians; see the module docs).
    pub fn tilted(self, pitch: f64, roll: f64) -> Result<Self> {
        for (name, v) in [("pose.pitch", pitch), ("pose.roll", roll)] {
            if !v.is_finite() {
                return Err(ModelError::invalid(name, format!("must be finite, got {v}")));
            }
        }
        Ok(Pose { pitch, roll, ..self })
    }

    /// This pose moving at `velocity` (x, y, z; m/s).
    pub fn moving(self, velocity: [f64; 3]) -> Result<Self> {
        if let Some(v) = velocity.iter().find(|v| !v.is_finite()) {
            return Err(ModelError::invalid("pose.velocity", format!("must be finite, got {v}")));
        }
        Ok(Pose { velocity, ..self })
    }

    /// The pose of a sensor mounted on this platform (moving with it: the lever arm's own
    /// speed while the platform turns is left out); an error naming `mounting` when the
    /// sum overflows (finite inputs near the largest float can make an infinite pose).
    pub fn mount(&self, mounting: &Mounting) -> Result<Pose> {
        let (s, c) = self.heading.sin_cos();
        let (x, y) = (
            self.x + c * mounting.forward - s * mounting.left,
            self.y + s * mounting.forward + c * mounting.left,
        );
        let heading = self.heading + mounting.yaw;
        let z = self.z + mounting.up;
        if !(x.is_finite() && y.is_finite() && heading.is_finite() && z.is_finite()) {
            return Err(ModelError::invalid("mounting", format!("the mounted sensor pose ({x}, {y}, {heading}) at height {z} is not finite: the lever arm or yaw overflows the platform's pose")));
        }
        Ok(Pose {
            x,
            y,
            heading,
            z,
            ..*self
        })
    }

    /// The precomputed world→sensor transform of this pose.
    pub fn frame(&self) -> SensorFrame {
        let (sin, cos) = self.heading.sin_cos();
        SensorFrame {
            origin: [self.x, self.y],
            height: self.z,
            velocity: self.velocity,
            cos,
            sin,
            tilt: (self.pitch != 0.0 || self.roll != 0.0).then(|| self.rotation()),
        }
    }

    /// M = R_x(−roll) · R_y(pitch) · R_z(−heading), world offset → sensor frame.
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        let (sr, cr) = self.roll.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        let (sh, ch) = self.heading.sin_cos();
        // R_z(−h) = [[ch, sh, 0], [−sh, ch, 0], [0, 0, 1]]; R_y(p) = [[cp, 0, sp], [0, 1, 0],
        // [−sp, 0, cp]]; R_x(−r) = [[1, 0, 0], [0, cr, sr], [0, −sr, cr]]
        let ry_rz = [[cp * ch, cp * sh, sp], [-sh, ch, 0.0], [-sp * ch, -sp * sh, cp]];
        let [a, b, c] = ry_rz;
        let mix = |u: f64, v: f64| -> [f64; 3] { [u * b[0] + v * c[0], u * b[1] + v * c[1], u * b[2] + v * c[2]] };
        [a, mix(cr, sr), mix(-sr, cr)]
    }
}

/// A pose with its heading's sine and cosine computed once, for evaluating many points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorFrame {
    pub origin: [f64; 2],
    pub height: f64,
    pub velocity: [f64; 3],
    pub cos: f64,
    pub sin: f64,
    /// World offset → sensor frame when the pose is pitched or rolled ([`Pose::rotation`]).
    pub tilt: Option<[[f64; 3]; 3]>,
}

impl SensorFrame {
    /// A body-frame direction (unit vector at `bearing`) expressed in the world frame.
    pub fn world_direction(&self, bearing: f64) -> [f64; 2] {
        let (s, c) = bearing.sin_cos();
        [self.cos * c - self.sin * s, self.sin * c + self.cos * s]
    }

    /// World point → body-frame point (forward, left).
    pub fn to_body(&self, p: [f64; 2]) -> [f64; 2] {
        let dx = p[0] - self.origin[0];
        let dy = p[1] - self.origin[1];
        [self.cos * dx + self.sin * dy, -self.sin * dx + self.cos * dy]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn close(a: [f64; 2], b: [f64; 2]) -> bool {
        (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12
    }

    #[test]
    fn body_frame_of_north_facing_sensor() {
        // Heading +y: a point to the east (+x) is on the sensor's right (negative left).
        let frame = Pose::new(10.0, 20.0, FRAC_PI_2).unwrap().frame();
        assert!(close(frame.to_body([15.0, 20.0]), [0.0, -5.0]));
        assert!(close(frame.to_body([10.0, 27.0]), [7.0, 0.0]));
    }

    #[test]
    fn world_direction_astern() {
        let frame = Pose::new(0.0, 0.0, 0.3).unwrap().frame();
        let d = frame.world_direction(PI);
        assert!(close(d, [(0.3f64 + PI).cos(), (0.3f64 + PI).sin()]));
    }

    #[test]
    fn a_mounting_that_overflows_the_pose_is_an_error() {
        let platform = Pose::new(0.0, f64::MAX, 0.0).unwrap();
        let err = platform.mount(&Mounting::new(0.0, f64::MAX, 0.0).unwrap()).unwrap_err();
        assert!(err.to_string().starts_with("mounting"), "{err}");
        assert!(platform.mount(&Mounting::new(0.0, -1.0, 0.0).unwrap()).is_ok());
    }

    #[test]
    fn mounting_lever_arm_and_yaw() {
        let platform = Pose::new(1.0, 2.0, FRAC_PI_2).unwrap();
        let sensor = platform.mount(&Mounting::new(3.0, 1.0, 0.5).unwrap()).unwrap();
        // Forward is +y, left is -x for a north-facing platform.
        assert!((sensor.x - 0.0).abs() < 1e-12);
        assert!((sensor.y - 5.0).abs() < 1e-12);
        assert!((sensor.heading - (FRAC_PI_2 + 0.5)).abs() < 1e-15);
    }

    #[test]
    fn a_mounting_raises_the_sensor() {
        let platform = Pose::raised(0.0, 0.0, 0.0, 12.0).unwrap();
        let sensor = platform.mount(&Mounting::raised(0.0, 0.0, 0.0, 3.5).unwrap()).unwrap();
        assert_eq!(sensor.z, 15.5);
        assert_eq!(sensor.frame().height, 15.5);
        assert_eq!(Pose::raised(0.0, 0.0, 0.0, f64::NAN).unwrap_err().argument(), "pose.z");
        assert_eq!(
            Mounting::raised(0.0, 0.0, 0.0, f64::INFINITY).unwrap_err().argument(),
            "mounting.up"
        );
    }

    #[test]
    fn non_finite_pose_is_rejected() {
        let err = Pose::new(f64::NAN, 0.0, 0.0).unwrap_err();
        assert_eq!(err.argument(), "pose.x");
    }
}
