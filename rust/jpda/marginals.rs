//! Exact joint association marginals (EHM2, as Stone Soup's `JPDAwithEHM2`), and a brute
//! force enumeration of the joint events to check them.
//!
//! One file, though long: the cluster split, the EHM2 tree (its detection sets, levels,
//! backward and forward passes) and the budget that bounds it are one algorithm over shared
//! types, and the enumeration that checks it stays beside it.

use super::{too_large, try_filled};
use crate::error::{ModelError, Result};
use crate::memory;
use std::collections::BTreeMap;

/// A set of a cluster's detections (bit `k` of word `k / 64`).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Bits(Vec<u64>);

impl Bits {
    // (a cluster's detections / 64 words: bounded by the tree's budget, TREE_LIMITS)
    fn empty(words: usize) -> Self {
        Bits(vec![0; words])
    }
    fn has(&self, k: usize) -> bool {
        self.0[k / 64] >> (k % 64) & 1 == 1
    }
    fn set(&mut self, k: usize) {
        self.0[k / 64] |= 1 << (k % 64);
    }
    fn intersects(&self, other: &Bits) -> bool {
        self.0.iter().zip(&other.0).any(|(a, b)| a & b != 0)
    }
    fn union(&self, other: &Bits) -> Bits {
        // (as long as `self`: a few words)
        Bits(self.0.iter().zip(&other.0).map(|(a, b)| a | b).collect())
    }
    /// `(self ∪ {k}) ∩ mask` (`k = None`: no detection).
    fn with_masked(&self, k: Option<usize>, mask: &Bits) -> Bits {
        let mut out = self.clone();
        if let Some(k) = k {
            out.set(k);
        }
        for (o, m) in out.0.iter_mut().zip(&mask.0) {
            *o &= m;
        }
        out
    }
}

/// One track of a cluster's EHM2 tree.
struct Level {
    /// (cluster-local detection or None for the missed detection, weight)
    hyps: Vec<(Option<usize>, f64)>,
    /// Detections used by this track or any below it.
    acc: Bits,
    children: Vec<usize>,
    /// Used-detection set of each node (those that matter to this subtree).
    nodes: Vec<Bits>,
    index: BTreeMap<Bits, usize>,
    /// For node n, hypothesis h, child c: the child's node (`NONE` when h is not allowed at n).
    next: Vec<usize>,
    backward: Vec<f64>,
    forward: Vec<f64>,
}

const NONE: usize = usize::MAX;

impl Level {
    /// The node of `key`, created if new; `budget` counts the cluster's nodes still allowed.
    fn node(&mut self, key: Bits, budget: &mut TreeBudget) -> Result<usize> {
        if let Some(&n) = self.index.get(&key) {
            return Ok(n);
        }
        budget.take_nodes(1)?;
        let n = self.nodes.len();
        self.nodes
            .try_reserve(1)
            .map_err(|_| budget.out_of_memory("the tree's nodes"))?;
        self.nodes.push(key.clone());
        self.index.insert(key, n);
        Ok(n)
    }
}

/// Most hypothesis-tree nodes one cluster may have (summed over its tracks' levels).
///
/// The tree is exact EHM2: a track's level has one node per distinct set of detections,
/// used by the tracks above it, that still matters below it, and that number grows
/// exponentially with the cluster's overlap. Unbounded, it took a context-aware JPDA whose
/// unseen tracks coasted for minutes (145 tracks sharing 35 detections) 21.7 s for one scan
/// and then more than 12 GB, until an allocation failed and aborted the process.
///
/// The budget comes from memory. A node costs ≈ 210 bytes (measured: 4.2 million nodes of a
/// dense 22 × 22 cluster held 1.28 GB of which 0.39 GB were links): its detection set twice
/// (the level's node list and its index key: a 24-byte `Vec<u64>` header and a heap block
/// of ≥ 32 bytes each), the index's B-tree entry and slack, its backward and forward
/// weights. 2²² ≈ 4.2 million nodes are thus ≈ 0.9 GB: what a machine with a few GB to spare
/// can hold beside other work, and far beyond what a tractable scan needs (the experiment's
/// bounded JPDAs stay orders of magnitude below; see `trackers.py`).
pub const MAX_TREE_NODES: usize = 1 << 22;

/// Most child-node links (node × hypothesis × child track, 8 bytes each) one cluster's tree
/// may hold: 2²⁴ ≈ 16.8 million links are 134 MB, so nodes and links together stay near
/// 1 GB. Links also bound the time: each is a set operation and an index look-up when built
/// (≈ 2 s for 16.8 million, measured on a dense cluster) and the forward pass costs links ×
/// children. Every node but the roots is reached through a link, so a tree within this
/// budget has at most this many nodes plus its roots; the node budget binds first only for
/// tracks with few hypotheses and children.
pub const MAX_TREE_EDGES: usize = 1 << 24;

