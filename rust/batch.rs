//! Batch evaluation over float64 state arrays, as (N, ncols) rows or as Stone Soup's (D, N)
//! particle columns: the position mapping, the gather of positions from either layout, the
//! split of states over threads, and the first-bad-row error.

use crate::error::{ModelError, Result};
use crate::simd::Lanes;
use rayon::prelude::*;
use std::sync::OnceLock;

/// Which columns of a state row hold the x and y position, the height z when the model is
/// evaluated in 3-D, and the velocity when a factor reads it (a range-rate notch). Stone
/// Soup's constant-velocity state [x, vx, y, vy] maps to (0, 2) with velocity (1, 3);
/// [x, vx, y, vy, z, vz] to (0, 2, 4) with velocity (1, 3, 5). Without a height, targets
/// are taken to be at the sensor's height (ranges are plane distances).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PositionMapping {
    pub x: usize,
    pub y: usize,
    pub z: Option<usize>,
    pub velocity: Option<VelocityMapping>,
}

/// The columns of the velocity: vx, vy, and vz exactly when the positions have a height.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VelocityMapping {
    pub vx: usize,
    pub vy: usize,
    pub vz: Option<usize>,
}

impl Default for PositionMapping {
    fn default() -> Self {
        PositionMapping {
            x: 0,
            y: 2,
            z: None,
            velocity: None,
        }
    }
}

impl PositionMapping {
    pub fn new(x: usize, y: usize) -> Result<Self> {
        if x == y {
            return Err(ModelError::invalid(
                "position_mapping",
                format!("x and y must be different columns, got ({x}, {y})"),
            ));
        }
        Ok(PositionMapping {
            x,
            y,
            z: None,
            velocity: None,
        })
    }

    /// The mapping (x, y, z): states with a height, evaluated in 3-D.
    pub fn raised(x: usize, y: usize, z: usize) -> Result<Self> {
        if z == x || z == y || x == y {
            return Err(ModelError::invalid(
                "position_mapping",
                format!("x, y and z must be different columns, got ({x}, {y}, {z})"),
            ));
        }
        Ok(PositionMapping {
            x,
            y,
            z: Some(z),
            velocity: None,
        })
    }

    /// This mapping with the velocity in columns `velocity` (vx, vy, and vz exactly when the
    /// positions have a height), all apart from the position's.
    pub fn with_velocity(self, velocity: VelocityMapping) -> Result<Self> {
        if velocity.vz.is_some() != self.z.is_some() {
            return Err(ModelError::invalid(
                "velocity_mapping",
                format!("{velocity} must have as many indices as position_mapping {self}"),
            ));
        }
        let columns = [
            Some(self.x),
            Some(self.y),
            self.z,
            Some(velocity.vx),
            Some(velocity.vy),
            velocity.vz,
        ];
        let used: Vec<usize> = columns.into_iter().flatten().collect(); // (≤ 6)
        if (1..used.len()).any(|i| used[..i].contains(&used[i])) {
            return Err(ModelError::invalid(
                "velocity_mapping",
                format!("{velocity} shares a column with position_mapping {self} or repeats one"),
            ));
        }
        Ok(PositionMapping {
            velocity: Some(velocity),
            ..self
        })
    }

    /// The largest position column the mapping reads.
    pub fn widest(&self) -> usize {
        self.x.max(self.y).max(self.z.unwrap_or(0))
    }

    /// Checks the mapping against the number of columns of the state array.
    pub fn check(&self, ncols: usize, argument: &'static str) -> Result<()> {
        if self.widest() >= ncols {
            return Err(ModelError::shape(
                argument,
                format!("position_mapping {self} is out of range for rows of {ncols} columns"),
            ));
        }
        if let Some(v) = self.velocity {
            if v.widest() >= ncols {
                return Err(ModelError::shape(
                    argument,
                    format!("velocity_mapping {v} is out of range for rows of {ncols} columns"),
                ));
            }
        }
        Ok(())
    }
}

impl VelocityMapping {
    fn widest(&self) -> usize {
        self.vx.max(self.vy).max(self.vz.unwrap_or(0))
    }
}

impl std::fmt::Display for VelocityMapping {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.vz {
            None => write!(f, "({}, {})", self.vx, self.vy),
            Some(vz) => write!(f, "({}, {}, {vz})", self.vx, self.vy),
        }
    }
}

