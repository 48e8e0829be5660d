//! Line of sight: a target is shadowed when the straight segment from the sensor to it
//! meets land (the radar shade behind islands). Grazing a coastline counts as blocked, and
//! so does a target on land.
//!
//! Two ways to ask, with the same answer (both test candidate coastline edges with one
//! closed segment–segment predicate, [`segments_meet`]; only how candidates are found
//! differs):
//!
//! * [`LineOfSight::visible`] for a single query: a walk down a parry BVH over the coastline
//!   edges' boxes, pruned by a segment–box test, O(log E) per target.
//! * [`LineOfSight::from_point`] for many targets seen from one sensor position (one scan):
//!   builds a [`VisibilityIndex`] once — the coastline edges sorted into angular bins around
//!   the sensor, each bin's edges ordered by their distance from the sensor — and then a
//!   target tests only the edges of its own bin that are nearer than itself, usually none
//!   or one. Building costs O(E log E) per sensor position, so it pays from a few thousand
//!   targets per position on.
//!
//! With no clearance the sensor is assumed to be at sea: from a sensor on land every ray
//! meets its own coastline (or ends on land) and every target is shadowed. A *clearance* c
//! (a sensor on a mast or a cliff top, above the land around it) lets land within c of the
//! sensor block nothing: the segment tested starts c along the way to the target,
//! s + c (t − s)/‖t − s‖, and a target within c is blocked only by standing on land.

use crate::error::{ModelError, Result};
use crate::land::{segments_meet, LandMask};
use crate::memory;
use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::Vector;
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy};
use std::sync::Arc;

#[derive(Debug, Clone)]
pub struct LineOfSight {
    land: Arc<LandMask>,
    /// Land nearer than this to the sensor blocks nothing (world units, ≥ 0).
    clearance: f64,
    /// Coastline edges as (a, b), in the land mask's order and index frame (world × `scale`,
    /// a power of two that is 1 unless the mask is tiny; see [`LandMask`]).
    edges: Vec<[[f64; 2]; 2]>,
    scale: f64,
    /// BVH over the edges' boxes, grown by `margin` so that rounding in the segment–box test
    /// never prunes an edge the segment touches.
    bvh: Bvh,
}

impl LineOfSight {
    pub fn new(land: Arc<LandMask>) -> Result<Self> {
        Self::with_clearance(land, 0.0)
    }

    /// Line of sight over which land within `clearance` of the sensor does not block (see
    /// the module docs); `clearance` must be finite and ≥ 0.
    pub fn with_clearance(land: Arc<LandMask>, clearance: f64) -> Result<Self> {
        if !(clearance.is_finite() && clearance >= 0.0) {
            return Err(ModelError::invalid(
                "clearance",
                format!("must be a finite distance >= 0, got {clearance}"),
            ));
        }
        let edges: Vec<[[f64; 2]; 2]> = memory::collected("land", land.edges().iter().map(|e| [e.a, e.b]))?;
        let scale = edges
            .iter()
            .flatten()
            .fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
        let boxes: Vec<Aabb> = memory::collected(
            "land",
            edges.iter().map(|[a, b]| {
                let margin = 1e-9 * ((a[0] - b[0]).abs() + (a[1] - b[1]).abs()) + 1e-12 * scale + f64::MIN_POSITIVE;
                Aabb::new(
                    Vector::new(a[0].min(b[0]) - margin, a[1].min(b[1]) - margin),
                    Vector::new(a[0].max(b[0]) + margin, a[1].max(b[1]) + margin),
                )
            }),
        )?;
        // (parry's tree allocates infallibly: about as large as the boxes just allocated)
        let bvh = Bvh::from_leaves(BvhBuildStrategy::default(), &boxes);
        let scale = land.scale();
        Ok(LineOfSight {
            land,
            clearance,
            edges,
            scale,
            bvh,
        })
    }

    pub fn land(&self) -> &Arc<LandMask> {
        &self.land
    }

    pub fn clearance(&self) -> f64 {
        self.clearance
    }

