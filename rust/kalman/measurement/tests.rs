//! Unit tests of the measurement models.

use super::*;
use nalgebra::DVector;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn radar(jacobian: Jacobian, yaw: f64) -> MeasurementModel {
    let (s, c) = yaw.sin_cos();
    // Stone Soup's rotation matrix for rotation_offset (0, 0, yaw) rotates world into
    // the sensor frame: R = Rz(−yaw).
    MeasurementModel::bearing_range(
        [0, 2],
        [10.0, -20.0],
        &[c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0],
        &[1e-4, 0.0, 0.0, 1.0],
        jacobian,
    )
    .unwrap()
}

#[test]
fn python_modulo_semantics() {
    assert_eq!(python_mod(-1.0, TWO_PI), -1.0 + TWO_PI);
    assert_eq!(python_mod(7.0, TWO_PI), 7.0 % TWO_PI);
    assert_eq!(mod_bearing(PI), -PI);
    assert!(mod_bearing(-PI - 0.1) > 3.0);
}

#[test]
fn spacing_matches_numpy() {
    assert_eq!(spacing(1.0), f64::EPSILON);
    assert_eq!(spacing(-1.0), -f64::EPSILON);
    assert_eq!(spacing(0.0), f64::from_bits(1));
}

#[test]
fn analytic_and_finite_difference_jacobians_agree() {
    let x = [512.0, 3.0, -230.0, -1.5];
    for yaw in [0.0, 0.7, -2.9] {
        let mut z = [0.0; 2];
        let mut fd = [0.0; 8];
        let mut exact = [0.0; 8];
        radar(Jacobian::FiniteDifference, yaw).linearise(&x, &mut z, &mut fd);
        radar(Jacobian::Analytic, yaw).linearise(&x, &mut z, &mut exact);
        for (a, b) in fd.iter().zip(&exact) {
            // the finite difference's round-off: ε·|φ|/δ with δ = 1e-8 for negative
            // coordinates, ~1e-5 relative to a derivative of ~1e-3
            assert!((a - b).abs() <= 1e-4 * b.abs().max(1e-6), "{a} vs {b}");
        }
        assert_eq!(exact[1], 0.0);
        assert_eq!(exact[4 + 3], 0.0);
    }
}

#[test]
fn analytic_falls_back_at_the_sensor() {
    let x = [10.0, 0.0, -20.0, 0.0];
    let mut z = [0.0; 2];
    let mut h = [f64::NAN; 8];
    radar(Jacobian::Analytic, 0.3).linearise(&x, &mut z, &mut h);
    assert!(h.iter().all(|v| v.is_finite()));
}

#[test]
fn bearing_difference_is_wrapped() {
    let model = radar(Jacobian::Analytic, 0.0);
    let mut out = [0.0; 2];
    model.difference(&[3.1, 5.0], &[-3.1, 2.0], &mut out);
    assert!((out[0] - (6.2 - TWO_PI)).abs() < 1e-12);
    assert_eq!(out[1], 3.0);
}

#[test]
fn mod_bearing_is_the_floored_modulo() {
    assert_eq!(mod_bearing(PI), -PI);
    assert_eq!(mod_bearing(-PI), -PI);
    assert_eq!(mod_bearing(0.5), 0.5);
    assert!((mod_bearing(3.0 * PI + 0.25) - (-PI + 0.25)).abs() < 1e-12);
    assert_eq!(spacing(1.0), f64::EPSILON);
    assert_eq!(spacing(-1.0), -f64::EPSILON);
}

#[test]
fn analytic_and_finite_difference_jacobians_agree_in_nalgebra_types() {
    let x = DVector::from_vec(vec![300.0, 2.0, -150.0, 1.0]);
    let (z_fd, h_fd) = radar(Jacobian::FiniteDifference, 0.7).linearised(&x);
    let (z_an, h_an) = radar(Jacobian::Analytic, 0.7).linearised(&x);
    assert_eq!(z_fd, z_an);
    // Forward differences with steps of 1e-8 (negative coordinates) carry an error of
    // one ulp of the value over the step: ~6e-14 / 1e-8 for a range of 300 m (Stone Soup's
    // own Jacobian here is off by 3.7e-6 in ∂ρ/∂y).
    for (a, b) in h_fd.iter().zip(h_an.iter()) {
        assert!((a - b).abs() <= 1e-5, "{a} vs {b}");
    }
    assert_eq!(h_an[(0, 1)], 0.0);
    assert_eq!(h_fd[(1, 3)], 0.0);
}

/// The bearing helpers against their definitions: Stone Soup's
/// floored `((x + π) mod 2π) − π` (as `rem_euclid`) and NumPy's `spacing` (as a branch on
/// the sign), bit for bit.
#[test]
fn bearing_helpers_are_their_definitions() {
    let floored = |x: f64| (x + PI).rem_euclid(2.0 * PI) - PI;
    let numpy_spacing = |x: f64| {
        let magnitude = x.abs();
        let step = f64::from_bits(magnitude.to_bits() + 1) - magnitude;
        if x.is_sign_negative() {
            -step
        } else {
            step
        }
    };
    let mut rng = StdRng::seed_from_u64(12);
    let mut values: Vec<f64> = (0..100_000).map(|_| rng.random_range(-40.0..40.0)).collect();
    values.extend((0..10_000).map(|_| rng.random_range(-1e6..1e6)));
    values.extend([
        0.0,
        -0.0,
        PI,
        -PI,
        3.0 * PI,
        -3.0 * PI,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
        1e300,
        -1e300,
        5e-324,
        -5e-324,
    ]);
    for v in values {
        assert_eq!(mod_bearing(v).to_bits(), floored(v).to_bits(), "mod_bearing({v:e})");
        assert_eq!(spacing(v).to_bits(), numpy_spacing(v).to_bits(), "spacing({v:e})");
    }
}