impl std::fmt::Display for PositionMapping {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.z {
            None => write!(f, "({}, {})", self.x, self.y),
            Some(z) => write!(f, "({}, {}, {z})", self.x, self.y),
        }
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
    /// The position of state `i`.
    #[inline(always)]
    pub fn position(self, data: &[f64], i: usize, mapping: PositionMapping) -> [f64; 2] {
        match self {
            Layout::Rows { ncols } => [data[i * ncols + mapping.x], data[i * ncols + mapping.y]],
            Layout::Columns { nstates } => [data[mapping.x * nstates + i], data[mapping.y * nstates + i]],
        }
    }
}

/// Reads the positions of states in lanes of four, straight from the caller's array (no
/// copy). One implementation per layout, so a kernel's block loop has no layout branch.
pub trait Positions: Copy {
    /// x and y of states `first..first + 4`.
    fn lanes<L: Lanes>(self, first: usize) -> (L, L);
    /// x and y of state `i`.
    fn one(self, i: usize) -> [f64; 2];

    /// As [`Self::lanes`] for the `count` < 4 states from `first` (a chunk's last block),
    /// padded with zeros: finite, so never reported as a bad state.
    #[inline(always)]
    fn partial<L: Lanes>(self, first: usize, count: usize) -> (L, L) {
        let (mut xs, mut ys) = ([0.0; 4], [0.0; 4]);
        for i in 0..count {
            [xs[i], ys[i]] = self.one(first + i);
        }
        (L::from_array(xs), L::from_array(ys))
    }
}

/// Stone Soup's constant-velocity rows [x, vx, y, vy]: four rows are four vector loads.
#[derive(Clone, Copy)]
pub struct CvRows<'a>(pub &'a [f64]);

impl Positions for CvRows<'_> {
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> (L, L) {
        L::rows4_columns02(&self.0[first * 4..])
    }
    #[inline(always)]
    fn one(self, i: usize) -> [f64; 2] {
        [self.0[i * 4], self.0[i * 4 + 2]]
    }
}

impl Velocities for CvRows<'_> {
    const MOVING: bool = true;
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> [L; 3] {
        let (vx, vy) = L::rows4_columns13(&self.0[first * 4..]);
        [vx, vy, L::splat(0.0)]
    }
    #[inline(always)]
    fn one(self, i: usize) -> [f64; 3] {
        [self.0[i * 4 + 1], self.0[i * 4 + 3], 0.0]
    }
}

/// Stone Soup's 3-D constant-velocity rows [x, vx, y, vy, z, vz]: the positions and the
/// heights of four rows from six vector loads.
#[derive(Clone, Copy)]
pub struct Cv3Rows<'a>(pub &'a [f64]);

impl Positions for Cv3Rows<'_> {
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> (L, L) {
        let (x, y, _) = L::rows4_columns024(&self.0[first * 6..]);
        (x, y)
    }
    #[inline(always)]
    fn one(self, i: usize) -> [f64; 2] {
        [self.0[i * 6], self.0[i * 6 + 2]]
    }
}

impl Heights for Cv3Rows<'_> {
    const RAISED: bool = true;
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> L {
        L::rows4_columns024(&self.0[first * 6..]).2
    }
    #[inline(always)]
    fn one(self, i: usize) -> f64 {
        self.0[i * 6 + 4]
    }
}

/// Any other (N, ncols) rows.
#[derive(Clone, Copy)]
pub struct Rows<'a> {
    pub data: &'a [f64],
    pub ncols: usize,
    pub mapping: PositionMapping,
}

impl Positions for Rows<'_> {
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> (L, L) {
        let [x0, y0] = self.one(first);
        let [x1, y1] = self.one(first + 1);
        let [x2, y2] = self.one(first + 2);
        let [x3, y3] = self.one(first + 3);
        (L::from_array([x0, x1, x2, x3]), L::from_array([y0, y1, y2, y3]))
    }
    #[inline(always)]
    fn one(self, i: usize) -> [f64; 2] {
        Layout::Rows { ncols: self.ncols }.position(self.data, i, self.mapping)
    }
}

/// A (D, N) C-ordered particle array: x and y are contiguous runs of their rows.
#[derive(Clone, Copy)]
pub struct Columns<'a> {
    pub xs: &'a [f64],
    pub ys: &'a [f64],
}

impl Positions for Columns<'_> {
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> (L, L) {
        (L::load(&self.xs[first..]), L::load(&self.ys[first..]))
    }
    #[inline(always)]
    fn one(self, i: usize) -> [f64; 2] {
        [self.xs[i], self.ys[i]]
    }
}