    /// Where the tested segment to `target` starts (index frame): the sensor, or with a
    /// clearance c the point c along the way; `None` when the target is within c.
    #[inline(always)]
    fn segment_start(&self, sensor: [f64; 2], target: [f64; 2]) -> Option<[f64; 2]> {
        if self.clearance == 0.0 {
            return Some(sensor);
        }
        let d = [target[0] - sensor[0], target[1] - sensor[1]];
        let c = self.clearance * self.scale;
        let r = d[0].hypot(d[1]);
        if r <= c || r.is_nan() {
            return None; // (NaN: the land test answers for it)
        }
        let f = c / r;
        Some([sensor[0] + f * d[0], sensor[1] + f * d[1]])
    }

    /// Whether the segment sensor → target is free of land (one query; see
    /// [`from_point`](Self::from_point) for many targets from one sensor position).
    #[inline]
    pub fn visible(&self, sensor: [f64; 2], target: [f64; 2]) -> bool {
        self.visible_scaled(self.to_index(sensor), self.to_index(target))
    }

    #[inline(always)]
    fn to_index(&self, p: [f64; 2]) -> [f64; 2] {
        [p[0] * self.scale, p[1] * self.scale]
    }

    /// [`visible`](Self::visible) for points already in the index frame.
    #[inline]
    fn visible_scaled(&self, sensor: [f64; 2], target: [f64; 2]) -> bool {
        if sensor == target {
            return !self.land.contains_scaled(target);
        }
        let Some(sensor) = self.segment_start(sensor, target) else {
            return !self.land.contains_scaled(target);
        };
        let d = [target[0] - sensor[0], target[1] - sensor[1]];
        if !(d[0].is_finite() && d[1].is_finite()) {
            return !self.land.contains_scaled(target);
        }
        let inv = [1.0 / d[0], 1.0 / d[1]];
        let blocked = self
            .bvh
            .leaves(|node| segment_may_touch_box(sensor, d, inv, node.mins(), node.maxs()))
            .any(|k| {
                let [a, b] = self.edges[k as usize];
                segments_meet(sensor, target, a, b)
            });
        // From a sensor at sea a target on land is always behind some coastline edge; the
        // containment test keeps the answer right for a sensor on land too.
        !blocked && !self.land.contains_scaled(target)
    }

    /// The per-scan index for many targets seen from `sensor`.
    pub fn from_point(&self, sensor: [f64; 2]) -> VisibilityIndex<'_> {
        VisibilityIndex::new(self, sensor)
    }
}

/// Conservative slab test: false only when the segment origin + t·d, t ∈ [0, 1], surely
/// misses the (already grown) box. `inv` = (1/d.x, 1/d.y), computed once per segment.
#[inline(always)]
fn segment_may_touch_box(origin: [f64; 2], d: [f64; 2], inv: [f64; 2], mins: Vector, maxs: Vector) -> bool {
    const SLACK: f64 = 1e-9;
    let (mut t0, mut t1) = (-SLACK, 1.0 + SLACK);
    for (o, d, inv, lo, hi) in [
        (origin[0], d[0], inv[0], mins.x, maxs.x),
        (origin[1], d[1], inv[1], mins.y, maxs.y),
    ] {
        if d == 0.0 {
            if o < lo || o > hi {
                return false;
            }
        } else {
            let (a, b) = ((lo - o) * inv, (hi - o) * inv);
            let (near, far) = if a < b { (a, b) } else { (b, a) };
            // Widen each slab's interval a hair: the products round.
            let pad = SLACK * near.abs().max(far.abs()).max(1.0);
            t0 = t0.max(near - pad);
            t1 = t1.min(far + pad);
        }
    }
    t0 <= t1
}

/// A monotone stand-in for the direction angle of (dx, dy), in [0, 4): 0 along +x, 1 along
/// +y, 2 along −x, 3 along −y. Opposite directions differ by exactly 2. No trigonometry.
#[inline(always)]
fn pseudo_angle(dx: f64, dy: f64) -> f64 {
    let p = dx / (dx.abs() + dy.abs());
    if dy < 0.0 {
        3.0 + p
    } else {
        1.0 - p
    }
}

/// Above this mean list length per land-facing bin the index defers to the BVH.
const MAX_MEAN_LIST: f64 = 64.0;

/// One edge listed in one angular bin.
#[derive(Debug, Clone, Copy)]
struct BinEdge {
    a: [f64; 2],
    b: [f64; 2],
    /// A lower bound of the squared distance from the sensor to the edge.
    near2: f64,
}

