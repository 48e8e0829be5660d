//! An online clutter-intensity map: λ learned per cell of a grid in the sensor's measurement
//! space from the detections that no track explains.
//!
//! Each cell c (measurement-space volume V_c: rad·m for a bearing–range cell, m² for an x/y
//! cell) holds a Gamma posterior over its clutter intensity λ_c (expected clutter points per
//! unit volume per scan). With a Gamma(λ₀ s₀ V_c, s₀ V_c) prior — intensity λ₀, worth s₀
//! scans of evidence — and Poisson counts n_{c,j} at scans j, discounted by the forgetting
//! factor γ ∈ (0, 1] per scan (a power prior: scan j counts γ^(k−j) at scan k), the
//! posterior mean after scan k is
//!
//!   λ_c = (λ₀ s₀ + N_c / V_c) / (s₀ + S),   N_c = Σ_j γ^(k−j) n_{c,j},   S = Σ_j γ^(k−j).
//!
//! An update is O(detections + gates) (pooled, plus one pass over the cells, below): instead
//! of multiplying every cell by γ each scan, N and S are stored multiplied by a running
//! scale (×1/γ per scan) and new evidence is added at the current scale; the scale is brought back by an exact power of two when it grows
//! large. Every update counts one scan of exposure for every cell (the sensor reports
//! clutter over its whole grid at every scan) except what *gates* take out: a gate (a disc
//! around a track's position) removes the detections inside it — they are the track's —
//! and its area from its cell's exposure that scan, so S_c = S − D_c with D_c the cell's
//! discounted gated fraction (capped at 1 per scan). A track, true or false, then neither
//! adds clutter evidence nor counts as a place where clutter was looked for and not found.
//! A gate's area (π r², in the measurement space: π r² / max(R, r) rad·m at range R for a
//! bearing–range map) is assigned to the cell of its centre. Outside the grid λ = λ₀.
//!
//! *Pooling* (optional) shares evidence between cells that are expected to have similar
//! clutter: a pool g (a range ring of a bearing–range map — every bearing at one range
//! cell — or the whole grid) has its own posterior with the λ₀ prior,
//!
//!   λ_g = (λ₀ s₀ V_g + Σ_c N_c) / (s₀ V_g + Σ_c V_c S_c),   V_g = Σ_c V_c,
//!
//! and a cell of the pool shrinks towards λ_g instead of λ₀, with weight s_p scans:
//! λ_c = (λ_g s_p + N_c / V_c) / (s_p + S_c) (an empirical-Bayes plug-in: λ_g includes the
//! cell's own counts). A ring pools tens of cells, so its level is learned in a few scans,
//! while a cell with much evidence of its own (a coast) still departs from it.
//!
//! s_p can instead be *estimated* from how much the pool's cells differ (a Gamma–Poisson
//! hierarchy: λ_c ~ Gamma with mean λ_g and variance τ_g², so a cell's prior weight is
//! s_c = λ_g / (τ_g² V_c) scans). τ_g² is the method-of-moments estimate: the spread of the
//! cells' counts about λ_g beyond the spread Poisson counts would have,
//!
//!   τ_g² = max(0, Σ_c [(N_c − λ_g V_c S_c)² − λ_g V_c S2_c]) / Σ_c (V_c S_c)²,
//!
//! with S2_c = Σ_j γ^(2(k−j)) the discounted count's variance per unit mean — derived from S
//! as if every scan had exposed every cell (S2 = (1 − x²) / (1 − γ²), x = 1 − S (1 − γ)),
//! times the cell's exposed share S_c / S. A pool whose cells agree (open sea) gets
//! τ_g² ≈ 0 and its cells take its level.
//!
//! A pool can hold a few cells that are not of it: a point source of persistent returns (a
//! buoy, a moored vessel, a rock), a stretch of coast, a patch that land hides. Moments are
//! not robust to them: one buoy's cell (16 discounted points where its ring of 59 cells
//! expects 0.6) makes τ_g² ten times λ_g² and so frees every cell of its ring (s_c ≈ 16
//! scans against ~100 of their own) and lifts the ring's level by 40 %. So a cell whose
//! counts its pool's level cannot explain *leaves the pool*: by the Chernoff bound on a
//! Poisson tail, P(N ≥ n) or P(N ≤ n) ≤ exp(−(n ln(n/μ) − n + μ)), in effective counts
//! (n = N_c S/S2, μ = λ_g V_c S_c S/S2: the discounted count scaled to a Poisson variance),
//! below [`APART`] / (the pool's number of cells) — a Bonferroni bound, so chance sets a
//! cell of a homogeneous pool apart less than 1 % of the time. A cell apart is estimated
//! alone (the λ₀ prior, as without pooling); the pool's level and spread are then those of
//! the cells that remain (the level's prior still weighs s₀ V_g). The test uses the level of
//! every cell, which the cells apart lift: it errs towards keeping a cell.
//!
//! (Counts weighted by clutter probabilities vary less than Poisson counts of the same mean —
//! Σw² ≤ Σw — so τ_g² is then underestimated: the cells are shrunk more, towards their pool.
//! Differences that a tracker puts there itself — a target's partly counted returns,
//! clutter hidden under a false track — count as spread, as a coast does. The residuals are
//! taken about λ_g, which includes the λ₀ prior and each cell's own counts, with no
//! correction for either: in a pool's first scans the prior's pull adds to τ_g², and in a
//! pool of few cells the own-count share takes from it.)
//!
//! The pools' sums (levels, spreads, the cells apart) are recomputed from the cells after each update
//! (O(cells), vectorised; an incremental sum would round differently from a restored one):
//! they are a function of the state, which therefore stays (counts, deficit, exposure,
//! scale) and restores exactly.
//!
//! Every value stays finite for every configuration the constructor accepts. The running
//! scale stays at most 2^256 after an update (a forgetting factor below 2^−256 discounts the
//! stored sums directly instead: its ×1/γ would leave f64), and a posterior mean whose
//! products would overflow (λ₀ s₀ V near f64's limit) is formed as the weighted mean
//! λ₀ · s/(s + S) + (N/V)/(s + S) instead. A λ is a density trackers divide by, so it is
//! kept within the normal doubles: at least f64::MIN_POSITIVE (a cell or pool estimated
//! below it, e.g. a tiny λ₀ after many empty scans) and at most f64::MAX (a detection in a
//! cell of volume ~1e−308).
//!
//! One file, though long: construction and restore, λ at a detection, the update and the
//! pools' levels all read and write the same scaled sums (counts, deficit, exposure, scale)
//! under the invariants above, so they stay together; the vectorised passes over the cells,
//! which read them through a view of their own, are in `pools`.