/// What is left of one cluster's tree budget, and the cluster it is for (the error names it).
struct TreeBudget {
    limits: TreeLimits,
    nodes: usize,
    edges: usize,
    tracks: usize,
    dets: usize,
}

/// The most nodes and node links of one cluster's tree.
#[derive(Debug, Clone, Copy)]
pub(super) struct TreeLimits {
    pub(super) nodes: usize,
    pub(super) edges: usize,
}

const TREE_LIMITS: TreeLimits = TreeLimits {
    nodes: MAX_TREE_NODES,
    edges: MAX_TREE_EDGES,
};

impl TreeBudget {
    fn new(limits: TreeLimits, tracks: usize, dets: usize) -> Self {
        TreeBudget {
            limits,
            nodes: limits.nodes,
            edges: limits.edges,
            tracks,
            dets,
        }
    }

    fn intractable(&self, what: String) -> ModelError {
        ModelError::invalid(
            "weights",
            format!(
                "the association cluster of {} tracks and {} detections (tracks sharing gated detections) is intractable for exact JPDA: {what}; \
                 bound the tracks' uncertainty (a deleter on covariance) or gate more tightly",
                self.tracks, self.dets
            ),
        )
    }

    fn take_nodes(&mut self, count: usize) -> Result<()> {
        if count > self.nodes {
            return Err(self.intractable(format!(
                "its hypothesis tree needs more than {} nodes",
                self.limits.nodes
            )));
        }
        self.nodes -= count;
        Ok(())
    }

    fn take_edges(&mut self, count: Option<usize>) -> Result<()> {
        match count {
            Some(count) if count <= self.edges => {
                self.edges -= count;
                Ok(())
            }
            _ => Err(self.intractable(format!(
                "its hypothesis tree needs more than {} node links",
                self.limits.edges
            ))),
        }
    }

    fn out_of_memory(&self, what: &str) -> ModelError {
        self.intractable(format!("allocating {what} failed"))
    }

    /// `len` copies of `value`, allocated fallibly.
    fn filled<T: Clone>(&self, len: usize, value: T, what: &str) -> Result<Vec<T>> {
        try_filled(Some(len), value).ok_or_else(|| self.out_of_memory(what))
    }
}

/// Multiplies `values` by the power of two that brings their largest near 1 (exact).
fn rescale(values: &mut [f64]) {
    let max = values.iter().copied().fold(0.0_f64, f64::max);
    if max > 0.0 && max.is_finite() {
        let exponent = (max.log2().floor() as i32).clamp(-1000, 1000);
        let factor = 2.0_f64.powi(-exponent);
        for v in values.iter_mut() {
            *v *= factor;
        }
    }
}

fn check_weights(weights: &[f64], valid: &[bool], tracks: usize, dets: usize) -> Result<()> {
    if weights.len() != tracks * (dets + 1) {
        return Err(ModelError::shape(
            "weights",
            format!("must be ({tracks}, {}), got {} values", dets + 1, weights.len()),
        ));
    }
    if valid.len() != tracks * dets {
        return Err(ModelError::shape(
            "gated",
            format!("must be ({tracks}, {dets}), got {} values", valid.len()),
        ));
    }
    for t in 0..tracks {
        let row = &weights[t * (dets + 1)..(t + 1) * (dets + 1)];
        let used = std::iter::once(0).chain((0..dets).filter(|&j| valid[t * dets + j]).map(|j| j + 1));
        for k in used {
            if !(row[k].is_finite() && row[k] >= 0.0) {
                return Err(ModelError::invalid(
                    "weights",
                    format!("row {t}, column {k}: must be finite and >= 0, got {}", row[k]),
                ));
            }
        }
    }
    Ok(())
}

fn no_event(tracks: &[usize]) -> ModelError {
    ModelError::invalid(
        "weights",
        format!("no joint association of tracks {tracks:?} has positive probability"),
    )
}

/// Exact marginal association probabilities of `tracks` tracks and `dets` detections:
/// `weights` (T×(M+1), column 0 the missed detection) are the single-hypothesis weights,
/// `valid` (T×M) which detection hypotheses exist. Returns T×(M+1), each row summing to 1
/// over its hypotheses (0 elsewhere).
///
/// Each cluster's tree is bounded by [`MAX_TREE_NODES`] and [`MAX_TREE_EDGES`]: a cluster
/// beyond them is an error naming its numbers of tracks and detections (argument `weights`).
pub fn joint_marginals(weights: &[f64], valid: &[bool], tracks: usize, dets: usize) -> Result<Vec<f64>> {
    joint_marginals_within(TREE_LIMITS, weights, valid, tracks, dets)
}

