//! Integration rules for E[f(p)] with p ~ N(m, P) in 2-D position space.
//!
//! A rule is a list of points u_k in standard-normal space with weights w_k summing to one;
//! E[f(p)] ≈ Σ w_k f(m + L u_k) with P = L Lᵀ. Offered: the mean alone (Stone Soup's
//! convention), the third-degree spherical–radial cubature rule (4 points at ±√2 on the
//! axes), the unscented transform (5 points, κ = 1) and tensor Gauss–Hermite rules of any
//! order (n² points, exact for polynomials of degree 2n − 1 in each axis). P_D is piecewise
//! constant, so no rule is exact on it: higher orders converge to the expectation.

use crate::error::{ModelError, Result};
use crate::simd::Lanes;
use nalgebra::{DMatrix, SymmetricEigen};

#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    points: Vec<[f64; 2]>,
    weights: Vec<f64>,
}

impl Rule {
    pub fn mean() -> Rule {
        Rule {
            points: vec![[0.0, 0.0]],
            weights: vec![1.0],
        }
    }

    pub fn cubature() -> Rule {
        let s = 2f64.sqrt();
        // (fixed sizes, as every rule's: at most 32² points, `order` being checked below)
        Rule {
            points: vec![[s, 0.0], [-s, 0.0], [0.0, s], [0.0, -s]],
            weights: vec![0.25; 4],
        }
    }

    /// Unscented transform with κ = 1 (n + κ = 3): centre weight 1/3, four points at ±√3.
    pub fn unscented() -> Rule {
        let s = 3f64.sqrt();
        let w = 1.0 / 6.0;
        Rule {
            points: vec![[0.0, 0.0], [s, 0.0], [-s, 0.0], [0.0, s], [0.0, -s]],
            weights: vec![1.0 / 3.0, w, w, w, w],
        }
    }

    /// Tensor Gauss–Hermite rule of `order` nodes per axis (probabilists' Hermite, so the
    /// nodes integrate against the standard normal). Nodes and weights come from the
    /// Golub–Welsch eigenproblem of the Jacobi matrix.
    pub fn gauss_hermite(order: usize) -> Result<Rule> {
        if !(1..=32).contains(&order) {
            return Err(ModelError::invalid(
                "order",
                format!("Gauss–Hermite order must be in 1..=32, got {order}"),
            ));
        }
        let mut jacobi = DMatrix::<f64>::zeros(order, order);
        for k in 1..order {
            let off = (k as f64).sqrt();
            jacobi[(k - 1, k)] = off;
            jacobi[(k, k - 1)] = off;
        }
        let eig = SymmetricEigen::new(jacobi);
        // (order ≤ 32, checked above: these hold at most 1024 values)
        let nodes: Vec<f64> = eig.eigenvalues.iter().copied().collect();
        let weights: Vec<f64> = (0..order).map(|k| eig.eigenvectors[(0, k)].powi(2)).collect();
        let mut points = Vec::with_capacity(order * order);
        let mut w2 = Vec::with_capacity(order * order); // (≤ 1024, as points)
        for (i, &xi) in nodes.iter().enumerate() {
            for (j, &xj) in nodes.iter().enumerate() {
                points.push([xi, xj]);
                w2.push(weights[i] * weights[j]);
            }
        }
        let total: f64 = w2.iter().sum();
        Ok(Rule {
            points,
            weights: w2.into_iter().map(|w| w / total).collect(),
        }) // (≤ 1024)
    }

