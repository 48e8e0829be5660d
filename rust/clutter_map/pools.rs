//! The passes over a map's cells behind an estimated pool weight (see the parent module's
//! docs): every column's moments, and which cells leave their pools. Both run four cells
//! of a row at a time ([`crate::simd`]: exactly rounded operations only, so every backend,
//! and the scalar tail of a row, gives the same bits), accumulating each column over the
//! rows in order.

use crate::simd::{dispatch, LaneKernel, Lanes};

/// A row-major grid's state as the passes read it, in unscaled units.
#[derive(Clone, Copy)]
pub(super) struct Cells<'a> {
    pub counts: &'a [f64],
    pub deficit: &'a [f64],
    pub volumes: &'a [f64],
    pub columns: usize,
    /// S × scale.
    pub exposure: f64,
    /// 1 / scale.
    pub inverse: f64,
}

impl Cells<'_> {
    /// A cell's discounted count n and exposed volume e = V_c S_c.
    #[inline(always)]
    pub fn at(&self, c: usize) -> (f64, f64) {
        (
            self.counts[c] * self.inverse,
            (self.exposure - self.deficit[c]) * self.inverse * self.volumes[c],
        )
    }

    /// Per column, the sums Σ n, Σ e, Σ n², Σ n e, Σ e² over its cells in row order, into
    /// `out` (one entry per column), with `running` (five buffers of a column each) as room.
    pub fn moments(self, running: &mut [Vec<f64>; 5], out: &mut [[f64; 5]]) {
        dispatch(Moments {
            cells: self,
            running,
            out,
        })
    }

    /// The same sums for column `j` over the cells `keep` holds, in row order.
    pub fn column_moments(&self, j: usize, keep: impl Fn(usize) -> bool) -> [f64; 5] {
        let mut sums = [0.0; 5];
        for c in (j..self.counts.len()).step_by(self.columns).filter(|c| keep(*c)) {
            let (n, e) = self.at(c);
            for (sum, term) in sums.iter_mut().zip([n, e, n * n, n * e, e * e]) {
                *sum += term;
            }
        }
        sums
    }

    /// Per row, whether a cell of it may leave its pool ([`may_leave`]), into `out` (one
    /// entry per row).
    pub fn rows_to_test(self, tests: Tests, out: &mut [bool]) {
        dispatch(RowsToTest {
            cells: self,
            tests,
            out,
        })
    }
}

/// A cell's test against its pool's level, in effective counts.
#[derive(Clone, Copy)]
pub(super) struct Tests<'a> {
    /// The level of every cell of the pool, per column.
    pub levels: &'a [f64],
    /// S / S2: counts to effective counts.
    pub effective: f64,
    /// ln(cells of the pool / APART).
    pub threshold: f64,
}

impl Tests<'_> {
    /// Whether a bound on the divergence of the cell (n, e) in column `j` exceeds the
    /// threshold: (n − μ)² / (2μ) for n ≥ μ, μ − n below (n ln(n/μ) ≤ 0 there).
    #[inline(always)]
    pub fn may_leave(&self, (count, exposed): (f64, f64), j: usize) -> bool {
        let (n, mu) = (count * self.effective, self.levels[j] * exposed * self.effective);
        let above = (n >= mu) & ((n - mu) * (n - mu) > 2.0 * self.threshold * mu);
        let below = (n < mu) & (mu - n > self.threshold);
        (mu > 0.0) & (above | below)
    }

    /// Whether the cell (n, e) in column `j` leaves its pool: its Poisson divergence
    /// n ln(n/μ) − n + μ from the level exceeds the threshold.
    pub fn leaves(&self, (count, exposed): (f64, f64), j: usize) -> bool {
        let (n, mu) = (count * self.effective, self.levels[j] * exposed * self.effective);
        let divergence = if n > 0.0 { n * (n / mu).ln() - n + mu } else { mu };
        mu > 0.0 && divergence > self.threshold
    }
}

struct Moments<'a> {
    cells: Cells<'a>,
    running: &'a mut [Vec<f64>; 5],
    out: &'a mut [[f64; 5]],
}

impl LaneKernel for Moments<'_> {
    type Output = ();

    #[inline(always)]
    fn run<L: Lanes>(self) {
        let Cells {
            counts,
            deficit,
            volumes,
            columns,
            exposure,
            inverse,
        } = self.cells;
        let full = columns / 4 * 4;
        let sums = self.running;
        for s in sums.iter_mut() {
            s.fill(0.0);
        }
        let (s, i) = (L::splat(exposure), L::splat(inverse));
        for ((n, d), v) in counts
            .chunks_exact(columns)
            .zip(deficit.chunks_exact(columns))
            .zip(volumes.chunks_exact(columns))
        {
            for j in (0..full).step_by(4) {
                let (n, e) = (L::load(&n[j..]) * i, (s - L::load(&d[j..])) * i * L::load(&v[j..]));
                // (written out: a closure or iterator here could be compiled outside the
                // AVX2 function)
                let [s0, s1, s2, s3, s4] = &mut *sums;
                (L::load(&s0[j..]) + n).store(&mut s0[j..]);
                (L::load(&s1[j..]) + e).store(&mut s1[j..]);
                (L::load(&s2[j..]) + n * n).store(&mut s2[j..]);
                (L::load(&s3[j..]) + n * e).store(&mut s3[j..]);
                (L::load(&s4[j..]) + e * e).store(&mut s4[j..]);
            }
            for j in full..columns {
                let (n, e) = (n[j] * inverse, (exposure - d[j]) * inverse * v[j]);
                for (sum, term) in sums.iter_mut().zip([n, e, n * n, n * e, e * e]) {
                    sum[j] += term;
                }
            }
        }
        for (j, out) in self.out.iter_mut().enumerate() {
            *out = sums.each_ref().map(|s| s[j]);
        }
    }
}