pub(super) fn joint_marginals_within(
    limits: TreeLimits,
    weights: &[f64],
    valid: &[bool],
    tracks: usize,
    dets: usize,
) -> Result<Vec<f64>> {
    check_weights(weights, valid, tracks, dets)?;
    let mut out = try_filled(tracks.checked_mul(dets + 1), 0.0).ok_or_else(|| too_large(tracks, dets))?;
    // Clusters: tracks connected through shared detections (union–find, smallest index as root).
    let mut parent: Vec<usize> = memory::collected("means", 0..tracks)?;
    fn find(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    for j in 0..dets {
        let mut first = None;
        for t in 0..tracks {
            if valid[t * dets + j] {
                match first {
                    None => first = Some(t),
                    Some(f) => {
                        let (a, b) = (find(&mut parent, f), find(&mut parent, t));
                        if a != b {
                            parent[a.max(b)] = a.min(b);
                        }
                    }
                }
            }
        }
    }
    let mut clusters: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for t in 0..tracks {
        let root = find(&mut parent, t);
        clusters.entry(root).or_default().push(t);
    }
    for members in clusters.values() {
        solve_cluster(limits, members, weights, valid, dets, &mut out)?;
    }
    Ok(out)
}

fn solve_cluster(
    limits: TreeLimits,
    members: &[usize],
    weights: &[f64],
    valid: &[bool],
    dets: usize,
    out: &mut [f64],
) -> Result<()> {
    // The cluster's detections, in index order.
    let local: Vec<usize> = memory::collected(
        "detections",
        (0..dets).filter(|&j| members.iter().any(|&t| valid[t * dets + j])),
    )?;
    let words = local.len().div_ceil(64).max(1);
    // (per level: its track's gated hypotheses, at most the cluster's detections)
    let mut levels: Vec<Level> = memory::collected(
        "detections",
        members.iter().map(|&t| {
            let row = &weights[t * (dets + 1)..(t + 1) * (dets + 1)];
            let mut hyps = vec![(None, row[0])];
            let mut meas = Bits::empty(words);
            for (k, &j) in local.iter().enumerate() {
                if valid[t * dets + j] {
                    hyps.push((Some(k), row[1 + j]));
                    meas.set(k);
                }
            }
            Level {
                hyps,
                acc: meas,
                children: Vec::new(),
                nodes: Vec::new(),
                index: BTreeMap::new(),
                next: Vec::new(),
                backward: Vec::new(),
                forward: Vec::new(),
            }
        }),
    )?;
    let n = levels.len();

    // The tree, built from the last track up: a track's children are the current roots whose
    // detections (theirs and their descendants') meet its own; the others stay roots.
    let mut roots: Vec<usize> = Vec::new();
    for l in (0..n).rev() {
        let own = levels[l].acc.clone();
        let mut acc = own.clone();
        let mut children = Vec::new();
        let mut kept = vec![l];
        for &r in &roots {
            if own.intersects(&levels[r].acc) {
                acc = acc.union(&levels[r].acc);
                children.push(r);
            } else {
                kept.push(r);
            }
        }
        levels[l].acc = acc;
        levels[l].children = children;
        roots = kept;
    }

    // Nodes, top down (a parent's index is below its children's), within the budget.
    let mut budget = TreeBudget::new(limits, n, local.len());
    for &r in &roots {
        levels[r].node(Bits::empty(words), &mut budget)?;
    }
    for l in 0..n {
        let children = std::mem::take(&mut levels[l].children);
        let hyps = std::mem::take(&mut levels[l].hyps);
        let nodes = std::mem::take(&mut levels[l].nodes);
        let links = nodes
            .len()
            .checked_mul(hyps.len())
            .and_then(|v| v.checked_mul(children.len()));
        budget.take_edges(links)?;
        let mut next = budget.filled(links.unwrap_or_default(), NONE, "the tree's node links")?;
        for (ni, used) in nodes.iter().enumerate() {
            for (h, &(det, _)) in hyps.iter().enumerate() {
                if det.is_some_and(|k| used.has(k)) {
                    continue;
                }
                for (ci, &c) in children.iter().enumerate() {
                    let key = used.with_masked(det, &levels[c].acc);
                    next[(ni * hyps.len() + h) * children.len() + ci] = levels[c].node(key, &mut budget)?;
                }
            }
        }
        let level = &mut levels[l];
        level.children = children;
        level.hyps = hyps;
        level.nodes = nodes;
        level.next = next;
    }

    let allowed = |level: &Level, ni: usize, h: usize| level.hyps[h].0.is_none_or(|k| !level.nodes[ni].has(k));

    // Backward weights, bottom up: B(n) = Σ_h w_h Π_c B(child node).
    for l in (0..n).rev() {
        let (nh, nc) = (levels[l].hyps.len(), levels[l].children.len());
        let mut backward = budget.filled(levels[l].nodes.len(), 0.0, "the backward weights")?;
        for (ni, b) in backward.iter_mut().enumerate() {
            for h in 0..nh {
                if !allowed(&levels[l], ni, h) {
                    continue;
                }
                let mut term = levels[l].hyps[h].1;
                for ci in 0..nc {
                    let c = levels[l].children[ci];
                    term *= levels[c].backward[levels[l].next[(ni * nh + h) * nc + ci]];
                }
                *b += term;
            }
        }
        rescale(&mut backward);
        levels[l].backward = backward;
    }

    // Forward weights, top down: each child node gathers F(parent) w_h Π_siblings B.
    for &r in &roots {
        levels[r].forward = budget.filled(levels[r].nodes.len(), 1.0, "the forward weights")?;
    }
    for l in 0..n {
        let (nh, nc) = (levels[l].hyps.len(), levels[l].children.len());
        rescale(&mut levels[l].forward);
        let children = levels[l].children.clone();
        for &c in &children {
            levels[c].forward = budget.filled(levels[c].nodes.len(), 0.0, "the forward weights")?;
        }
        for ni in 0..levels[l].nodes.len() {
            for h in 0..nh {
                if !allowed(&levels[l], ni, h) {
                    continue;
                }
                let base = levels[l].forward[ni] * levels[l].hyps[h].1;
                // (one per child of the level: bounded by the tree's budget)
                let child_nodes: Vec<usize> = (0..nc).map(|ci| levels[l].next[(ni * nh + h) * nc + ci]).collect();
                for ci in 0..nc {
                    let mut term = base;
                    for (si, &s) in children.iter().enumerate() {
                        if si != ci {
                            term *= levels[s].backward[child_nodes[si]];
                        }
                    }
                    levels[children[ci]].forward[child_nodes[ci]] += term;
                }
            }
        }
    }

    // Posterior of each hypothesis: w_h Σ_n F(n) Π_c B(child node), normalised per track.
    for (l, &t) in members.iter().enumerate() {
        let level = &levels[l];
        let (nh, nc) = (level.hyps.len(), level.children.len());
        let mut post = vec![0.0; nh]; // (one per hypothesis of the level, which exist)
        for (h, p) in post.iter_mut().enumerate() {
            let mut sum = 0.0;
            for ni in 0..level.nodes.len() {
                if !allowed(level, ni, h) {
                    continue;
                }
                let mut term = level.forward[ni];
                for ci in 0..nc {
                    term *= levels[level.children[ci]].backward[level.next[(ni * nh + h) * nc + ci]];
                }
                sum += term;
            }
            *p = level.hyps[h].1 * sum;
        }
        let total: f64 = post.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(no_event(members));
        }
        let row = &mut out[t * (dets + 1)..(t + 1) * (dets + 1)];
        for (h, &(det, _)) in level.hyps.iter().enumerate() {
            let column = det.map_or(0, |k| 1 + local[k]);
            row[column] = post[h] / total;
        }
    }
    Ok(())
}