    pub fn points(&self) -> &[[f64; 2]] {
        &self.points
    }

    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// Lower Cholesky factor [[l11, 0], [l21, l22]] of a symmetric positive semi-definite 2×2
/// matrix [[a, b], [b, c]]. Zero variances are allowed (a point mass); a matrix that is not
/// PSD beyond rounding, or not symmetric, returns None.
#[inline]
pub fn cholesky2(a: f64, b: f64, b_t: f64, c: f64) -> Option<[f64; 3]> {
    let scale = a.abs().max(c.abs()).max(f64::MIN_POSITIVE);
    if !(a.is_finite() && b.is_finite() && b_t.is_finite() && c.is_finite()) {
        return None;
    }
    if (b - b_t).abs() > 1e-9 * scale || a < -1e-12 * scale || c < -1e-12 * scale {
        return None;
    }
    let l11 = positive_part(a).sqrt();
    let l21 = if l11 > 0.0 {
        b / l11
    } else if b.abs() <= 1e-12 * scale {
        0.0
    } else {
        return None;
    };
    let rest = c - l21 * l21;
    if rest < -1e-9 * scale {
        return None;
    }
    Some([l11, l21, positive_part(rest).sqrt()])
}

/// max(v, 0) with +0 for every v ≤ 0 (also −0), as the lanes compute it.
#[inline(always)]
fn positive_part(v: f64) -> f64 {
    if v > 0.0 {
        v
    } else {
        0.0
    }
}

/// [`cholesky2`] of four matrices at once, the same bits: the factors, and a mask of the
/// lanes for which `cholesky2` gives None (their factors are meaningless).
#[inline(always)]
pub(crate) fn cholesky2_lanes<L: Lanes>(a: L, b: L, b_t: L, c: L) -> (L::Mask, [L; 3]) {
    let zero = L::splat(0.0);
    let scale = a.abs().max(c.abs()).max(L::splat(f64::MIN_POSITIVE));
    let non_finite = L::or(
        L::or(a.non_finite(), b.non_finite()),
        L::or(b_t.non_finite(), c.non_finite()),
    );
    let asymmetric = (b - b_t).abs().gt(L::splat(1e-9) * scale);
    let tolerance = L::splat(-1e-12) * scale;
    let negative = L::or(a.lt(tolerance), c.lt(tolerance));
    let l11 = a.max(zero).sqrt();
    let pivot = l11.gt(zero);
    let l21 = L::select(pivot, b.div(l11), zero);
    // No pivot: only a zero covariance is allowed.
    let unpivoted = L::and(l11.le(zero), b.abs().gt(L::splat(1e-12) * scale));
    let rest = c - l21 * l21;
    let indefinite = rest.lt(L::splat(-1e-9) * scale);
    let bad = L::or(
        L::or(non_finite, asymmetric),
        L::or(L::or(negative, unpivoted), indefinite),
    );
    (bad, [l11, l21, rest.max(zero).sqrt()])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moment(rule: &Rule, f: impl Fn(f64, f64) -> f64) -> f64 {
        rule.points()
            .iter()
            .zip(rule.weights())
            .map(|(p, w)| w * f(p[0], p[1]))
            .sum()
    }

    #[test]
    fn rules_match_standard_normal_moments() {
        for rule in [
            Rule::cubature(),
            Rule::unscented(),
            Rule::gauss_hermite(3).unwrap(),
            Rule::gauss_hermite(8).unwrap(),
        ] {
            assert!((moment(&rule, |_, _| 1.0) - 1.0).abs() < 1e-12);
            assert!(moment(&rule, |x, _| x).abs() < 1e-12);
            assert!((moment(&rule, |x, _| x * x) - 1.0).abs() < 1e-12);
            assert!((moment(&rule, |_, y| y * y) - 1.0).abs() < 1e-12);
            assert!(moment(&rule, |x, y| x * y).abs() < 1e-12);
        }
        // Fourth moment of N(0,1) is 3: Gauss–Hermite of order ≥ 3 gets it exactly.
        assert!((moment(&Rule::gauss_hermite(3).unwrap(), |x, _| x.powi(4)) - 3.0).abs() < 1e-10);
    }

    #[test]
    fn cholesky_of_psd_and_degenerate() {
        let [l11, l21, l22] = cholesky2(4.0, 2.0, 2.0, 5.0).unwrap();
        assert!((l11 - 2.0).abs() < 1e-15 && (l21 - 1.0).abs() < 1e-15 && (l22 - 2.0).abs() < 1e-15);
        assert_eq!(cholesky2(0.0, 0.0, 0.0, 0.0), Some([0.0, 0.0, 0.0]));
        assert!(cholesky2(1.0, 2.0, 2.0, 1.0).is_none(), "indefinite");
        assert!(cholesky2(1.0, 0.1, 0.2, 1.0).is_none(), "not symmetric");
        assert!(cholesky2(-1.0, 0.0, 0.0, 1.0).is_none());
    }
}
