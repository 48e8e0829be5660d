//! Small dense row-major matrix helpers for the per-component Gaussian maths (D ≈ 4–9,
//! m ≈ 2–3): plain loops on slices, no allocation in the hot calls.

/// `c (n×m) = a (n×k) · b (k×m)`.
pub fn matmul(a: &[f64], b: &[f64], n: usize, k: usize, m: usize, c: &mut [f64]) {
    for i in 0..n {
        for j in 0..m {
            let mut sum = 0.0;
            for l in 0..k {
                sum += a[i * k + l] * b[l * m + j];
            }
            c[i * m + j] = sum;
        }
    }
}

/// `c (n×m) = a (n×k) · bᵀ` for `b` stored `(m×k)`.
pub fn matmul_bt(a: &[f64], b: &[f64], n: usize, k: usize, m: usize, c: &mut [f64]) {
    for i in 0..n {
        for j in 0..m {
            let mut sum = 0.0;
            for l in 0..k {
                sum += a[i * k + l] * b[j * k + l];
            }
            c[i * m + j] = sum;
        }
    }
}

/// `c (n×n) = a (n×k) · bᵀ` for `b` stored `(n×k)`, when the product is symmetric in exact
/// arithmetic (`(F P) Fᵀ`, `(K S) Kᵀ`): the lower triangle is computed and mirrored, so
/// the result is symmetric to the last bit (round-off asymmetry in a covariance can grow
/// scan after scan).
pub fn symmetric_product(a: &[f64], b: &[f64], n: usize, k: usize, c: &mut [f64]) {
    for i in 0..n {
        for j in 0..=i {
            let mut sum = 0.0;
            for l in 0..k {
                sum += a[i * k + l] * b[j * k + l];
            }
            c[i * n + j] = sum;
            c[j * n + i] = sum;
        }
    }
}

/// `y (n) = a (n×k) · x (k)`.
pub fn matvec(a: &[f64], x: &[f64], n: usize, k: usize, y: &mut [f64]) {
    for i in 0..n {
        let mut sum = 0.0;
        for l in 0..k {
            sum += a[i * k + l] * x[l];
        }
        y[i] = sum;
    }
}

/// `xᵀ A x` for a (n×n) matrix.
pub fn quadratic_form(a: &[f64], x: &[f64], n: usize) -> f64 {
    let mut total = 0.0;
    for i in 0..n {
        let mut row = 0.0;
        for j in 0..n {
            row += a[i * n + j] * x[j];
        }
        total += x[i] * row;
    }
    total
}

/// Inverse and log-determinant of a symmetric positive-definite (n×n) matrix by Cholesky;
/// `None` if it is not positive definite (or not finite).
pub fn spd_inverse(a: &[f64], n: usize) -> Option<(Vec<f64>, f64)> {
    // (n² values: as large as `a`, which exists; the scan paths use spd_inverse_into)
    let mut inverse = vec![0.0; n * n];
    let mut scratch = vec![0.0; 2 * n * n];
    let log_det = spd_inverse_into(a, n, &mut inverse, &mut scratch)?;
    Some((inverse, log_det))
}

/// [`spd_inverse`] into `inverse` (n×n), with `scratch` of at least 2n² values: no
/// allocation, for loops over many small matrices.
pub fn spd_inverse_into(a: &[f64], n: usize, inverse: &mut [f64], scratch: &mut [f64]) -> Option<f64> {
    let (l, rest) = scratch.split_at_mut(n * n);
    if !cholesky_into(a, n, l) {
        return None;
    }
    let log_det = 2.0 * (0..n).map(|i| l[i * n + i].ln()).sum::<f64>();
    inverse_from_cholesky(l, n, inverse, &mut rest[..n * n]);
    Some(log_det)
}

/// The Cholesky factor `L` (lower, `A = L Lᵀ`) of the lower triangle of `a` into `l`;
/// false if `a` is not positive definite (or not finite).
#[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: NaN fails the test
pub fn cholesky_into(a: &[f64], n: usize, l: &mut [f64]) -> bool {
    for i in 0..n {
        for j in 0..=i {
            let mut sum = a[i * n + j];
            for k in 0..j {
                sum -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if !(sum > 0.0) || !sum.is_finite() {
                    return false;
                }
                l[i * n + i] = sum.sqrt();
            } else {
                l[i * n + j] = sum / l[j * n + j];
                l[j * n + i] = 0.0;
            }
        }
    }
    true
}

/// `A⁻¹ = L⁻ᵀ L⁻¹` from the Cholesky factor `l`, with `scratch` of n² values.
pub fn inverse_from_cholesky(l: &[f64], n: usize, inverse: &mut [f64], scratch: &mut [f64]) {
    let inv_l = &mut scratch[..n * n];
    for i in 0..n {
        inv_l[i * n + i] = 1.0 / l[i * n + i];
        for j in 0..i {
            let mut sum = 0.0;
            for k in j..i {
                sum -= l[i * n + k] * inv_l[k * n + j];
            }
            inv_l[i * n + j] = sum / l[i * n + i];
            inv_l[j * n + i] = 0.0;
        }
    }
    for i in 0..n {
        for j in 0..=i {
            let mut sum = 0.0;
            for k in i..n {
                sum += inv_l[k * n + i] * inv_l[k * n + j];
            }
            inverse[i * n + j] = sum;
            inverse[j * n + i] = sum;
        }
    }
}