/// Where the states' heights are read: nowhere (a planar evaluation, every target at the
/// sensor's height) or a column of their rows or particles. The kernels are generic over
/// it, so the planar ones carry no height code.
pub trait Heights: Copy {
    /// Whether the states have heights (false: the planar evaluation).
    const RAISED: bool;
    /// The heights of states `first..first + 4`.
    fn lanes<L: Lanes>(self, first: usize) -> L;
    /// The height of state `i`.
    fn one(self, i: usize) -> f64;
    /// As [`Self::lanes`] for the `count` < 4 states from `first`, zero-padded.
    #[inline(always)]
    fn partial<L: Lanes>(self, first: usize, count: usize) -> L {
        let mut zs = [0.0; 4];
        for (i, z) in zs.iter_mut().enumerate().take(count) {
            *z = self.one(first + i);
        }
        L::from_array(zs)
    }
}

/// No heights: the planar evaluation.
#[derive(Clone, Copy)]
pub struct Planar;

impl Heights for Planar {
    const RAISED: bool = false;
    #[inline(always)]
    fn lanes<L: Lanes>(self, _: usize) -> L {
        L::splat(0.0)
    }
    #[inline(always)]
    fn one(self, _: usize) -> f64 {
        0.0
    }
}

/// Heights in column `z` of (N, ncols) rows.
#[derive(Clone, Copy)]
pub struct RowHeights<'a> {
    pub data: &'a [f64],
    pub ncols: usize,
    pub z: usize,
}

impl Heights for RowHeights<'_> {
    const RAISED: bool = true;
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> L {
        L::from_array([
            self.one(first),
            self.one(first + 1),
            self.one(first + 2),
            self.one(first + 3),
        ])
    }
    #[inline(always)]
    fn one(self, i: usize) -> f64 {
        self.data[i * self.ncols + self.z]
    }
}

/// Heights as a contiguous run (the z row of a (D, N) C-ordered particle array).
#[derive(Clone, Copy)]
pub struct ColumnHeights<'a>(pub &'a [f64]);

impl Heights for ColumnHeights<'_> {
    const RAISED: bool = true;
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> L {
        L::load(&self.0[first..])
    }
    #[inline(always)]
    fn one(self, i: usize) -> f64 {
        self.0[i]
    }
}

/// Where the states' velocities are read: nowhere (no factor reads them), or columns of
/// their rows or rows of a particle array. Velocities without a height have vz = 0.
pub trait Velocities: Copy {
    /// Whether the states have velocities.
    const MOVING: bool;
    /// vx, vy, vz of states `first..first + 4`.
    fn lanes<L: Lanes>(self, first: usize) -> [L; 3];
    /// vx, vy, vz of state `i`.
    fn one(self, i: usize) -> [f64; 3];
    /// As [`Self::lanes`] for the `count` < 4 states from `first`, zero-padded.
    #[inline(always)]
    fn partial<L: Lanes>(self, first: usize, count: usize) -> [L; 3] {
        let mut v = [[0.0; 4]; 3];
        for i in 0..count {
            let one = self.one(first + i);
            for (axis, value) in v.iter_mut().zip(one) {
                axis[i] = value;
            }
        }
        [L::from_array(v[0]), L::from_array(v[1]), L::from_array(v[2])]
    }
}

/// No velocities: no factor reads them.
#[derive(Clone, Copy)]
pub struct Still;

impl Velocities for Still {
    const MOVING: bool = false;
    #[inline(always)]
    fn lanes<L: Lanes>(self, _: usize) -> [L; 3] {
        [L::splat(0.0); 3]
    }
    #[inline(always)]
    fn one(self, _: usize) -> [f64; 3] {
        [0.0; 3]
    }
}

/// Velocities in columns of (N, ncols) rows.
#[derive(Clone, Copy)]
pub struct RowVelocities<'a> {
    pub data: &'a [f64],
    pub ncols: usize,
    pub mapping: VelocityMapping,
}