/// Line of sight from one sensor position to any number of targets; see the module docs.
/// Answers exactly as [`LineOfSight::visible`] does for the same sensor.
#[derive(Debug, Clone)]
pub struct VisibilityIndex<'a> {
    sight: &'a LineOfSight,
    /// In world coordinates, as given.
    sensor: [f64; 2],
    /// The sensor in the index frame.
    sensor_scaled: [f64; 2],
    /// The sensor touches the coastline (with no clearance): every segment from it meets land.
    on_coast: bool,
    /// Too many edges per direction for angular lists: ask the BVH per target.
    dense: bool,
    bins: usize,
    /// CSR over bins; each bin's edges ascending in `near2`.
    bin_start: Vec<u32>,
    entries: Vec<BinEdge>,
}

impl<'a> VisibilityIndex<'a> {
    fn new(sight: &'a LineOfSight, origin: [f64; 2]) -> Self {
        let edges = &sight.edges;
        let sensor = sight.to_index(origin);
        let mut index = VisibilityIndex {
            sight,
            sensor: origin,
            sensor_scaled: sensor,
            on_coast: false,
            dense: false,
            bins: 1,
            bin_start: vec![0, 0],
            entries: Vec::new(),
        };
        let s = sensor;
        let s_size = s[0].abs().max(s[1].abs());

        // Pass 1, per edge: a lower bound of its distance and the pseudo-angle interval
        // [lo, hi] it covers as seen from the sensor (widened for rounding).
        struct Span {
            edge: u32,
            near2: f64,
            lo: f64,
            hi: f64,
        }
        // (the index's buffers: one span per edge, entries within `budget` below, a few times
        // the sight's own edges, which were allocated fallibly when it was built; a query
        // answers a bool, so this per-sensor index is not made fallible)
        let mut spans = Vec::with_capacity(edges.len());
        let mut coverage = 0.0; // Σ (hi − lo): how many edges a direction meets, × 4
        for (k, &[a, b]) in edges.iter().enumerate() {
            if sight.clearance == 0.0 && segments_meet(s, s, a, b) {
                index.on_coast = true;
                return index;
            }
            let (da, db) = ([a[0] - s[0], a[1] - s[1]], [b[0] - s[0], b[1] - s[1]]);
            let near = distance_to_segment(da, db);
            let size = s_size.max(a[0].abs()).max(a[1].abs()).max(b[0].abs()).max(b[1].abs());
            // Rounding in the differences above and in a target's own offset from the
            // sensor: bound it generously so the bins and the distance cut-off never drop
            // an edge a target's segment can touch.
            let fuzz = 64.0 * f64::EPSILON * size;
            let (lo, hi) = if near <= fuzz {
                // Too close to tell directions apart: every direction.
                (0.0, 4.0)
            } else {
                let (pa, pb) = (pseudo_angle(da[0], da[1]), pseudo_angle(db[0], db[1]));
                let cross = da[0] * db[1] - da[1] * db[0];
                // Counter-clockwise from `start` over `len` (pseudo-angle units).
                let (start, len) = if cross > 0.0 {
                    (pa, (pb - pa).rem_euclid(4.0))
                } else if cross < 0.0 {
                    (pb, (pa - pb).rem_euclid(4.0))
                } else {
                    // Collinear with the sensor (not through it): one direction, up to rounding.
                    let len = (pb - pa).rem_euclid(4.0);
                    if len > 2.0 {
                        (pb, 4.0 - len)
                    } else {
                        (pa, len)
                    }
                };
                // Angular error of directions known to ±fuzz at distance ≥ near (a
                // pseudo-angle moves at most 2 units per radian).
                let slack = 4.0 * (fuzz / (near - fuzz)) + 1e-12;
                let (lo, hi) = (start - slack, start + len + slack);
                if hi - lo >= 4.0 {
                    (0.0, 4.0)
                } else {
                    (lo, hi)
                }
            };
            coverage += hi - lo;
            let near_low = (near - fuzz).max(0.0) * (1.0 - 1e-9);
            spans.push(Span {
                edge: k as u32,
                near2: near_low * near_low,
                lo,
                hi,
            });
        }

        // Bins: about one per edge, fewer when the coastline is so folded (a direction
        // meets many edges) that the lists would outgrow a budget of entries; when even
        // that leaves long lists, targets are answered through the BVH instead.
        let n = edges.len().max(1);
        let budget = (32 * n + (1 << 16)) as f64;
        let mut bins = n.next_power_of_two().clamp(256, 1 << 16);
        while bins > 64 && bins as f64 * coverage / 4.0 + 2.0 * n as f64 > budget {
            bins /= 2;
        }
        let per_unit = bins as f64 / 4.0;
        // Mean list length over the bins a direction towards land falls in.
        let occupied = (coverage / 4.0).min(1.0).max(1.0 / bins as f64);
        let mean_list = (coverage * per_unit + n as f64) / (occupied * bins as f64);
        if mean_list > MAX_MEAN_LIST {
            index.dense = true;
            return index;
        }
        let bin_range = |span: &Span| -> (usize, usize) {
            let first = (span.lo * per_unit).floor() as i64;
            let count = ((span.hi * per_unit).floor() as i64 - first + 1) as usize;
            (first.rem_euclid(bins as i64) as usize, count.min(bins))
        };

        // Pass 2: nearest first overall, then a stable counting sort into bins keeps every
        // bin's list nearest first.
        spans.sort_unstable_by(|x, y| x.near2.total_cmp(&y.near2));
        index.bins = bins;
        index.bin_start = vec![0; bins + 1];
        for span in &spans {
            let (first, count) = bin_range(span);
            for i in 0..count {
                index.bin_start[(first + i) % bins + 1] += 1;
            }
        }
        for i in 0..bins {
            index.bin_start[i + 1] += index.bin_start[i];
        }
        // (bins ≤ 2^16; the entries as bounded above)
        let mut fill: Vec<u32> = index.bin_start[..bins].to_vec();
        index.entries = vec![
            BinEdge {
                a: [0.0; 2],
                b: [0.0; 2],
                near2: 0.0
            };
            index.bin_start[bins] as usize
        ];
        for span in &spans {
            let [a, b] = edges[span.edge as usize];
            let (first, count) = bin_range(span);
            for i in 0..count {
                let bin = (first + i) % bins;
                index.entries[fill[bin] as usize] = BinEdge {
                    a,
                    b,
                    near2: span.near2,
                };
                fill[bin] += 1;
            }
        }
        index
    }

