//! Integration rules for E[f(p)] with p ~ N(m, P) in 2-D position space.
//!
//! A rule is a list of points u_k in standard-normal space with weights w_k summing to one;
//! E[f(p)] ≈ Σ w_k f(m + L u_k) with P = L Lᵀ. Offered: the mean alone (Stone Soup's
//! convention), the third-degree spherical–radial cubature rule (4 points at ±√2 on the
//! axes), the unscented transform (5 points, κ = 1) and tensor Gauss–Hermite rules of any
//! order (n² points, exact for polynomials of degree 2n − 1 in each axis). P_D is piecewise
//! constant, so no rule is exact on it: higher orders converge to the expectation.
//! Each rule has its 3-D form for states with a height ([`Rule::spatial`]): the same
//! construction in three axes (6 cubature points at ±√3; the unscented transform with the
//! same κ = 1, a centre weight 1/4 and 6 points at ±2; n³ Gauss–Hermite points).

use crate::error::{ModelError, Result};
use crate::simd::Lanes;
use nalgebra::{DMatrix, SymmetricEigen};

#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    kind: Kind,
    points: Vec<[f64; 2]>,
    weights: Vec<f64>,
}

/// Which construction a rule is, so that its 3-D form can be built.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Mean,
    Cubature,
    Unscented,
    GaussHermite(usize),
}

/// A rule in three dimensions (x, y, z in standard-normal space), for states with a height.
#[derive(Debug, Clone, PartialEq)]
pub struct SpatialRule {
    points: Vec<[f64; 3]>,
    weights: Vec<f64>,
}

impl SpatialRule {
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    pub fn weights(&self) -> &[f64] {
        &self.weights
    }
}

impl Rule {
    pub fn mean() -> Rule {
        Rule {
            kind: Kind::Mean,
            points: vec![[0.0, 0.0]],
            weights: vec![1.0],
        }
    }

    pub fn cubature() -> Rule {
        let s = 2f64.sqrt();
        // (fixed sizes, as every rule's: at most 32² points, `order` being checked below)
        Rule {
            kind: Kind::Cubature,
            points: vec![[s, 0.0], [-s, 0.0], [0.0, s], [0.0, -s]],
            weights: vec![0.25; 4],
        }
    }

    /// Unscented transform with κ = 1 (n + κ = 3): centre weight 1/3, four points at ±√3.
    pub fn unscented() -> Rule {
        let s = 3f64.sqrt();
        let w = 1.0 / 6.0;
        Rule {
            kind: Kind::Unscented,
            points: vec![[0.0, 0.0], [s, 0.0], [-s, 0.0], [0.0, s], [0.0, -s]],
            weights: vec![1.0 / 3.0, w, w, w, w],
        }
    }