use crate::error::{ModelError, Result};
use crate::memory;
use crate::pose::Pose;
use std::f64::consts::PI;

mod pools;
use pools::{Cells, Tests};

/// The coordinates a map's grid is laid over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapSpace {
    /// (bearing in the sensor's frame, radians in [−π, π); range from the sensor, m):
    /// the measurement space of a 2-D bearing–range radar; λ per rad·m.
    BearingRange,
    /// (x along the sensor's heading, y to its left), m; λ per m².
    BodyXY,
    /// World (x, y), m; λ per m².
    WorldXY,
}

/// How cells share evidence (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pooling {
    /// Every cell on its own, shrinking towards λ₀.
    None,
    /// A bearing–range map's range rings: the cells of one range cell, every bearing.
    Range,
    /// The whole grid.
    Grid,
}

/// Scales above this are brought back by [`RESCALE`] (both exact powers of two).
const LARGE: f64 = 1.157920892373162e77; // 2^256
const RESCALE: f64 = 8.636168555094445e-78; // 2^-256
/// With an estimated pool weight: the chance, at most, that a cell of a homogeneous pool is
/// set apart (see the module docs).
pub const APART: f64 = 0.01;
/// The largest total volume of a grid: with the scaled exposure (at most 2^310: 2^256 from
/// the scale, 2^53 scans, a factor 2 in flight) the pools' sums V·S stay below f64::MAX.
const MAX_VOLUME: f64 = 2.1040543606193494e211; // 2^702

#[derive(Debug, Clone, PartialEq)]
pub struct ClutterMap {
    space: MapSpace,
    edges: [Vec<f64>; 2],
    prior_intensity: f64,
    prior_scans: f64,
    forgetting: f64,
    /// Cell volumes, row-major (axis 0 × axis 1).
    volumes: Vec<f64>,
    /// N_c × scale, row-major.
    counts: Vec<f64>,
    /// D_c × scale: the discounted scans' gated fractions of each cell.
    deficit: Vec<f64>,
    /// S × scale.
    exposure: f64,
    scale: f64,
    pooling: Pooling,
    /// s_p: the weight of a cell's pool in its prior, scans (None: from the pool's spread).
    pooled_scans: Option<f64>,
    /// V_g per pool (empty without pooling).
    pool_volumes: Vec<f64>,
    /// Σ_c N_c × scale per pool (with a fixed s_p; an estimated one keeps its own sums).
    pool_counts: Vec<f64>,
    /// Σ_c V_c D_c × scale per pool (likewise).
    pool_deficit: Vec<f64>,
    /// λ_g per pool over the cells not apart, when s_p is estimated (else empty).
    pool_level: Vec<f64>,
    /// τ_g² per pool over the cells not apart, when s_p is estimated (else empty).
    pool_spread: Vec<f64>,
    /// Per cell, whether it has left its pool, when s_p is estimated (else empty).
    apart: Vec<bool>,
    /// Room for the pools' passes, allocated with the pools: an update allocates nothing.
    scratch: Scratch,
}

