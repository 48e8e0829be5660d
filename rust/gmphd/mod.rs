//! The Gaussian-mixture PHD filter's scan, on arrays.
//!
//! One scan of Stone Soup's GM-PHD chain (Vo & Ma 2006) — `GaussianMixtureHypothesiser`
//! over a `DistanceHypothesiser` (Kalman prediction, Mahalanobis gate), `PHDUpdater`,
//! `GaussianMixtureReducer` — computed on a [`Mixture`] kept as arrays between scans:
//!
//! * [`Mixture::predict`]: `x ← F x`, `P ← (F P) Fᵀ + Q`, one `(F, Q)` per time-step group;
//! * [`Mixture::update`]: the measurement prediction of each component
//!   (`ẑ`, `H` or the Jacobian, `S = H P Hᵀ + R`), the gate `d(ẑ, z) < g` on the Mahalanobis
//!   distance with `S`, then for each detection `z` (in the order given) the components it
//!   gates (in mixture order) with weight
//!   `P_D(x) · w · N(z; ẑ, S) · p_S / (Σ + λ(z))` and the Kalman posterior, then each
//!   component's missed-detection term `w (1 − P_D(x)) p_S`; birth components (tag 0) get a
//!   new tag when detected (and `p_S`, as stock) and no missed-detection term;
//! * [`Mixture::reduce`]: prune, greedy merge, unique tags, truncate.
//!
//! The order of every loop is the stock pipeline's (under ctxmodels' stable detection
//! order), so components, tags and weights come out in the stock order; the arithmetic is
//! the same formulae, so values agree with the stock pipeline to rounding.
//!
//! This file holds the mixture's storage and the operations on it as a whole (adding,
//! keeping, moving and predicting components); the update and the reduction, each an
//! algorithm of its own, are the submodules `update` and `reduce`.

mod reduce;
mod update;

pub use reduce::ReduceParams;
pub use update::UpdateParams;

use crate::error::{ModelError, Result};
use crate::kalman;
use crate::memory;

/// The tag of a birth component: never a track; a detected birth gets a fresh tag.
pub const BIRTH: u64 = 0;

/// Gaussian components as arrays: `means` (N×D), `covars` (N×D×D), `weights`, `tags`, and
/// `times` (an integer clock, e.g. microseconds; carried, never read by the maths).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mixture {
    pub ndim: usize,
    pub means: Vec<f64>,
    pub covars: Vec<f64>,
    pub weights: Vec<f64>,
    pub tags: Vec<u64>,
    pub times: Vec<i64>,
    /// The next fresh tag (tags are never reused).
    pub next_tag: u64,
}

impl Mixture {
    pub fn new(ndim: usize) -> Self {
        Mixture {
            ndim,
            next_tag: 1,
            ..Default::default()
        }
    }

    pub fn len(&self) -> usize {
        self.weights.len()
    }

    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    pub fn mean(&self, i: usize) -> &[f64] {
        &self.means[i * self.ndim..(i + 1) * self.ndim]
    }

    pub fn covar(&self, i: usize) -> &[f64] {
        let d2 = self.ndim * self.ndim;
        &self.covars[i * d2..(i + 1) * d2]
    }

    pub(crate) fn fresh_tag(&mut self) -> u64 {
        let tag = self.next_tag;
        self.next_tag += 1;
        tag
    }