    /// Tensor Gauss–Hermite rule of `order` nodes per axis (probabilists' Hermite, so the
    /// nodes integrate against the standard normal).
    pub fn gauss_hermite(order: usize) -> Result<Rule> {
        let (nodes, weights) = hermite(order)?;
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
            kind: Kind::GaussHermite(order),
            points,
            weights: w2.into_iter().map(|w| w / total).collect(),
        })
    }

    /// The same rule in three dimensions.
    pub fn spatial(&self) -> SpatialRule {
        let axes = |s: f64| {
            let mut points = Vec::with_capacity(6);
            for axis in 0..3 {
                for sign in [1.0, -1.0] {
                    let mut p = [0.0; 3];
                    p[axis] = sign * s;
                    points.push(p);
                }
            }
            points
        };
        match self.kind {
            Kind::Mean => SpatialRule {
                points: vec![[0.0; 3]],
                weights: vec![1.0],
            },
            Kind::Cubature => SpatialRule {
                points: axes(3f64.sqrt()),
                weights: vec![1.0 / 6.0; 6],
            },
            // n + κ = 4: centre weight κ/(n + κ), the others 1/(2(n + κ)) at ±√(n + κ)
            Kind::Unscented => {
                let mut points = vec![[0.0; 3]];
                points.extend(axes(2.0));
                let mut weights = vec![0.25];
                weights.extend([0.125; 6]);
                SpatialRule { points, weights }
            }
            Kind::GaussHermite(order) => {
                // (the order was checked when the plane rule was built)
                let (nodes, weights) = hermite(order).unwrap_or_default();
                let n = nodes.len();
                let mut points = Vec::with_capacity(n * n * n); // (≤ 32³, as order ≤ 32)
                let mut w3 = Vec::with_capacity(n * n * n);
                for (i, &xi) in nodes.iter().enumerate() {
                    for (j, &xj) in nodes.iter().enumerate() {
                        for (k, &xk) in nodes.iter().enumerate() {
                            points.push([xi, xj, xk]);
                            w3.push(weights[i] * weights[j] * weights[k]);
                        }
                    }
                }
                let total: f64 = w3.iter().sum();
                SpatialRule {
                    points,
                    weights: w3.into_iter().map(|w| w / total).collect(),
                }
            }
        }
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

/// The nodes and weights of the `order`-point probabilists' Gauss–Hermite rule in one
/// dimension, from the Golub–Welsch eigenproblem of the Jacobi matrix.
fn hermite(order: usize) -> Result<(Vec<f64>, Vec<f64>)> {
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
    Ok((nodes, weights))
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

/// Lower Cholesky factor [l11, l21, l22, l31, l32, l33] of a symmetric positive
/// semi-definite 3×3 matrix `m` (row-major), column by column; a zero pivot needs a zero
/// column below it. None for a matrix that is not finite, not symmetric or not PSD beyond
/// rounding (the tolerances of [`cholesky2`]).
pub fn cholesky3(m: [f64; 9]) -> Option<[f64; 6]> {
    if m.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let scale = m[0].abs().max(m[4].abs()).max(m[8].abs()).max(f64::MIN_POSITIVE);
    if [(1, 3), (2, 6), (5, 7)]
        .iter()
        .any(|&(i, j)| (m[i] - m[j]).abs() > 1e-9 * scale)
    {
        return None;
    }
    let pivot = |v: f64| (v >= -1e-9 * scale).then(|| positive_part(v).sqrt());
    let below = |v: f64, l: f64| {
        if l > 0.0 {
            Some(v / l)
        } else {
            (v.abs() <= 1e-12 * scale).then_some(0.0)
        }
    };
    if m[0] < -1e-12 * scale || m[4] < -1e-12 * scale || m[8] < -1e-12 * scale {
        return None;
    }
    let l11 = pivot(m[0])?;
    let (l21, l31) = (below(m[3], l11)?, below(m[6], l11)?);
    let l22 = pivot(m[4] - l21 * l21)?;
    let l32 = below(m[7] - l31 * l21, l22)?;
    let l33 = pivot(m[8] - l31 * l31 - l32 * l32)?;
    Some([l11, l21, l22, l31, l32, l33])
}

/// The velocity of a Gaussian over position and velocity (D = 2 or 3 axes of each) given
/// its position at the rule's point m + L u: normal with mean μ_v + B u and covariance
/// V − B Bᵀ, where P = L Lᵀ is the position block, S the cross block (S[i][j] =
/// cov(v_i, p_j)), V the velocity block and B = S L⁻ᵀ (solved row by row; a zero pivot, a
/// position known exactly along that axis, gets a zero column). Returned as (B, V − B Bᵀ),
/// padded to 3 × 3 with zeros.
pub fn velocity_given_position<const D: usize>(
    l: [[f64; D]; D],
    cross: [[f64; D]; D],
    velocity: [[f64; D]; D],
) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    let mut b = [[0.0; 3]; 3];
    for i in 0..D {
        for j in 0..D {
            let mut v = cross[i][j];
            for k in 0..j {
                v -= b[i][k] * l[j][k];
            }
            b[i][j] = if l[j][j] > 0.0 { v / l[j][j] } else { 0.0 };
        }
    }
    let mut c = [[0.0; 3]; 3];
    for i in 0..D {
        for j in 0..D {
            let mut v = velocity[i][j];
            for (bik, bjk) in b[i].iter().zip(&b[j]).take(D) {
                v -= bik * bjk;
            }
            c[i][j] = v;
        }
    }
    (b, c)
}

/// Whether the symmetric `n`×`n` matrix `m` (row-major, n ≤ 6) is finite, symmetric and
/// positive semi-definite to rounding: a Cholesky factorisation that accepts a pivot down to
/// −1e-9 of its diagonal's scale as 0, and then only a column whose entries are 0 to the
/// same relative tolerance (a zero variance has no covariance with anything).
pub fn is_positive_semidefinite(m: &[f64], n: usize) -> bool {
    if n > 6 || m.len() != n * n || m.iter().any(|v| !v.is_finite()) {
        return false;
    }
    let scale = |i: usize, j: usize| (m[i * n + i].abs() * m[j * n + j].abs()).sqrt().max(f64::MIN_POSITIVE);
    for i in 0..n {
        for j in 0..i {
            if (m[i * n + j] - m[j * n + i]).abs() > 1e-9 * scale(i, j).max(m[i * n + j].abs()) {
                return false;
            }
        }
    }
    let mut l = [[0.0f64; 6]; 6];
    for j in 0..n {
        let pivot = m[j * n + j] - (0..j).map(|k| l[j][k] * l[j][k]).sum::<f64>();
        if pivot < -1e-9 * scale(j, j) {
            return false;
        }
        let zero = pivot <= 1e-12 * scale(j, j);
        l[j][j] = if zero { 0.0 } else { pivot.sqrt() };
        for i in j + 1..n {
            let rest = m[i * n + j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if zero {
                if rest.abs() > 1e-9 * scale(i, j) {
                    return false;
                }
                l[i][j] = 0.0;
            } else {
                l[i][j] = rest / l[j][j];
            }
        }
    }
    true
}

/// μ_v + B u: the mean velocity at a rule's point u ([`velocity_given_position`]).
#[inline(always)]
pub fn velocity_at_point(mean: [f64; 3], b: &[[f64; 3]; 3], u: [f64; 3]) -> [f64; 3] {
    let mut v = mean;
    for (vi, bi) in v.iter_mut().zip(b) {
        *vi += bi[0] * u[0] + bi[1] * u[1] + bi[2] * u[2];
    }
    v
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
    fn spatial_rules_match_standard_normal_moments() {
        for rule in [
            Rule::mean(),
            Rule::cubature(),
            Rule::unscented(),
            Rule::gauss_hermite(4).unwrap(),
        ] {
            let r = rule.spatial();
            let m = |f: &dyn Fn([f64; 3]) -> f64| -> f64 {
                r.points().iter().zip(r.weights()).map(|(p, w)| w * f(*p)).sum()
            };
            assert!((m(&|_| 1.0) - 1.0).abs() < 1e-12);
            for a in 0..3 {
                assert!(m(&|p| p[a]).abs() < 1e-12);
                if rule != Rule::mean() {
                    assert!((m(&|p| p[a] * p[a]) - 1.0).abs() < 1e-12, "{rule:?} axis {a}");
                }
                assert!(m(&|p| p[a] * p[(a + 1) % 3]).abs() < 1e-12);
            }
        }
        assert_eq!(Rule::gauss_hermite(4).unwrap().spatial().points().len(), 64);
    }

    #[test]
    fn cholesky3_rebuilds_the_matrix_and_refuses_bad_ones() {
        let m = [4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0];
        let [l11, l21, l22, l31, l32, l33] = cholesky3(m).unwrap();
        let l = [[l11, 0.0, 0.0], [l21, l22, 0.0], [l31, l32, l33]];
        for i in 0..3 {
            for j in 0..3 {
                let v: f64 = (0..3).map(|k| l[i][k] * l[j][k]).sum();
                assert!((v - m[3 * i + j]).abs() < 1e-14, "{i}{j}");
            }
        }
        // a plane Gaussian at a fixed height: zero variance in z
        assert_eq!(
            cholesky3([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0]),
            Some([1.0, 0.0, 1.0, 0.0, 0.0, 0.0])
        );
        assert!(
            cholesky3([1.0, 0.0, 2.0, 0.0, 1.0, 0.0, 2.0, 0.0, 1.0]).is_none(),
            "indefinite"
        );
        assert!(
            cholesky3([1.0, 0.0, 0.1, 0.0, 1.0, 0.0, 0.2, 0.0, 1.0]).is_none(),
            "not symmetric"
        );
        assert!(cholesky3([1.0, 0.0, 0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0, 1.0]).is_none());
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