/// Buffers an estimated pool weight's passes reuse (contents: a function of the state).
#[derive(Debug, Clone, Default, PartialEq)]
struct Scratch {
    /// Per column: its moments.
    sums: Vec<[f64; 5]>,
    /// Per column: the level of every cell of its pool; whether a cell of it left.
    levels: Vec<f64>,
    changed: Vec<bool>,
    /// Per row: whether a cell of it may leave its pool.
    rows: Vec<bool>,
    /// The moments' running sums, one column-long buffer per moment.
    moments: [Vec<f64>; 5],
}

/// Per-column sums as the whole grid's: the columns together, in order.
fn whole(sums: &[[f64; 5]]) -> [f64; 5] {
    let mut whole = [0.0; 5];
    for s in sums {
        for (w, v) in whole.iter_mut().zip(s) {
            *w += v;
        }
    }
    whole
}

fn check_edges(argument: &'static str, edges: &[f64], lowest: f64, highest: f64) -> Result<()> {
    if edges.len() < 2 {
        return Err(ModelError::invalid(
            argument,
            format!("a grid axis needs at least 2 edges, got {}", edges.len()),
        ));
    }
    if let Some(v) = edges.iter().find(|v| !v.is_finite()) {
        return Err(ModelError::invalid(argument, format!("edges must be finite, got {v}")));
    }
    if edges.windows(2).any(|w| w[0] >= w[1]) {
        // (finite, checked above)
        return Err(ModelError::invalid(argument, "edges must be strictly increasing"));
    }
    if edges[0] < lowest || edges[edges.len() - 1] > highest {
        return Err(ModelError::invalid(
            argument,
            format!("edges must lie in [{lowest}, {highest}]"),
        ));
    }
    Ok(())
}

fn positive(argument: &'static str, value: f64) -> Result<()> {
    if !(value.is_finite() && value > 0.0) {
        return Err(ModelError::invalid(
            argument,
            format!("must be finite and > 0, got {value}"),
        ));
    }
    Ok(())
}

/// The posterior mean (m w + x) / (w + s) of a prior mean m worth w against evidence x over
/// exposure s: `direct`, as the caller formed it (the bits every restore and test relies
/// on), unless it overflowed or left the normal doubles; then the weighted mean
/// m · w/(w + s) + x/(w + s), in which no product can overflow, kept within
/// [f64::MIN_POSITIVE, f64::MAX].
#[inline]
fn posterior_mean(direct: f64, mean: f64, weight: f64, evidence: f64, exposure: f64) -> f64 {
    if direct.is_finite() && direct >= f64::MIN_POSITIVE {
        return direct;
    }
    let exposure = exposure.max(0.0); // (rounding can leave S − D an ulp below 0)
    let total = weight + exposure;
    if weight.is_infinite() || total == 0.0 {
        return mean.clamp(f64::MIN_POSITIVE, f64::MAX); // the prior alone, or nothing to weigh
    }
    let rate = if evidence.is_infinite() {
        f64::MAX
    } else {
        evidence / total
    };
    let value = mean * (weight / total) + rate;
    // (NaN only from a restored state whose sums are themselves at f64's limit)
    if value.is_nan() {
        mean
    } else {
        value.clamp(f64::MIN_POSITIVE, f64::MAX)
    }
}