    /// Appends components (births, or a mixture given by the user). Tags other than
    /// [`BIRTH`] must be below `next_tag` (the caller allocates them with [`Self::reserve_tags`]).
    pub fn extend(
        &mut self,
        means: &[f64],
        covars: &[f64],
        weights: &[f64],
        tags: &[u64],
        times: &[i64],
    ) -> Result<()> {
        let n = weights.len();
        let d = self.ndim;
        if means.len() != n * d || covars.len() != n * d * d || tags.len() != n || times.len() != n {
            return Err(ModelError::shape(
                "components",
                format!("expected {n} means of dimension {d}, {n} covariances ({d}×{d}), {n} tags and {n} times"),
            ));
        }
        if let Some(row) = (0..n).find(|&i| !means[i * d..(i + 1) * d].iter().all(|v| v.is_finite())) {
            return Err(ModelError::non_finite("means", row, "component means must be finite"));
        }
        if let Some(row) = (0..n).find(|&i| !covars[i * d * d..(i + 1) * d * d].iter().all(|v| v.is_finite())) {
            return Err(ModelError::non_finite(
                "covars",
                row,
                "component covariances must be finite",
            ));
        }
        if let Some(row) = weights.iter().position(|w| !w.is_finite() || *w < 0.0) {
            return Err(ModelError::non_finite(
                "weights",
                row,
                "weights must be finite and >= 0",
            ));
        }
        if let Some(row) = tags.iter().position(|&t| t >= self.next_tag) {
            return Err(ModelError::invalid(
                "tags",
                format!("tag {} of row {row} was not reserved", tags[row]),
            ));
        }
        self.reserve(n)?;
        self.means.extend_from_slice(means);
        self.covars.extend_from_slice(covars);
        self.weights.extend_from_slice(weights);
        self.tags.extend_from_slice(tags);
        self.times.extend_from_slice(times);
        Ok(())
    }

    /// Births at the `means` rows (N×D), each with `covar` (D×D), its `weights` entry, the [`BIRTH`] tag
    /// and `time`, appended in order; with `circle` (x/y position indices, centre, radius)
    /// only those inside it. The same as [`Self::extend`]ing a fresh mixture, keeping its
    /// components inside the circle ([`Self::retain_inside_circle`]) and taking them all
    /// ([`Self::take_from`]), in one call.
    pub fn extend_births(
        &mut self,
        means: &[f64],
        covar: &[f64],
        weights: &[f64],
        time: i64,
        circle: Option<([usize; 2], [f64; 2], f64)>,
    ) -> Result<()> {
        let d = self.ndim;
        if covar.len() != d * d || !means.len().is_multiple_of(d) {
            return Err(ModelError::shape(
                "births",
                format!("expected means of dimension {d} and one {d}×{d} covariance"),
            ));
        }
        let n = means.len() / d;
        if weights.len() != n {
            return Err(ModelError::shape(
                "weights",
                format!("must have {n} entries (one per birth), got {}", weights.len()),
            ));
        }
        let mut fresh = Mixture::new(d);
        let covars = memory::collected("covars", (0..n).flat_map(|_| covar.iter().copied()))?;
        let (tags, times) = (memory::filled("tags", n, BIRTH)?, memory::filled("times", n, time)?);
        fresh.extend(means, &covars, weights, &tags, &times)?;
        if let Some((position, centre, radius)) = circle.filter(|_| !fresh.is_empty()) {
            fresh.retain_inside_circle(position, centre, radius)?;
        }
        let take = memory::filled("take", fresh.len(), true)?;
        self.take_from(&mut fresh, &take)
    }

    /// Room for `n` more components, fallibly, before anything changes.
    pub(crate) fn reserve(&mut self, n: usize) -> Result<()> {
        let d = self.ndim;
        let bytes = (self.len() as u128 + n as u128) * (d as u128 * d as u128 + d as u128 + 3) * 8;
        let fail = |_| ModelError::memory("means", bytes);
        let (more_means, more_covars) = (
            memory::product("means", &[n, d])?,
            memory::product("means", &[n, d, d])?,
        );
        self.means.try_reserve(more_means).map_err(fail)?;
        self.covars.try_reserve(more_covars).map_err(fail)?;
        self.weights.try_reserve(n).map_err(fail)?;
        self.tags.try_reserve(n).map_err(fail)?;
        self.times.try_reserve(n).map_err(fail)
    }

    /// `count` fresh tags, for components that come with their own (string) tags.
    pub fn reserve_tags(&mut self, count: u64) -> u64 {
        let first = self.next_tag;
        self.next_tag += count;
        first
    }