struct RowsToTest<'a> {
    cells: Cells<'a>,
    tests: Tests<'a>,
    out: &'a mut [bool],
}

impl LaneKernel for RowsToTest<'_> {
    type Output = ();

    #[inline(always)]
    fn run<L: Lanes>(self) {
        let Cells {
            counts,
            deficit,
            volumes,
            columns,
            exposure,
            inverse,
        } = self.cells;
        let Tests {
            levels,
            effective,
            threshold,
        } = self.tests;
        let full = columns / 4 * 4;
        let (s, i, k, t, zero) = (
            L::splat(exposure),
            L::splat(inverse),
            L::splat(effective),
            L::splat(threshold),
            L::splat(0.0),
        );
        let twice = L::splat(2.0 * threshold);
        let rows = counts
            .chunks_exact(columns)
            .zip(deficit.chunks_exact(columns))
            .zip(volumes.chunks_exact(columns));
        for ((row, ((n, d), v)), test) in rows.enumerate().zip(self.out.iter_mut()) {
            let mut flagged = L::none();
            for j in (0..full).step_by(4) {
                let e = (s - L::load(&d[j..])) * i * L::load(&v[j..]);
                let (n, mu) = (L::load(&n[j..]) * i * k, L::load(&levels[j..]) * e * k);
                let gap = n - mu;
                let above = L::and(n.ge(mu), (gap * gap).gt(twice * mu));
                let below = L::and(n.lt(mu), (mu - n).gt(t));
                flagged = L::or(flagged, L::and(mu.gt(zero), L::or(above, below)));
            }
            let first = row * columns;
            *test = L::any(flagged) || (full..columns).any(|j| self.tests.may_leave(self.cells.at(first + j), j));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::{run_on, Backend};

    /// 9 rows × 7 columns (a tail of 3 after the lanes), some gated; in the first 4 rows
    /// each count is its cell's mean under `levels` (nothing to test), then counts from 0
    /// to ~12.
    fn grid(levels: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let cells = 9 * 7;
        let deficit: Vec<f64> = (0..cells).map(|c| if c % 5 == 0 { 1.5 } else { 0.0 }).collect();
        let volumes: Vec<f64> = (0..cells).map(|c| 1.0 + (c % 7) as f64 * 0.25).collect();
        let counts = (0..cells)
            .map(|c| {
                if c < 4 * 7 {
                    levels[c % 7] * (6.0 - deficit[c]) * volumes[c]
                } else {
                    ((c * 37 % 11) as f64).powi(2) / 10.0 * 3.0
                }
            })
            .collect();
        (counts, deficit, volumes)
    }

    #[test]
    fn the_lanes_give_the_scalar_sums_and_tests_on_every_backend() {
        let levels: Vec<f64> = (0..7).map(|j| 0.4 + 0.1 * j as f64).collect();
        let (counts, deficit, volumes) = grid(&levels);
        let cells = Cells {
            counts: &counts,
            deficit: &deficit,
            volumes: &volumes,
            columns: 7,
            exposure: 6.0,
            inverse: 0.5,
        };
        let tests = Tests {
            levels: &levels,
            effective: 1.7,
            threshold: 4.0,
        };
        let scalar_sums: Vec<[f64; 5]> = (0..7).map(|j| cells.column_moments(j, |_| true)).collect();
        let scalar_rows: Vec<bool> = (0..9)
            .map(|r| (0..7).any(|j| tests.may_leave(cells.at(r * 7 + j), j)))
            .collect();
        assert!(
            scalar_rows.iter().any(|r| *r) && !scalar_rows.iter().all(|r| *r),
            "{scalar_rows:?}"
        );
        for backend in [Backend::Portable, Backend::Avx2].into_iter().filter(|b| b.available()) {
            // (the buffers start dirty: a pass must not depend on what they held)
            let (mut running, mut sums, mut rows) =
                (std::array::from_fn(|_| vec![9.0; 7]), vec![[9.0; 5]; 7], vec![true; 9]);
            run_on(
                backend,
                Moments {
                    cells,
                    running: &mut running,
                    out: &mut sums,
                },
            );
            run_on(
                backend,
                RowsToTest {
                    cells,
                    tests,
                    out: &mut rows,
                },
            );
            assert_eq!(sums, scalar_sums, "{backend:?}");
            assert_eq!(rows, scalar_rows, "{backend:?}");
        }
    }

    #[test]
    fn the_bound_never_keeps_a_cell_that_leaves() {
        let levels = [1.0];
        for threshold in [0.5, 3.0, 9.2] {
            let tests = Tests {
                levels: &levels,
                effective: 1.0,
                threshold,
            };
            for k in 0..4000 {
                let n = k as f64 * 0.01; // counts 0 to 40 against a mean of 1 (exposure 1)
                if tests.leaves((n, 1.0), 0) {
                    assert!(tests.may_leave((n, 1.0), 0), "n {n}, threshold {threshold}");
                }
            }
        }
    }
}