impl ClutterMap {
    /// A fresh map (the prior everywhere). `edges[0]` is bearing (rad, within [−π, π]) or x,
    /// `edges[1]` range (m, ≥ 0) or y.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: NaN fails the test
    pub fn new(
        space: MapSpace,
        edges: [Vec<f64>; 2],
        prior_intensity: f64,
        prior_scans: f64,
        forgetting: f64,
    ) -> Result<Self> {
        let (low, high) = match space {
            MapSpace::BearingRange => ([-PI, 0.0], [PI, f64::INFINITY]),
            _ => ([f64::NEG_INFINITY; 2], [f64::INFINITY; 2]),
        };
        check_edges("edges", &edges[0], low[0], high[0])?;
        check_edges("edges", &edges[1], low[1], high[1])?;
        positive("prior_intensity", prior_intensity)?;
        if prior_intensity < f64::MIN_POSITIVE {
            // (a λ is a density trackers divide by: 1/λ must be finite)
            return Err(ModelError::invalid(
                "prior_intensity",
                format!(
                    "must be at least {:e} (a normal double), got {prior_intensity:e}",
                    f64::MIN_POSITIVE
                ),
            ));
        }
        positive("prior_scans", prior_scans)?;
        if !(forgetting > 0.0 && forgetting <= 1.0) {
            return Err(ModelError::invalid(
                "forgetting",
                format!("must be in (0, 1], got {forgetting}"),
            ));
        }
        let cells = memory::product("edges", &[edges[0].len() - 1, edges[1].len() - 1])?;
        let mut volumes = memory::with_room("edges", cells)?;
        for a in edges[0].windows(2) {
            for b in edges[1].windows(2) {
                volumes.push((a[1] - a[0]) * (b[1] - b[0]));
            }
        }
        if let Some(v) = volumes.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(ModelError::invalid(
                "edges",
                format!("every cell needs a finite volume > 0, got {v}"),
            ));
        }
        let total = (edges[0][edges[0].len() - 1] - edges[0][0]) * (edges[1][edges[1].len() - 1] - edges[1][0]);
        if !(total <= MAX_VOLUME) {
            return Err(ModelError::invalid(
                "edges",
                format!("the grid's volume must be at most {MAX_VOLUME:e} (2^702), got {total:e}"),
            ));
        }
        let (counts, deficit) = (
            memory::filled("edges", cells, 0.0)?,
            memory::filled("edges", cells, 0.0)?,
        );
        Ok(ClutterMap {
            space,
            edges,
            prior_intensity,
            prior_scans,
            forgetting,
            volumes,
            counts,
            deficit,
            exposure: 0.0,
            scale: 1.0,
            pooling: Pooling::None,
            pooled_scans: Some(prior_scans),
            pool_volumes: Vec::new(),
            pool_counts: Vec::new(),
            pool_deficit: Vec::new(),
            pool_level: Vec::new(),
            pool_spread: Vec::new(),
            apart: Vec::new(),
            scratch: Scratch::default(),
        })
    }

    /// The map with its cells pooled (see the module docs): `pooled_scans` (s_p > 0) is the
    /// weight of a cell's pool in its prior; None estimates it from the pool's spread.
    /// Range rings need a bearing–range map.
    pub fn with_pooling(mut self, pooling: Pooling, pooled_scans: Option<f64>) -> Result<Self> {
        if pooling == Pooling::Range && self.space != MapSpace::BearingRange {
            return Err(ModelError::invalid("pooling", "range rings need a bearing-range map"));
        }
        if let Some(weight) = pooled_scans {
            positive("pooling_scans", weight)?;
        }
        let [rows, columns] = self.shape();
        let mut rings = memory::filled("edges", columns, 0.0)?;
        for row in self.volumes.chunks_exact(columns) {
            for (total, v) in rings.iter_mut().zip(row) {
                *total += v;
            }
        }
        self.pool_volumes = match pooling {
            Pooling::None => Vec::new(),
            Pooling::Range => rings,
            Pooling::Grid => vec![rings.iter().sum()],
        };
        let pools = self.pool_volumes.len();
        (self.pool_counts, self.pool_deficit) = (
            memory::filled("edges", pools, 0.0)?,
            memory::filled("edges", pools, 0.0)?,
        );
        (self.pool_level, self.pool_spread, self.apart) = (Vec::new(), Vec::new(), Vec::new());
        self.scratch = Scratch::default();
        if pooling != Pooling::None && pooled_scans.is_none() {
            (self.pool_level, self.pool_spread) = (
                memory::filled("edges", pools, 0.0)?,
                memory::filled("edges", pools, 0.0)?,
            );
            self.apart = memory::filled("edges", self.counts.len(), false)?;
            let column = || memory::filled("edges", columns, 0.0);
            self.scratch = Scratch {
                sums: memory::filled("edges", columns, [0.0; 5])?,
                levels: memory::filled("edges", columns, 0.0)?,
                changed: memory::filled("edges", columns, false)?,
                rows: memory::filled("edges", rows, false)?,
                moments: [column()?, column()?, column()?, column()?, column()?],
            };
        }
        self.pooling = pooling;
        self.pooled_scans = pooled_scans;
        self.refresh_pools();
        Ok(self)
    }

    /// The pool of a cell (row-major index), if pooled.
    #[inline]
    fn pool_of(&self, cell: usize) -> Option<usize> {
        match self.pooling {
            Pooling::None => None,
            Pooling::Range => Some(cell % (self.edges[1].len() - 1)),
            Pooling::Grid => Some(0),
        }
    }

    /// Recomputes the pools' sums from their cells: per range column, the rows in order
    /// (contiguous rows, so the compiler vectorises it), and for the whole grid the columns'
    /// sums in order. A function of the state alone, so restores are exact.
    fn refresh_pools(&mut self) {
        if self.pooling == Pooling::None {
            return;
        }
        if self.pooled_scans.is_none() {
            self.estimate_pools();
            return;
        }
        let columns = self.edges[1].len() - 1;
        let (counts, deficit) = (&mut self.pool_counts, &mut self.pool_deficit);
        if self.pooling == Pooling::Range {
            counts.fill(0.0);
            deficit.fill(0.0);
            for ((n, d), v) in self
                .counts
                .chunks_exact(columns)
                .zip(self.deficit.chunks_exact(columns))
                .zip(self.volumes.chunks_exact(columns))
            {
                for j in 0..columns {
                    counts[j] += n[j];
                    deficit[j] += v[j] * d[j];
                }
            }
            return;
        }
        // the whole grid: per column over the rows in order, then the columns in order
        let (mut total_counts, mut total_deficit) = (0.0, 0.0);
        for j in 0..columns {
            let (mut n, mut d) = (0.0, 0.0);
            for c in (j..self.counts.len()).step_by(columns) {
                n += self.counts[c];
                d += self.volumes[c] * self.deficit[c];
            }
            total_counts += n;
            total_deficit += d;
        }
        (counts[0], deficit[0]) = (total_counts, total_deficit);
    }

    /// With an estimated pool weight (see the module docs): which cells leave their pools,
    /// then the level λ_g and spread τ_g² of each pool over the cells that stay — from the
    /// state alone (the passes of [`pools`], per range column over the rows in order), then
    /// for the whole grid the columns together.
    fn estimate_pools(&mut self) {
        let columns = self.edges[1].len() - 1;
        let rows = self.counts.len() / columns;
        let inverse = 1.0 / self.scale;
        let total = self.exposure * inverse;
        let gamma = self.forgetting;
        let squares = if gamma < 1.0 {
            let x = (1.0 - total * (1.0 - gamma)).max(0.0);
            (1.0 - x * x) / (1.0 - gamma * gamma)
        } else {
            total
        };
        // the discounted count's variance per unit mean, S2 / S, and its inverse (effective counts)
        let per_scan = if total > 0.0 { squares / total } else { 0.0 };
        let effective = if squares > 0.0 { total / squares } else { 0.0 };
        let members = match self.pooling {
            Pooling::Grid => self.counts.len(),
            _ => rows,
        };
        let threshold = (members as f64 / APART).ln();
        let (mut scratch, mut apart) = (std::mem::take(&mut self.scratch), std::mem::take(&mut self.apart));
        let cells = Cells {
            counts: &self.counts,
            deficit: &self.deficit,
            volumes: &self.volumes,
            columns,
            exposure: self.exposure,
            inverse,
        };
        let Scratch {
            sums,
            levels,
            changed,
            rows: to_test,
            moments,
        } = &mut scratch;
        cells.moments(moments, sums);
        // every cell's pool level (of all its cells), per column
        match self.pooling {
            Pooling::Grid => levels.fill(self.level(&whole(sums), self.pool_volumes[0])),
            _ => {
                for ((level, s), v) in levels.iter_mut().zip(sums.iter()).zip(&self.pool_volumes) {
                    *level = self.level(s, *v);
                }
            }
        }
        // cells apart: a bound on each cell's divergence first (vectorised, per row), the
        // logarithm only in rows where the bound cannot keep every cell
        let tests = Tests {
            levels,
            effective,
            threshold,
        };
        apart.fill(false);
        changed.fill(false);
        cells.rows_to_test(tests, to_test);
        for row in (0..rows).filter(|row| to_test[*row]) {
            for (j, column_changed) in changed.iter_mut().enumerate().take(columns) {
                let c = row * columns + j;
                if tests.may_leave(cells.at(c), j) && tests.leaves(cells.at(c), j) {
                    apart[c] = true;
                    *column_changed = true;
                }
            }
        }
        // a column with cells apart: its sums again over the cells that stay (rare; not by
        // subtraction, where a coast's large counts would cancel against the rest)
        for j in (0..columns).filter(|j| changed[*j]) {
            sums[j] = cells.column_moments(j, |c| !apart[c]);
        }
        for g in 0..self.pool_volumes.len() {
            let s = if self.pooling == Pooling::Grid {
                whole(sums)
            } else {
                sums[g]
            };
            let [_, e, nn, ne, ee] = s;
            let l = self.level(&s, self.pool_volumes[g]);
            // Σ (n − λ e)² − λ (S2/S) Σ e, expanded
            let excess = nn - 2.0 * l * ne + l * l * ee - l * per_scan * e;
            self.pool_level[g] = l;
            // (NaN where e² overflows, in a grid of huge cells: no spread resolved, max gives
            // 0; an infinite one, from a level near f64::MAX, is the largest double instead)
            self.pool_spread[g] = if ee > 0.0 {
                #[allow(clippy::manual_clamp)] // clamp keeps NaN; max(0) turns it into 0
                (excess / ee).max(0.0).min(f64::MAX)
            } else {
                0.0
            };
        }
        (self.scratch, self.apart) = (scratch, apart);
    }

    /// λ_g of a pool of `volume` from its cells' sums (Σ n, Σ e, …), with the λ₀ prior.
    fn level(&self, sums: &[f64; 5], volume: f64) -> f64 {
        let direct =
            (self.prior_intensity * self.prior_scans * volume + sums[0]) / (self.prior_scans * volume + sums[1]);
        posterior_mean(
            direct,
            self.prior_intensity,
            self.prior_scans * volume,
            sums[0],
            sums[1],
        )
    }

    /// The map with a saved state (see [`state`](Self::state)).
    pub fn with_state(self, counts: Vec<f64>, deficit: Vec<f64>, exposure: f64, scale: f64) -> Result<Self> {
        self.with_saved(Some(counts), Some(deficit), exposure, scale)
    }

    /// [`with_state`](Self::with_state) where a missing `counts` or `deficit` is the fresh
    /// map's (zeros; no second grid is allocated).
    pub fn with_saved(
        mut self,
        counts: Option<Vec<f64>>,
        deficit: Option<Vec<f64>>,
        exposure: f64,
        scale: f64,
    ) -> Result<Self> {
        let counts = counts.unwrap_or_else(|| std::mem::take(&mut self.counts));
        let deficit = deficit.unwrap_or_else(|| std::mem::take(&mut self.deficit));
        for (argument, values) in [("counts", &counts), ("deficit", &deficit)] {
            if values.len() != self.volumes.len() {
                return Err(ModelError::shape(
                    argument,
                    format!(
                        "must have one entry per cell ({}), got {}",
                        self.volumes.len(),
                        values.len()
                    ),
                ));
            }
            if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(ModelError::invalid(
                    argument,
                    format!("must be finite and >= 0, got {v}"),
                ));
            }
        }
        if !(exposure.is_finite() && exposure >= 0.0) {
            return Err(ModelError::invalid(
                "exposure",
                format!("must be finite and >= 0, got {exposure}"),
            ));
        }
        if !(scale.is_finite() && scale > 0.0) {
            return Err(ModelError::invalid(
                "scale",
                format!("must be finite and > 0, got {scale}"),
            ));
        }
        if let Some(v) = deficit.iter().find(|v| **v > exposure) {
            return Err(ModelError::invalid(
                "deficit",
                format!("cannot exceed the exposure ({exposure}), got {v}"),
            ));
        }
        self.counts = counts;
        self.deficit = deficit;
        self.exposure = exposure;
        self.scale = scale;
        self.refresh_pools();
        Ok(self)
    }

    /// (counts, deficit, exposure — each × scale —, scale): everything an update changes.
    pub fn state(&self) -> (&[f64], &[f64], f64, f64) {
        (&self.counts, &self.deficit, self.exposure, self.scale)
    }

    /// λ outside the grid, and the prior mean everywhere.
    pub fn prior_intensity(&self) -> f64 {
        self.prior_intensity
    }

    pub fn shape(&self) -> [usize; 2] {
        [self.edges[0].len() - 1, self.edges[1].len() - 1]
    }

    /// The detection's coordinates in the map's space. `measured`: its measured range
    /// (NaN: from the position), used by a bearing–range map.
    #[inline]
    fn coordinates(&self, pose: &Pose, x: f64, y: f64, measured: f64) -> [f64; 2] {
        let (dx, dy) = (x - pose.x, y - pose.y);
        match self.space {
            MapSpace::BearingRange => {
                let mut bearing = dy.atan2(dx) - pose.heading;
                // to [−π, π): the heading is already in range, so one turn at most
                if bearing >= PI {
                    bearing -= 2.0 * PI;
                } else if bearing < -PI {
                    bearing += 2.0 * PI;
                }
                let range = if measured.is_nan() { dx.hypot(dy) } else { measured };
                [bearing, range]
            }
            MapSpace::BodyXY => {
                let (sin, cos) = pose.heading.sin_cos();
                [cos * dx + sin * dy, cos * dy - sin * dx]
            }
            MapSpace::WorldXY => [x, y],
        }
    }

    /// The cell (row-major) holding (u, v): half-open [e_i, e_(i+1)) on each axis.
    #[inline]
    fn cell(&self, [u, v]: [f64; 2]) -> Option<usize> {
        let axis = |edges: &[f64], value: f64| {
            if !(value >= edges[0] && value < edges[edges.len() - 1]) {
                return None;
            }
            Some(edges.partition_point(|e| *e <= value) - 1)
        };
        let i = axis(&self.edges[0], u)?;
        let j = axis(&self.edges[1], v)?;
        Some(i * (self.edges[1].len() - 1) + j)
    }

    #[inline]
    fn intensity_of(&self, cell: usize) -> f64 {
        let (n, s) = (
            self.counts[cell] / self.scale,
            (self.exposure - self.deficit[cell]) / self.scale,
        );
        let (prior, weight) = match (self.pool_of(cell), self.pooled_scans) {
            (Some(g), Some(weight)) => (self.pool_intensity(g), weight),
            (Some(_), None) if self.apart[cell] => (self.prior_intensity, self.prior_scans),
            (Some(g), None) => {
                let (level, spread) = (self.pool_level[g], self.pool_spread[g]);
                let weight = level / (spread * self.volumes[cell]);
                if !weight.is_finite() {
                    return level; // the cells agree (τ² = 0, or below what f64 resolves)
                }
                (level, weight)
            }
            (None, _) => (self.prior_intensity, self.prior_scans),
        };
        let evidence = n / self.volumes[cell];
        posterior_mean((prior * weight + evidence) / (weight + s), prior, weight, evidence, s)
    }

    /// λ_g of a pool: its cells' evidence together, with the λ₀ prior.
    #[inline]
    fn pool_intensity(&self, pool: usize) -> f64 {
        let volume = self.pool_volumes[pool];
        let exposed = ((volume * self.exposure - self.pool_deficit[pool]) / self.scale).max(0.0);
        let (weight, evidence) = (self.prior_scans * volume, self.pool_counts[pool] / self.scale);
        let direct = (self.prior_intensity * self.prior_scans * volume + evidence) / (weight + exposed);
        posterior_mean(direct, self.prior_intensity, weight, evidence, exposed)
    }

    /// λ at a world position (NaN when the position is not finite).
    #[inline]
    pub fn value_at(&self, pose: &Pose, x: f64, y: f64, measured: f64) -> f64 {
        if !(x.is_finite() && y.is_finite()) {
            return f64::NAN;
        }
        match self.cell(self.coordinates(pose, x, y, measured)) {
            Some(c) => self.intensity_of(c),
            None => self.prior_intensity,
        }
    }

    /// λ at each of the world `positions` (M, 2, row-major) with their measured `ranges`
    /// (NaN: from the position); a position that is not finite, or a range that is
    /// infinite or negative, is an error naming its row.
    pub fn intensity_at(&self, pose: &Pose, positions: &[f64], ranges: Option<&[f64]>) -> Result<Vec<f64>> {
        let m = self.check_detections(positions, ranges)?;
        let mut values = memory::with_room("positions", m)?;
        values.extend((0..m).map(|i| {
            self.value_at(
                pose,
                positions[2 * i],
                positions[2 * i + 1],
                ranges.map_or(f64::NAN, |r| r[i]),
            )
        }));
        Ok(values)
    }

    /// The number of detections in `positions`, after checking them and their `ranges`.
    fn check_detections(&self, positions: &[f64], ranges: Option<&[f64]>) -> Result<usize> {
        if !positions.len().is_multiple_of(2) {
            return Err(ModelError::shape("positions", "must be (M, 2)"));
        }
        let m = positions.len() / 2;
        if let Some(row) = (0..m).find(|&i| !(positions[2 * i].is_finite() && positions[2 * i + 1].is_finite())) {
            return Err(ModelError::non_finite("positions", row, "position is NaN or infinite"));
        }
        if let Some(r) = ranges {
            if r.len() != m {
                return Err(ModelError::shape(
                    "ranges",
                    format!("must have {m} entries, got {}", r.len()),
                ));
            }
            if let Some(row) = r.iter().position(|v| v.is_infinite() || *v < 0.0) {
                return Err(ModelError::non_finite(
                    "ranges",
                    row,
                    "range is infinite or negative (NaN = use the position)",
                ));
            }
        }
        Ok(m)
    }

    /// The posterior mean λ of every cell, row-major.
    pub fn intensities(&self) -> Result<Vec<f64>> {
        let mut values = memory::with_room("edges", self.counts.len())?;
        values.extend((0..self.counts.len()).map(|c| self.intensity_of(c)));
        Ok(values)
    }

    /// Brings the scale back to at most [`LARGE`] by exact powers of two.
    fn rescale(&mut self) {
        while self.scale > LARGE {
            for v in self.counts.iter_mut().chain(self.deficit.iter_mut()) {
                *v *= RESCALE;
            }
            self.exposure *= RESCALE;
            self.scale *= RESCALE;
        }
    }

    /// One scan: the `positions` (M, 2, world x/y) of its detections, with their measured
    /// ranges (NaN: none), and `gates` (G, 3: world x, y, radius ≥ 0) around the tracks'
    /// positions — detections inside a gate are not clutter, and its area is not exposed.
    /// Checks every input before changing anything.
    pub fn update(&mut self, pose: &Pose, positions: &[f64], ranges: Option<&[f64]>, gates: &[f64]) -> Result<()> {
        self.update_weighted(pose, positions, ranges, None, gates)
    }

    /// [`update`](Self::update) with each detection counting `weights[i]` ∈ [0, 1] of a
    /// clutter point instead of 1: the probability that it is clutter, when a tracker
    /// knows it (a PHD update's λ / (λ + Σ P_D w g), a JPDA's no-target association).
    /// The expected clutter count then feeds the posterior: an EM-style estimate.
    pub fn update_weighted(
        &mut self,
        pose: &Pose,
        positions: &[f64],
        ranges: Option<&[f64]>,
        weights: Option<&[f64]>,
        gates: &[f64],
    ) -> Result<()> {
        let m = self.check_detections(positions, ranges)?;
        if let Some(w) = weights {
            if w.len() != m {
                return Err(ModelError::shape(
                    "weights",
                    format!("must have {m} entries, got {}", w.len()),
                ));
            }
            if let Some(row) = w.iter().position(|v| !(*v >= 0.0 && *v <= 1.0)) {
                return Err(ModelError::non_finite("weights", row, "a weight must be in [0, 1]"));
            }
        }
        if !gates.len().is_multiple_of(3) {
            return Err(ModelError::shape("gates", "must be (G, 3): x, y, radius"));
        }
        if let Some(g) = gates
            .chunks_exact(3)
            .position(|g| !(g.iter().all(|v| v.is_finite()) && g[2] >= 0.0))
        {
            return Err(ModelError::non_finite(
                "gates",
                g,
                "a gate needs a finite centre and a finite radius >= 0",
            ));
        }
        // the gated fractions this scan, per cell (room for every gate, before anything changes)
        let mut gated: Vec<(usize, f64)> = memory::with_room("gates", gates.len() / 3)?;
        self.rescale(); // (a restored state may hold any finite scale; a map's own is ≤ 2^256)
        if self.forgetting >= RESCALE {
            self.scale /= self.forgetting; // (≤ 2^512: the scale is ≤ 2^256 between updates)
        } else {
            // 1/γ would leave the scale's range: the stored sums are discounted instead
            for v in self.counts.iter_mut().chain(self.deficit.iter_mut()) {
                *v *= self.forgetting;
            }
            self.exposure *= self.forgetting;
        }
        let inside_a_gate = |x: f64, y: f64| {
            gates
                .chunks_exact(3)
                .any(|g| (x - g[0]).powi(2) + (y - g[1]).powi(2) <= g[2] * g[2])
        };
        for i in 0..m {
            let (x, y) = (positions[2 * i], positions[2 * i + 1]);
            if inside_a_gate(x, y) {
                continue;
            }
            let measured = ranges.map_or(f64::NAN, |r| r[i]);
            if let Some(c) = self.cell(self.coordinates(pose, x, y, measured)) {
                self.counts[c] += weights.map_or(self.scale, |w| w[i] * self.scale);
            }
        }
        // each gated cell's fraction this scan, summed in gate order, then capped at 1
        for g in gates.chunks_exact(3) {
            let centre = self.coordinates(pose, g[0], g[1], f64::NAN);
            let Some(c) = self.cell(centre) else { continue };
            let area = match self.space {
                MapSpace::BearingRange => PI * g[2] * g[2] / centre[1].max(g[2]),
                _ => PI * g[2] * g[2],
            };
            match gated.iter_mut().find(|(cell, _)| *cell == c) {
                Some((_, fraction)) => *fraction += area / self.volumes[c],
                None => gated.push((c, area / self.volumes[c])),
            }
        }
        for (c, fraction) in gated {
            if fraction > 0.0 {
                self.deficit[c] += self.scale * fraction.min(1.0);
            }
        }
        self.exposure += self.scale;
        self.rescale();
        self.refresh_pools();
        Ok(())
    }
}

#[cfg(test)]
mod tests;