/// Inverse of a general (n×n) matrix by Gauss–Jordan elimination with partial pivoting
/// into `inverse`, `scratch` of at least n² values; false (inverse NaN) when singular.
#[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: NaN fails the test
pub fn general_inverse_into(a: &[f64], n: usize, inverse: &mut [f64], scratch: &mut [f64]) -> bool {
    let work = &mut scratch[..n * n];
    work.copy_from_slice(&a[..n * n]);
    inverse
        .iter_mut()
        .take(n * n)
        .enumerate()
        .for_each(|(k, v)| *v = if k / n == k % n { 1.0 } else { 0.0 });
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&x, &y| work[x * n + col].abs().total_cmp(&work[y * n + col].abs()))
            .unwrap_or(col);
        let value = work[pivot * n + col];
        if !(value.abs() > 0.0) || !value.is_finite() {
            inverse.iter_mut().take(n * n).for_each(|v| *v = f64::NAN);
            return false;
        }
        for k in 0..n {
            work.swap(col * n + k, pivot * n + k);
            inverse.swap(col * n + k, pivot * n + k);
        }
        for k in 0..n {
            work[col * n + k] /= value;
            inverse[col * n + k] /= value;
        }
        for row in 0..n {
            if row == col {
                continue;
            }
            let factor = work[row * n + col];
            if factor == 0.0 {
                continue;
            }
            for k in 0..n {
                work[row * n + k] -= factor * work[col * n + k];
                inverse[row * n + k] -= factor * inverse[col * n + k];
            }
        }
    }
    true
}

/// Moore–Penrose pseudo-inverse (singular values below `1e-15 · σ_max` taken as zero, as
/// NumPy's `pinv` does), for covariances that are not positive definite.
pub fn pseudo_inverse(a: &[f64], n: usize) -> Vec<f64> {
    // (n² values, as large as `a`, which exists; nalgebra's SVD allocates several such
    // matrices infallibly itself)
    let matrix = nalgebra::DMatrix::from_row_slice(n, n, a);
    let svd = matrix.svd(true, true);
    let largest = svd.singular_values.iter().cloned().fold(0.0, f64::max);
    match svd.pseudo_inverse(1e-15 * largest) {
        Ok(inverse) => {
            let mut out = vec![0.0; n * n]; // (n², as `a`)
            for i in 0..n {
                for j in 0..n {
                    out[i * n + j] = inverse[(i, j)];
                }
            }
            out
        }
        Err(_) => vec![f64::NAN; n * n], // (as above: n² values, as many as `a` holds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spd_inverse_inverts_and_gives_log_det() {
        let a = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
        let (inv, log_det) = spd_inverse(&a, 3).unwrap();
        let mut product = [0.0; 9];
        matmul(&a, &inv, 3, 3, 3, &mut product);
        for i in 0..3 {
            for j in 0..3 {
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((product[i * 3 + j] - expected).abs() < 1e-14);
            }
        }
        let det = 4.0 * (3.0 * 2.0 - 0.04) - 1.0 * (2.0 - 0.1) + 0.5 * (0.2 - 1.5);
        assert!((log_det - f64::ln(det)).abs() < 1e-14);
    }

    #[test]
    fn spd_inverse_refuses_indefinite_and_nan() {
        assert!(spd_inverse(&[1.0, 2.0, 2.0, 1.0], 2).is_none());
        assert!(spd_inverse(&[f64::NAN, 0.0, 0.0, 1.0], 2).is_none());
    }

    #[test]
    fn general_inverse_of_an_indefinite_matrix() {
        let a = [1.0, 2.0, 2.0, 1.0];
        let mut inv = [0.0; 4];
        let mut scratch = [0.0; 4];
        assert!(general_inverse_into(&a, 2, &mut inv, &mut scratch));
        let mut product = [0.0; 4];
        matmul(&a, &inv, 2, 2, 2, &mut product);
        assert!((product[0] - 1.0).abs() < 1e-15 && product[1].abs() < 1e-15);
        assert!(!general_inverse_into(&[1.0, 2.0, 2.0, 4.0], 2, &mut inv, &mut scratch));
        assert!(inv[0].is_nan());
    }

    #[test]
    fn pseudo_inverse_of_singular_matrix() {
        let a = [1.0, 0.0, 0.0, 0.0];
        let p = pseudo_inverse(&a, 2);
        assert!((p[0] - 1.0).abs() < 1e-15 && p[1] == 0.0 && p[2] == 0.0 && p[3].abs() < 1e-15);
    }
}