    /// Keeps the components whose flag is set, in order.
    pub fn retain(&mut self, keep: &[bool]) -> Result<()> {
        if keep.len() != self.len() {
            return Err(ModelError::shape(
                "keep",
                format!("expected {} flags, got {}", self.len(), keep.len()),
            ));
        }
        let d = self.ndim;
        let mut out = 0;
        for (i, &kept) in keep.iter().enumerate() {
            if !kept {
                continue;
            }
            if out != i {
                self.means.copy_within(i * d..(i + 1) * d, out * d);
                self.covars.copy_within(i * d * d..(i + 1) * d * d, out * d * d);
                self.weights[out] = self.weights[i];
                self.tags[out] = self.tags[i];
                self.times[out] = self.times[i];
            }
            out += 1;
        }
        self.truncate_to(out);
        Ok(())
    }

    fn truncate_to(&mut self, n: usize) {
        let d = self.ndim;
        self.means.truncate(n * d);
        self.covars.truncate(n * d * d);
        self.weights.truncate(n);
        self.tags.truncate(n);
        self.times.truncate(n);
    }

    /// Keeps the components whose x/y position (`position` indices) lies in the disc of
    /// `radius` around `centre` (boundary included), as `CircularRegion.contains` decides.
    pub fn retain_inside_circle(&mut self, position: [usize; 2], centre: [f64; 2], radius: f64) -> Result<()> {
        let d = self.ndim;
        if position[0] >= d || position[1] >= d {
            return Err(ModelError::invalid(
                "position_mapping",
                format!("indices {position:?} out of range for dimension {d}"),
            ));
        }
        let limit = radius * radius;
        let keep: Vec<bool> = memory::collected(
            "means",
            (0..self.len()).map(|i| {
                let x = self.mean(i);
                let (dx, dy) = (x[position[0]] - centre[0], x[position[1]] - centre[1]);
                dx * dx + dy * dy <= limit
            }),
        )?;
        self.retain(&keep)
    }

    /// Moves the components of `other` whose flag is set to the end of this mixture (in
    /// order); the others stay in `other`, in order.
    pub fn take_from(&mut self, other: &mut Mixture, take: &[bool]) -> Result<()> {
        if take.len() != other.len() {
            return Err(ModelError::shape(
                "take",
                format!("expected {} flags, got {}", other.len(), take.len()),
            ));
        }
        if other.ndim != self.ndim {
            return Err(ModelError::shape(
                "other",
                format!("dimension {} differs from {}", other.ndim, self.ndim),
            ));
        }
        if let Some(row) = (0..other.len()).find(|&i| take[i] && other.tags[i] >= self.next_tag) {
            return Err(ModelError::invalid(
                "other",
                format!("row {row}'s tag {} was not reserved here", other.tags[row]),
            ));
        }
        let keep: Vec<bool> = memory::collected("take", take.iter().map(|t| !t))?;
        self.reserve(take.iter().filter(|t| **t).count())?;
        for i in (0..other.len()).filter(|&i| take[i]) {
            self.means.extend_from_slice(other.mean(i));
            self.covars.extend_from_slice(other.covar(i));
            self.weights.push(other.weights[i]);
            self.tags.push(other.tags[i]);
            self.times.push(other.times[i]);
        }
        other.retain(&keep)
    }

    /// Keeps the components whose RMS x/y position standard deviation
    /// `√(tr P_xy / 2)` is at most `max_std` (`tr P_xy ≤ 2 σ²`).
    pub fn retain_position_std(&mut self, position: [usize; 2], max_std: f64) -> Result<()> {
        let d = self.ndim;
        if position[0] >= d || position[1] >= d {
            return Err(ModelError::invalid(
                "position_mapping",
                format!("indices {position:?} out of range for dimension {d}"),
            ));
        }
        let limit = 2.0 * max_std * max_std;
        let keep: Vec<bool> = memory::collected(
            "means",
            (0..self.len()).map(|i| {
                let c = self.covar(i);
                c[position[0] * d + position[0]] + c[position[1] * d + position[1]] <= limit
            }),
        )?;
        self.retain(&keep)
    }