    /// Whether this index answers through the BVH because the coastline, seen from its
    /// sensor, is too folded for short angular lists.
    pub fn is_dense(&self) -> bool {
        self.dense
    }

    pub fn sensor(&self) -> [f64; 2] {
        self.sensor
    }

    /// Whether the segment sensor → `target` is free of land.
    #[inline]
    pub fn visible(&self, target: [f64; 2]) -> bool {
        let s = self.sensor_scaled;
        let target = self.sight.to_index(target);
        if s == target {
            return !self.sight.land.contains_scaled(target);
        }
        if self.on_coast {
            return false;
        }
        if self.dense {
            return self.sight.visible_scaled(s, target);
        }
        let (dx, dy) = (target[0] - s[0], target[1] - s[1]);
        let r2 = dx * dx + dy * dy;
        // (the bin and the distance cut-off are the sensor's: the segment from `start` is
        // part of the segment from the sensor, so its candidates are among these)
        let Some(start) = self.sight.segment_start(s, target) else {
            return !self.sight.land.contains_scaled(target);
        };
        // NaN lands in bin 0 and meets nothing; the land test answers for it.
        let bin = ((pseudo_angle(dx, dy) * (self.bins as f64 / 4.0)) as usize) % self.bins;
        let list = &self.entries[self.bin_start[bin] as usize..self.bin_start[bin + 1] as usize];
        for e in list {
            if e.near2 > r2 {
                break;
            }
            if segments_meet(start, target, e.a, e.b) {
                return false;
            }
        }
        !self.sight.land.contains_scaled(target)
    }

    /// How many (bin, edge) entries the index holds (its size).
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// Distance from the origin to the segment a–b (given relative to the origin).
fn distance_to_segment(a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        (-(a[0] * ab[0] + a[1] * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let p = [a[0] + t * ab[0], a[1] + t * ab[1]];
    let exact_end = (a[0] * a[0] + a[1] * a[1]).min(b[0] * b[0] + b[1] * b[1]).sqrt();
    (p[0] * p[0] + p[1] * p[1]).sqrt().min(exact_end)
}

#[cfg(test)]
mod tests;