/// The marginals by enumerating every joint event (each track: missed or one of its
/// hypotheses, no detection twice). Exponential: for tests and small inputs only.
pub fn brute_force_marginals(weights: &[f64], valid: &[bool], tracks: usize, dets: usize) -> Result<Vec<f64>> {
    check_weights(weights, valid, tracks, dets)?;
    // (its buffers below are as large as `weights`, which exists; the enumeration's time,
    // not memory, limits its inputs: a reference for tests)
    // (for tests: every buffer here is as large as `weights`, which exists)
    let options: Vec<Vec<usize>> = (0..tracks)
        .map(|t| {
            std::iter::once(0)
                .chain((0..dets).filter(|&j| valid[t * dets + j]).map(|j| j + 1))
                .collect()
        })
        .collect();
    let mut sums = vec![0.0; tracks * (dets + 1)];
    let mut choice = vec![0usize; tracks];
    let mut total = 0.0;
    'events: loop {
        let mut used = vec![false; dets + 1]; // (for tests, as above)
        let mut ok = true;
        let mut product = 1.0;
        for t in 0..tracks {
            let column = options[t][choice[t]];
            if column > 0 {
                if used[column] {
                    ok = false;
                    break;
                }
                used[column] = true;
            }
            product *= weights[t * (dets + 1) + column];
        }
        if ok {
            total += product;
            for t in 0..tracks {
                sums[t * (dets + 1) + options[t][choice[t]]] += product;
            }
        }
        for t in 0..tracks {
            choice[t] += 1;
            if choice[t] < options[t].len() {
                continue 'events;
            }
            choice[t] = 0;
        }
        break;
    }
    if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(no_event(&(0..tracks).collect::<Vec<_>>())); // (for tests, as above)
    }
    Ok(sums.iter().map(|s| s / total).collect()) // (for tests, as above)
}
