//! Batch evaluation over (N, ncols) row-major float64 state arrays: the position mapping,
//! the split of rows over threads, and the first-bad-row error.

use crate::error::{ModelError, Result};
use rayon::prelude::*;

/// Which columns of a state row hold the x and y position. Stone Soup's constant-velocity
/// state [x, vx, y, vy] maps to (0, 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PositionMapping {
    pub x: usize,
    pub y: usize,
}

impl Default for PositionMapping {
    fn default() -> Self {
        PositionMapping { x: 0, y: 2 }
    }
}

impl PositionMapping {
    pub fn new(x: usize, y: usize) -> Result<Self> {
        if x == y {
            return Err(ModelError::invalid("position_mapping", format!("x and y must be different columns, got ({x}, {y})")));
        }
        Ok(PositionMapping { x, y })
    }

    /// Checks the mapping against the number of columns of the state array.
    pub fn check(&self, ncols: usize, argument: &'static str) -> Result<()> {
        if self.x >= ncols || self.y >= ncols {
            return Err(ModelError::shape(
                argument,
                format!("position_mapping ({}, {}) is out of range for rows of {ncols} columns", self.x, self.y),
            ));
        }
        Ok(())
    }
}

/// Rows handled by one task: large enough to amortise scheduling, small enough that the
/// per-chunk scratch stays in L1/L2.
pub const CHUNK: usize = 1024;

/// Below this many rows the work stays on the calling thread.
pub const PARALLEL_THRESHOLD: usize = 32 * 1024;

/// Calls `kernel(first_row, out_chunk)` over `out` in chunks of [`CHUNK`] rows, in parallel
/// for large N. The kernel returns the index (within its chunk) of the first row it could
/// not evaluate; the smallest such global row is reported.
pub fn for_each_chunk<F>(out: &mut [f64], kernel: F) -> Option<usize>
where
    F: Fn(usize, &mut [f64]) -> Option<usize> + Sync,
{
    let run = |(c, chunk): (usize, &mut [f64])| kernel(c * CHUNK, chunk).map(|bad| c * CHUNK + bad);
    if out.len() >= PARALLEL_THRESHOLD {
        out.par_chunks_mut(CHUNK).enumerate().filter_map(run).min()
    } else {
        out.chunks_mut(CHUNK).enumerate().filter_map(run).min()
    }
}

/// Checks the state array's length against N rows of `ncols`.
pub fn check_rows(states: &[f64], ncols: usize, n_out: usize, argument: &'static str) -> Result<usize> {
    if ncols == 0 {
        return Err(ModelError::shape(argument, "rows must have at least one column"));
    }
    if states.len() % ncols != 0 {
        return Err(ModelError::shape(argument, format!("length {} is not a multiple of the row width {ncols}", states.len())));
    }
    let n = states.len() / ncols;
    if n != n_out {
        return Err(ModelError::shape("out", format!("must have {n} entries (one per row of {argument}), got {n_out}")));
    }
    Ok(n)
}