impl Velocities for RowVelocities<'_> {
    const MOVING: bool = true;
    // (no closures here: they would be compiled apart from the kernel, without its AVX2)
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> [L; 3] {
        let (a, b, c, d) = (
            self.one(first),
            self.one(first + 1),
            self.one(first + 2),
            self.one(first + 3),
        );
        [
            L::from_array([a[0], b[0], c[0], d[0]]),
            L::from_array([a[1], b[1], c[1], d[1]]),
            L::from_array([a[2], b[2], c[2], d[2]]),
        ]
    }
    #[inline(always)]
    fn one(self, i: usize) -> [f64; 3] {
        let row = &self.data[i * self.ncols..][..self.ncols];
        let VelocityMapping { vx, vy, vz } = self.mapping;
        let z = match vz {
            Some(vz) => row[vz],
            None => 0.0,
        };
        [row[vx], row[vy], z]
    }
}

/// Velocities as contiguous runs (rows of a (D, N) C-ordered particle array).
#[derive(Clone, Copy)]
pub struct ColumnVelocities<'a> {
    pub vx: &'a [f64],
    pub vy: &'a [f64],
    pub vz: Option<&'a [f64]>,
}

impl Velocities for ColumnVelocities<'_> {
    const MOVING: bool = true;
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize) -> [L; 3] {
        let vz = match self.vz {
            Some(vz) => L::load(&vz[first..]),
            None => L::splat(0.0),
        };
        [L::load(&self.vx[first..]), L::load(&self.vy[first..]), vz]
    }
    #[inline(always)]
    fn one(self, i: usize) -> [f64; 3] {
        let z = match self.vz {
            Some(vz) => vz[i],
            None => 0.0,
        };
        [self.vx[i], self.vy[i], z]
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
/// for large N (serially in a process forked after the pool started, and with a pool of one
/// thread, where handing the work over would only add the hand-off). The kernel returns
/// the index (within its chunk) of the first row it could not evaluate; the smallest such
/// global row is reported. Chunks are the same either way, so are the results.
pub fn for_each_chunk<F>(out: &mut [f64], kernel: F) -> Option<usize>
where
    F: Fn(usize, &mut [f64]) -> Option<usize> + Sync,
{
    for_each_chunk_from(out, PARALLEL_THRESHOLD, kernel)
}

/// [`for_each_chunk`], in parallel from `threshold` rows (kernels costlier per row than
/// the range and sector factors pay for the threads sooner).
pub fn for_each_chunk_from<F>(out: &mut [f64], threshold: usize, kernel: F) -> Option<usize>
where
    F: Fn(usize, &mut [f64]) -> Option<usize> + Sync,
{
    let run = |(c, chunk): (usize, &mut [f64])| kernel(c * CHUNK, chunk).map(|bad| c * CHUNK + bad);
    if out.len() >= threshold && pool_usable() && rayon::current_num_threads() > 1 {
        out.par_chunks_mut(CHUNK).enumerate().filter_map(run).min()
    } else {
        out.chunks_mut(CHUNK).enumerate().filter_map(run).min()
    }
}

/// Checks a (D, N) particle array of `ndim` rows against N = `n_out` states and the mapping.
pub fn check_columns(
    states: &[f64],
    ndim: usize,
    n_out: usize,
    mapping: PositionMapping,
    argument: &'static str,
) -> Result<()> {
    if mapping.widest() >= ndim {
        return Err(ModelError::shape(
            argument,
            format!("has {ndim} rows (state dimensions), but position_mapping {mapping} reads beyond them"),
        ));
    }
    if let Some(v) = mapping.velocity.filter(|v| v.widest() >= ndim) {
        return Err(ModelError::shape(
            argument,
            format!("has {ndim} rows (state dimensions), but velocity_mapping {v} reads beyond them"),
        ));
    }
    if states.len() != ndim * n_out {
        return Err(ModelError::shape(
            argument,
            format!(
                "must hold {ndim} × {n_out} values (one column per output), got {}",
                states.len()
            ),
        ));
    }
    Ok(())
}

/// Checks the state array's length against N rows of `ncols`.
pub fn check_rows(states: &[f64], ncols: usize, n_out: usize, argument: &'static str) -> Result<usize> {
    if ncols == 0 {
        return Err(ModelError::shape(argument, "rows must have at least one column"));
    }
    if !states.len().is_multiple_of(ncols) {
        return Err(ModelError::shape(
            argument,
            format!("length {} is not a multiple of the row width {ncols}", states.len()),
        ));
    }
    let n = states.len() / ncols;
    if n != n_out {
        return Err(ModelError::shape(
            "out",
            format!("must have {n} entries (one per row of {argument}), got {n_out}"),
        ));
    }
    Ok(n)
}
