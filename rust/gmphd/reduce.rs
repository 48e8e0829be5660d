//! Mixture reduction as Stone Soup's `GaussianMixtureReducer` does it: prune, greedy merge
//! (Vo & Ma), unique tags, truncate — in its order, with the shared-tag pass in
//! first-appearance order (stock iterates a set of random tag strings there).
//!
//! One file, though long: the four passes run in order on one mixture, and most of the
//! length is the greedy merge with its search for candidates (per-axis bounds and an index
//! on the first coordinate), which serves the merge alone.

use super::Mixture;
use crate::error::{ModelError, Result};
use crate::kalman::linalg::{
    cholesky_into, general_inverse_into, inverse_from_cholesky, pseudo_inverse, quadratic_form, spd_inverse_into,
};
use crate::memory;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Tags are distinct integers handed out in sequence: their own hash.
#[derive(Default)]
struct TagHasher(u64);

impl Hasher for TagHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = self.0.rotate_left(8) ^ u64::from(b);
        }
    }
    fn write_u64(&mut self, value: u64) {
        self.0 = value.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

#[derive(Debug, Clone, Copy)]
pub struct ReduceParams {
    pub pruning: bool,
    pub prune_threshold: f64,
    pub merging: bool,
    /// Squared Mahalanobis distance below which a component merges into the heaviest.
    pub merge_threshold: f64,
    pub truncating: bool,
    pub max_components: usize,
    /// `kdtree_max_distance`: only components within this Euclidean distance (whole state
    /// vector) of the heaviest's own mean are merge candidates; `None`: all.
    pub max_distance: Option<f64>,
}

/// Widens the bounds of [`Candidate`] against rounding (they only skip work).
const BOUND_SLACK: f64 = 1.000_001;

/// A merge candidate's covariance `P`: the inverse the stock measure uses (NumPy's
/// `pinv`: the inverse when `P` is regular), computed when first needed, and, where known,
/// the diagonal of a matrix `C` with `δᵀ P⁺ δ ≥ δᵀ C⁻¹ δ` for every δ: `P` itself when it
/// is symmetric positive definite, else the inverse of the symmetric part of `P⁻¹` (round-off
/// can leave a covariance non-symmetric; `δᵀ P⁻¹ δ` only sees that part). Since the
/// ellipsoid `δᵀ C⁻¹ δ < t` projects onto axis k as `δ_k² < t C_kk`, a candidate whose
/// mean differs from the running merge by `δ_k² ≥ t C_kk` in any coordinate cannot merge.
struct Candidates {
    d: usize,
    /// Per rank: the Cholesky factor of a symmetric positive-definite `P`, or the inverse.
    matrices: Vec<f64>,
    inverted: Vec<bool>,
    /// Per rank and coordinate: `t · C_kk` (widened), ∞ where no bound is known.
    limits: Vec<f64>,
}

impl Candidates {
    fn new(
        covars: impl Iterator<Item = (usize, impl AsRef<[f64]>)>,
        n: usize,
        d: usize,
        threshold: f64,
    ) -> Result<Self> {
        // (as large as the mixture's own covariances and means, whose sizes did not overflow)
        let zeros = |len: usize| memory::filled("means", len, 0.0);
        let mut this = Candidates {
            d,
            matrices: zeros(n * d * d)?,
            inverted: memory::filled("means", n, false)?,
            limits: memory::filled("means", n * d, f64::INFINITY)?,
        };
        let mut scratch = zeros(2 * d * d)?;
        let mut part = zeros(d * d)?;
        let mut part_inverse = zeros(d * d)?;
        for (rank, covar) in covars {
            let covar = covar.as_ref();
            let matrix = &mut this.matrices[rank * d * d..(rank + 1) * d * d];
            let limits = &mut this.limits[rank * d..(rank + 1) * d];
            let symmetric = (0..d).all(|r| (0..r).all(|c| covar[r * d + c] == covar[c * d + r]));
            if symmetric && cholesky_into(covar, d, matrix) {
                for k in 0..d {
                    limits[k] = threshold * covar[k * d + k] * BOUND_SLACK;
                }
                continue;
            }
            this.inverted[rank] = true;
            if !general_inverse_into(covar, d, matrix, &mut scratch) {
                matrix.copy_from_slice(&pseudo_inverse(covar, d));
                continue;
            }
            for r in 0..d {
                for c in 0..d {
                    part[r * d + c] = (matrix[r * d + c] + matrix[c * d + r]) / 2.0;
                }
            }
            if spd_inverse_into(&part, d, &mut part_inverse, &mut scratch).is_some() {
                for k in 0..d {
                    limits[k] = threshold * part_inverse[k * d + k] * BOUND_SLACK;
                }
            }
        }
        Ok(this)
    }

    /// The inverse (the stock measure's pinv) of rank `rank`'s covariance.
    fn inverse(&mut self, rank: usize, scratch: &mut [f64]) -> &[f64] {
        let d = self.d;
        let matrix = &mut self.matrices[rank * d * d..(rank + 1) * d * d];
        if !self.inverted[rank] {
            let (work, factor) = scratch.split_at_mut(d * d);
            let factor = &mut factor[..d * d];
            factor.copy_from_slice(matrix);
            inverse_from_cholesky(factor, d, matrix, work);
            self.inverted[rank] = true;
        }
        &self.matrices[rank * d * d..(rank + 1) * d * d]
    }
}

/// The ranks whose first coordinate lies within their own `radius` of a query point, in
/// increasing rank: a sorted index over the ranks with radius up to the 90th percentile
/// (searched in a window of that width) and a list of the wider ones.
struct CandidateIndex {
    by_first: Vec<(f64, usize)>,
    width: f64,
    wide: Vec<usize>,
}

impl CandidateIndex {
    fn new(first: &[f64], radius: &[f64]) -> Result<Self> {
        let mut finite: Vec<f64> = memory::collected("means", radius.iter().copied().filter(|r| r.is_finite()))?;
        finite.sort_by(f64::total_cmp);
        let width = finite.get(finite.len() * 9 / 10).copied().unwrap_or(0.0);
        let (mut by_first, mut wide) = (
            memory::with_room("means", first.len())?,
            memory::with_room("means", first.len())?,
        );
        for (rank, (&x, &r)) in first.iter().zip(radius).enumerate() {
            if r <= width && x.is_finite() {
                by_first.push((x, rank));
            } else {
                wide.push(rank);
            }
        }
        by_first.sort_by(|a, b| a.0.total_cmp(&b.0));
        Ok(CandidateIndex { by_first, width, wide })
    }

    /// Into `hits`: the ranks in `ranks` with `|first − centre| ≤ radius` (a rank whose
    /// radius is negative, merged already, never), ascending.
    fn near(&self, centre: f64, ranks: std::ops::Range<usize>, first: &[f64], radius: &[f64], hits: &mut Vec<usize>) {
        hits.clear();
        let keep = |rank: usize| ranks.contains(&rank) && (first[rank] - centre).abs() <= radius[rank];
        let low = self.by_first.partition_point(|&(x, _)| x < centre - self.width);
        for &(x, rank) in &self.by_first[low..] {
            if x > centre + self.width {
                break;
            }
            if keep(rank) {
                hits.push(rank);
            }
        }
        hits.extend(self.wide.iter().copied().filter(|&rank| keep(rank)));
        hits.sort_unstable();
    }
}

/// For each rank `T`, the lower ranks `k` whose per-axis bounds admit `T`'s own mean
/// (`δ_a² ≤ limit_ka` on every axis `a`, `δ = m_k − m_T`), ascending: the candidates of `T`'s
/// first merge test, found in one sweep over the ranks sorted by their first coordinate
/// (each `k` looks at the means within its radius) instead of one query per `T`. For
/// finite means only; a rank whose radius is NaN is nobody's candidate, as in the index.
#[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: NaN fails the test
fn first_candidates(ranked_means: &[f64], limits: &[f64], radius: &[f64], d: usize) -> Result<Vec<Vec<usize>>> {
    let n = radius.len();
    let mut order: Vec<usize> = memory::collected("means", 0..n)?;
    order.sort_by(|&a, &b| ranked_means[a * d].total_cmp(&ranked_means[b * d]));
    // the means in that order, contiguous: the inner loop walks them linearly
    let firsts: Vec<f64> = memory::collected("means", order.iter().map(|&rank| ranked_means[rank * d]))?;
    let mut sorted: Vec<f64> = memory::with_room("means", ranked_means.len())?;
    sorted.extend(
        order
            .iter()
            .flat_map(|&rank| ranked_means[rank * d..(rank + 1) * d].iter().copied()),
    );
    let mut lists = memory::filled("means", n, Vec::new())?;
    for k in 0..n {
        let (x, reach) = (ranked_means[k * d], radius[k]);
        if reach.is_nan() {
            continue;
        }
        let other = &ranked_means[k * d..(k + 1) * d];
        let limit = &limits[k * d..(k + 1) * d];
        let low = firsts.partition_point(|&first| first < x - reach);
        let high = low + firsts[low..].partition_point(|&first| first <= x + reach);
        for (j, centre) in sorted[low * d..high * d].chunks_exact(d).enumerate() {
            let mut inside = true;
            for a in 0..d {
                let delta = other[a] - centre[a];
                inside &= !(delta * delta > limit[a]);
            }
            let top = order[low + j];
            if inside && top > k {
                lists[top]
                    .try_reserve(1)
                    .map_err(|_| ModelError::memory("means", (lists[top].len() as u128 + 1) * 8))?;
                lists[top].push(k);
            }
        }
    }
    Ok(lists)
}

impl Mixture {
    pub fn reduce(&mut self, params: &ReduceParams) -> Result<()> {
        if params.prune_threshold.is_nan()
            || params.merge_threshold.is_nan()
            || params.max_distance.is_some_and(f64::is_nan)
        {
            return Err(ModelError::invalid(
                "reducer",
                "prune_threshold and merge_threshold must not be NaN",
            ));
        }
        if self.is_empty() {
            return Ok(());
        }
        if params.pruning {
            self.prune(params.prune_threshold)?;
        }
        if self.len() > 1 && params.merging {
            self.merge(params.merge_threshold, params.max_distance, true)?;
            self.unique_tags()?;
        }
        if self.len() > params.max_components && params.truncating {
            self.truncate(params.max_components)?;
        }
        Ok(())
    }

    fn prune(&mut self, threshold: f64) -> Result<()> {
        let mut pruned = 0.0;
        for &w in &self.weights {
            if w < threshold {
                pruned += w;
            }
        }
        let keep: Vec<bool> = memory::collected("means", self.weights.iter().map(|&w| w >= threshold))?;
        self.retain(&keep)?;
        let share_count = self.len() as f64;
        for w in &mut self.weights {
            *w += pruned / share_count;
        }
        Ok(())
    }

    /// Ascending weight, ties in input order (Python's stable `sorted`).
    fn ascending(&self) -> Result<Vec<usize>> {
        let mut order: Vec<usize> = memory::collected("means", 0..self.len())?;
        order.sort_by(|&a, &b| self.weights[a].total_cmp(&self.weights[b]));
        Ok(order)
    }

    /// `listed`: take each heaviest's first candidates from [`first_candidates`] (false:
    /// from the index alone; the same merges, which the tests check).
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: NaN fails the test
    pub(super) fn merge(&mut self, threshold: f64, max_distance: Option<f64>, listed: bool) -> Result<()> {
        let (n, d) = (self.len(), self.ndim);
        let order = self.ascending()?;
        // By rank (ascending weight): means, candidates, and the |δ|² above which a rank
        // cannot merge (`bound`); `radius` = √bound on the first coordinate alone, −1 once
        // a rank has left the remaining set (so the first test also drops it).
        let mut ranked_means = memory::with_room("means", self.means.len())?;
        let mut scratch = memory::filled("means", 2 * d * d, 0.0)?;
        let mut candidates = Candidates::new(
            order.iter().enumerate().map(|(rank, &i)| (rank, self.covar(i))),
            n,
            d,
            threshold,
        )?;
        let mut first = memory::filled("means", n, 0.0)?;
        let mut radius = memory::filled("means", n, f64::INFINITY)?;
        for (rank, &i) in order.iter().enumerate() {
            ranked_means.extend_from_slice(self.mean(i));
            first[rank] = self.mean(i)[0];
            radius[rank] = candidates.limits[rank * d].sqrt() * BOUND_SLACK;
        }
        let index = CandidateIndex::new(&first, &radius)?;
        let lists = (listed && ranked_means.iter().all(|x| x.is_finite()))
            .then(|| first_candidates(&ranked_means, &candidates.limits, &radius, d))
            .transpose()?;
        // (hits: at most n ranks)
        let mut hits = memory::with_room("means", n)?;
        let mut out = Mixture {
            ndim: d,
            next_tag: self.next_tag,
            ..Default::default()
        };
        out.reserve(n)?;
        let mut mean = memory::filled("means", d, 0.0)?;
        let mut covar = memory::filled("means", d * d, 0.0)?;
        let mut delta = memory::filled("means", d, 0.0)?;
        for top in (0..n).rev() {
            if radius[top] < 0.0 {
                continue; // merged into a heavier one
            }
            radius[top] = -1.0;
            let best = order[top];
            mean.copy_from_slice(self.mean(best));
            covar.copy_from_slice(self.covar(best));
            let mut weight = self.weights[best];
            let origin = self.mean(best);
            // Ranks below `top` in increasing order, each against the running merge: a
            // branch-free first test over all of them, the exact ones for the few it keeps,
            // again from the next rank whenever a merge moves the mean. Until the first
            // merge the running mean is `top`'s own, whose candidates were listed at once.
            let mut start = 0;
            let mut listed = lists.as_ref().map(|lists| &lists[top]);
            loop {
                match listed.take() {
                    Some(list) => {
                        hits.clear();
                        hits.extend(list.iter().copied().filter(|&rank| radius[rank] >= 0.0));
                    }
                    None => index.near(mean[0], start..top, &first, &radius, &mut hits),
                }
                let mut merged = None;
                for &rank in &hits {
                    let other = &ranked_means[rank * d..(rank + 1) * d];
                    if let Some(limit) = max_distance {
                        // the stock k-d tree gate: around the heaviest's own mean, not the
                        // running merge; candidates visited in increasing weight (stock:
                        // in a set's address order, which no run can reproduce)
                        let distance: f64 = other.iter().zip(origin).map(|(a, b)| (a - b) * (a - b)).sum();
                        if !(distance.sqrt() <= limit) {
                            continue;
                        }
                    }
                    let limit = &candidates.limits[rank * d..(rank + 1) * d];
                    let mut outside = false;
                    for k in 0..d {
                        delta[k] = other[k] - mean[k];
                        outside |= delta[k] * delta[k] > limit[k];
                    }
                    if outside {
                        continue;
                    }
                    let inverse = candidates.inverse(rank, &mut scratch);
                    if quadratic_form(inverse, &delta, d) < threshold {
                        merged = Some(rank);
                        break;
                    }
                }
                let Some(rank) = merged else { break };
                radius[rank] = -1.0;
                let other = &ranked_means[rank * d..(rank + 1) * d];
                let c = order[rank];
                let other_weight = self.weights[c];
                let weight_sum = weight + other_weight;
                let w1 = weight / weight_sum;
                let w2 = other_weight / weight_sum;
                let other_covar = self.covar(c);
                for k in 0..d {
                    delta[k] = mean[k] - other[k];
                }
                for r in 0..d {
                    for s in 0..d {
                        covar[r * d + s] =
                            (covar[r * d + s] * w1 + other_covar[r * d + s] * w2) + delta[r] * delta[s] * w1 * w2;
                    }
                }
                for k in 0..d {
                    mean[k] = mean[k] * w1 + other[k] * w2;
                }
                weight = if weight_sum > 1.0 { 1.0 } else { weight_sum };
                start = rank + 1;
            }
            out.means.extend_from_slice(&mean);
            out.covars.extend_from_slice(&covar);
            out.weights.push(weight);
            out.tags.push(self.tags[best]);
            out.times.push(self.times[best]);
        }
        *self = out;
        Ok(())
    }

    /// Components sharing a tag: the heaviest keeps it, the others get fresh tags; tags in
    /// first-appearance order, each tag's components by decreasing weight (stable).
    fn unique_tags(&mut self) -> Result<()> {
        let n = self.len();
        let mut sorted = memory::copied("tags", &self.tags)?;
        sorted.sort_unstable();
        if sorted.windows(2).all(|pair| pair[0] != pair[1]) {
            return Ok(()); // no shared tags (the usual case)
        }
        // (the rare case, as large as the tags: the map and lists grow as they are filled)
        let mut first_seen: Vec<u64> = Vec::new();
        let mut groups: HashMap<u64, Vec<usize>, BuildHasherDefault<TagHasher>> = HashMap::default();
        for i in 0..n {
            let members = groups.entry(self.tags[i]).or_default();
            if members.is_empty() {
                first_seen.push(self.tags[i]);
            }
            members.push(i);
        }
        let mut order = memory::with_room("tags", n)?;
        let mut renamed = memory::with_room("tags", n)?;
        for tag in &first_seen {
            let mut members = groups.remove(tag).unwrap_or_default();
            members.sort_by(|&a, &b| self.weights[b].total_cmp(&self.weights[a]));
            order.push(members[0]);
            for &i in &members[1..] {
                order.push(i);
                renamed.push(i);
            }
        }
        for i in renamed {
            self.tags[i] = self.fresh_tag();
        }
        self.reorder(&order)
    }

    fn reorder(&mut self, order: &[usize]) -> Result<()> {
        let d = self.ndim;
        let mut out = Mixture {
            ndim: d,
            next_tag: self.next_tag,
            ..Default::default()
        };
        out.reserve(order.len())?;
        for &i in order {
            out.means.extend_from_slice(self.mean(i));
            out.covars.extend_from_slice(self.covar(i));
            out.weights.push(self.weights[i]);
            out.tags.push(self.tags[i]);
            out.times.push(self.times[i]);
        }
        *self = out;
        Ok(())
    }

    fn truncate(&mut self, limit: usize) -> Result<()> {
        if limit == 0 {
            return Err(ModelError::invalid("max_number_components", "must be at least 1"));
        }
        let mut order: Vec<usize> = memory::collected("means", 0..self.len())?;
        order.sort_by(|&a, &b| self.weights[b].total_cmp(&self.weights[a]));
        let mut dropped = 0.0;
        for &i in &order[limit..] {
            dropped += self.weights[i];
        }
        self.reorder(&order[..limit])?;
        let share = dropped / limit as f64;
        for w in &mut self.weights {
            *w += share;
        }
        Ok(())
    }
}