    /// Stone Soup's track extraction: the rows (ascending) whose tag has a track (`tracked`)
    /// or whose weight exceeds `threshold`, birth components excepted; and the `tracked`
    /// tags no component carries any more (their tracks end), in the order given.
    pub fn track_rows(&self, tracked: &[u64], threshold: f64) -> Result<(Vec<usize>, Vec<u64>)> {
        let mut sorted = memory::copied("tracked", tracked)?;
        sorted.sort_unstable();
        let mut present = memory::filled("tracked", sorted.len(), false)?;
        let mut rows = memory::with_room("means", self.len())?;
        for (i, (&tag, &weight)) in self.tags.iter().zip(&self.weights).enumerate() {
            let found = sorted.binary_search(&tag).ok();
            if let Some(at) = found {
                present[at] = true;
            }
            if tag != BIRTH && (found.is_some() || weight > threshold) {
                rows.push(i);
            }
        }
        let gone = memory::collected(
            "tracked",
            tracked
                .iter()
                .copied()
                .filter(|tag| sorted.binary_search(tag).is_ok_and(|at| !present[at])),
        )?;
        Ok((rows, gone))
    }

    /// The distinct component times, ascending (a scan predicts once per time step).
    pub fn distinct_times(&self) -> Result<Vec<i64>> {
        let mut times = memory::copied("times", &self.times)?;
        times.sort_unstable();
        times.dedup();
        Ok(times)
    }

    /// Kalman prediction to `now` of components stamped `from[g]`, with `F`, `Q` of group
    /// `g` (`transitions`, `noises`: the groups' D×D matrices one after another); every
    /// component's time must be one of `from`. The components take the time `now`.
    pub fn predict_from(&mut self, from: &[i64], now: i64, transitions: &[f64], noises: &[f64]) -> Result<()> {
        let mut group = memory::with_room("times", self.len())?;
        for (row, time) in self.times.iter().enumerate() {
            match from.iter().position(|t| t == time) {
                Some(g) => group.push(g),
                None => {
                    return Err(ModelError::invalid(
                        "from_times",
                        format!("component {row}'s time {time} has no transition"),
                    ))
                }
            }
        }
        self.predict(&group, transitions, noises)?;
        self.times.iter_mut().for_each(|t| *t = now);
        Ok(())
    }

    /// Kalman prediction: component `i` uses `F`, `Q` of group `group[i]`; `transitions`
    /// and `noises` hold the groups' (D×D) matrices one after another.
    pub fn predict(&mut self, group: &[usize], transitions: &[f64], noises: &[f64]) -> Result<()> {
        let d = self.ndim;
        let d2 = d * d;
        if group.len() != self.len() {
            return Err(ModelError::shape(
                "group",
                format!("expected {} group indices, got {}", self.len(), group.len()),
            ));
        }
        if transitions.len() != noises.len() || !transitions.len().is_multiple_of(d2.max(1)) {
            return Err(ModelError::shape(
                "transitions",
                format!("expected (G, {d}, {d}) transition matrices and noise covariances"),
            ));
        }
        let groups = transitions.len().checked_div(d2).unwrap_or(0);
        if let Some(row) = group.iter().position(|&g| g >= groups) {
            return Err(ModelError::invalid(
                "group",
                format!("row {row} names group {} of {groups}", group[row]),
            ));
        }
        if !transitions.iter().chain(noises).all(|v| v.is_finite()) {
            return Err(ModelError::invalid(
                "transitions",
                "transition matrices and noise covariances must be finite",
            ));
        }
        let mut scratch = memory::filled("means", 2 * d2 + d, 0.0)?;
        for (i, &g) in group.iter().enumerate() {
            kalman::predict_state(
                &transitions[g * d2..(g + 1) * d2],
                &noises[g * d2..(g + 1) * d2],
                &mut self.means[i * d..(i + 1) * d],
                &mut self.covars[i * d2..(i + 1) * d2],
                &mut scratch,
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
