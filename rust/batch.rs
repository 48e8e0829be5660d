//! Batch evaluation over float64 state arrays, as (N, ncols) rows or as Stone Soup's (D, N)
//! particle columns: the position mapping, the gather of positions from either layout, the
//! split of states over threads, and the first-bad-row error.

use crate::error::{ModelError, Result};
use rayon::prelude::*;
use std::sync::OnceLock;

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

/// How N states of D values lie in a flat C-ordered array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// (N, D): state i is row i (a mixture's means).
    Rows { ncols: usize },
    /// (D, N): state i is column i (Stone Soup's `StateVectors` of particles), read in place
    /// with stride N instead of transposing.
    Columns { nstates: usize },
}

impl Layout {
    /// Positions of states `first..first + xs.len()` into `xs`, `ys`. One gather for both
    /// layouts, so P_D is computed by the same kernel whichever way the states lie.
    #[inline]
    pub fn gather(self, data: &[f64], first: usize, mapping: PositionMapping, xs: &mut [f64], ys: &mut [f64]) {
        let n = xs.len();
        match self {
            // Stone Soup's [x, vx, y, vy]: fixed offsets let the gather vectorise.
            Layout::Rows { ncols: 4 } if mapping == PositionMapping::default() => {
                for (i, row) in data[first * 4..(first + n) * 4].chunks_exact(4).enumerate() {
                    xs[i] = row[0];
                    ys[i] = row[2];
                }
            }
            Layout::Rows { ncols } => {
                for (i, row) in data[first * ncols..(first + n) * ncols].chunks_exact(ncols).enumerate() {
                    xs[i] = row[mapping.x];
                    ys[i] = row[mapping.y];
                }
            }
            // A particle's x and y are contiguous runs of their rows.
            Layout::Columns { nstates } => {
                xs.copy_from_slice(&data[mapping.x * nstates + first..][..n]);
                ys.copy_from_slice(&data[mapping.y * nstates + first..][..n]);
            }
        }
    }
}

/// Memory order of a (D, N) particle array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MemoryOrder {
    /// Row-major: row j holds dimension j of every particle (Stone Soup's `StateVectors`
    /// as built by stacking or by a transition model).
    C,
    /// Column-major: each particle's column is contiguous (what NumPy gives for
    /// `state_vector[:, indices]`, i.e. after resampling).
    F,
}

impl MemoryOrder {
    /// The layout of the N states of a (ndim, N) array in this order.
    pub fn layout(self, ndim: usize, n: usize) -> Layout {
        match self {
            MemoryOrder::C => Layout::Columns { nstates: n },
            MemoryOrder::F => Layout::Rows { ncols: ndim },
        }
    }
}

/// Rows handled by one task: large enough to amortise scheduling, small enough that the
/// per-chunk scratch stays in L1/L2.
pub const CHUNK: usize = 1024;

/// Below this many rows the work stays on the calling thread.
pub const PARALLEL_THRESHOLD: usize = 32 * 1024;

/// The process that first handed work to Rayon's global pool. A process forked from it
/// (a multiprocessing worker, say) inherits the pool's bookkeeping but none of its threads:
/// work handed to the pool there would wait forever, so a forked child stays serial.
static POOL_OWNER: OnceLock<u32> = OnceLock::new();

/// Whether this process may use Rayon's global pool (see [`POOL_OWNER`]).
pub fn pool_usable() -> bool {
    *POOL_OWNER.get_or_init(std::process::id) == std::process::id()
}

/// Calls `kernel(first_row, out_chunk)` over `out` in chunks of [`CHUNK`] rows, in parallel
/// for large N (serially in a process forked after the pool started). The kernel returns
/// the index (within its chunk) of the first row it could not evaluate; the smallest such
/// global row is reported. Chunks are the same either way, so are the results.
pub fn for_each_chunk<F>(out: &mut [f64], kernel: F) -> Option<usize>
where
    F: Fn(usize, &mut [f64]) -> Option<usize> + Sync,
{
    let run = |(c, chunk): (usize, &mut [f64])| kernel(c * CHUNK, chunk).map(|bad| c * CHUNK + bad);
    if out.len() >= PARALLEL_THRESHOLD && pool_usable() {
        out.par_chunks_mut(CHUNK).enumerate().filter_map(run).min()
    } else {
        out.chunks_mut(CHUNK).enumerate().filter_map(run).min()
    }
}

/// Checks a (D, N) particle array of `ndim` rows against N = `n_out` states and the mapping.
pub fn check_columns(states: &[f64], ndim: usize, n_out: usize, mapping: PositionMapping, argument: &'static str) -> Result<()> {
    if mapping.x >= ndim || mapping.y >= ndim {
        return Err(ModelError::shape(
            argument,
            format!("has {ndim} rows (state dimensions), but position_mapping ({}, {}) reads beyond them", mapping.x, mapping.y),
        ));
    }
    if states.len() != ndim * n_out {
        return Err(ModelError::shape(argument, format!("must hold {ndim} × {n_out} values (one column per output), got {}", states.len())));
    }
    Ok(())
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
