//! Range bands: a value that is piecewise constant in range from the sensor.
//!
//! `edges` e_0 < e_1 < … < e_{k-1} split [0, ∞) into k + 1 bands holding `values`
//! v_0 … v_k. Who owns an edge is explicit, because the paper's equations differ:
//! the lidar's 0.2 band is 50 ≤ r < 80 (edge owned by the band above) while the radar's
//! 0.4 band is 50 < r < 1612 (the 50 m edge owned by the band below). `upper_owns[i]`
//! says that r == e_i falls into the band above e_i.

use crate::error::{ModelError, Result};
use crate::memory;
use crate::simd::Lanes;

#[derive(Debug, Clone, PartialEq)]
pub struct RangeBands {
    edges: Vec<f64>,
    values: Vec<f64>,
    upper_owns: Vec<bool>,
    /// Edge k is passed at range √s ⇔ s ≥ `root_thresholds[k]`: [`Self::at`] of a range
    /// computed as √s, read from s itself (see [`root_threshold`]).
    root_thresholds: Vec<f64>,
}

impl RangeBands {
    pub fn new(edges: Vec<f64>, values: Vec<f64>, upper_owns: Vec<bool>) -> Result<Self> {
        if values.len() != edges.len() + 1 {
            return Err(ModelError::shape(
                "values",
                format!(
                    "needs one more entry than edges ({} edges → {} values), got {}",
                    edges.len(),
                    edges.len() + 1,
                    values.len()
                ),
            ));
        }
        if upper_owns.len() != edges.len() {
            return Err(ModelError::shape(
                "upper_owns",
                format!("needs one entry per edge ({}), got {}", edges.len(), upper_owns.len()),
            ));
        }
        for (i, &e) in edges.iter().enumerate() {
            if !e.is_finite() || e < 0.0 {
                return Err(ModelError::invalid(
                    "edges",
                    format!("edge {i} must be finite and >= 0, got {e}"),
                ));
            }
            if i > 0 && e <= edges[i - 1] {
                return Err(ModelError::invalid(
                    "edges",
                    format!(
                        "must be strictly increasing, but edge {i} ({e}) <= edge {} ({})",
                        i - 1,
                        edges[i - 1]
                    ),
                ));
            }
        }
        for (i, &v) in values.iter().enumerate() {
            if !v.is_finite() {
                return Err(ModelError::invalid(
                    "values",
                    format!("value {i} must be finite, got {v}"),
                ));
            }
        }
        let root_thresholds = memory::collected(
            "edges",
            edges.iter().zip(&upper_owns).map(|(&e, &owns)| root_threshold(e, owns)),
        )?;
        Ok(RangeBands {
            edges,
            values,
            upper_owns,
            root_thresholds,
        })
    }

    /// All values (for checks such as "every value is a probability").
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The value at range `r` (r ≥ 0).
    #[inline(always)]
    pub fn at(&self, r: f64) -> f64 {
        // Edges are few (2–4): a linear scan beats a binary search and stays branch-light.
        let mut value = self.values[0];
        for (i, &edge) in self.edges.iter().enumerate() {
            if passed_scalar(r, edge, self.upper_owns[i]) {
                value = self.values[i + 1];
            }
        }
        value
    }

    /// [`Self::at`] for four ranges (r ≥ 0 or NaN), the same bits.
    #[inline(always)]
    pub(crate) fn lanes_at<L: Lanes>(&self, r: L) -> L {
        let mut value = L::splat(self.values[0]);
        for (i, &edge) in self.edges.iter().enumerate() {
            value = L::select(
                passed(r, L::splat(edge), self.upper_owns[i]),
                L::splat(self.values[i + 1]),
                value,
            );
        }
        value
    }

    /// The bands read through their root thresholds as a [`OneEdge`] of sums of squares, if
    /// they have one edge: its [`OneEdge::lanes_at_squared`] gives [`Self::lanes_at_root`]'s
    /// bits, with its three numbers in registers.
    pub fn one_root_edge(&self) -> Option<OneEdge> {
        (self.root_thresholds.len() == 1).then(|| OneEdge {
            at_least: self.root_thresholds[0],
            below: self.values[0],
            above: self.values[1],
        })
    }

    /// [`Self::lanes_at`] of the ranges `s.sqrt()`, the same bits, without the square root:
    /// `s` four squared ranges (sums of squares: ≥ 0, +inf or NaN).
    #[inline(always)]
    pub(crate) fn lanes_at_root<L: Lanes>(&self, s: L) -> L {
        let mut value = L::splat(self.values[0]);
        for (i, &t) in self.root_thresholds.iter().enumerate() {
            value = L::select(s.ge(L::splat(t)), L::splat(self.values[i + 1]), value);
        }
        value
    }
}

/// The least float s ≥ 0 (or +inf) whose square root is past `edge` (finite, ≥ 0).
///
/// A correctly rounded square root is monotone, so {s : √s past the edge} is every float
/// from some threshold up: comparing s with it decides exactly what comparing the computed
/// range √s with the edge decides — unlike comparing s with e², which can differ by an ulp
/// next to the edge. e² (rounded) lies within a couple of ulps of the threshold, so the
/// walk below takes a step or two.
fn root_threshold(edge: f64, upper_owns: bool) -> f64 {
    let past = |s: f64| passed_scalar(s.sqrt(), edge, upper_owns);
    let mut t = edge * edge;
    while t > 0.0 && past(t.next_down()) {
        t = t.next_down();
    }
    // Ends at +inf at the latest: √inf = inf is past every finite edge.
    while !past(t) {
        t = t.next_up();
    }
    t
}

#[inline(always)]
fn passed_scalar(r: f64, edge: f64, upper_owns: bool) -> bool {
    r > edge || (r == edge && upper_owns)
}

/// Whether `r` is past `edge`: beyond it, or on it when the band above owns the edge.
#[inline(always)]
fn passed<L: Lanes>(r: L, edge: L, upper_owns: bool) -> L::Mask {
    // r ≥ e ⇔ r > e or r == e (both false for NaN).
    if upper_owns {
        r.ge(edge)
    } else {
        r.gt(edge)
    }
}

/// `if condition { a } else { b }` without a branch: bit masks, exact values. Range and
/// bearing outcomes are data-dependent, so a branch here mispredicts on real data.
#[inline(always)]
pub(crate) fn select(condition: bool, a: f64, b: f64) -> f64 {
    let mask = (condition as u64).wrapping_neg();
    f64::from_bits((a.to_bits() & mask) | (b.to_bits() & !mask))
}

/// Most edges the branch-free squared-range form takes; models with more use [`RangeBands::at`].
pub const SQUARED_EDGES: usize = 4;

/// [`RangeBands`] compared on squared range, for whole chunks: edge by edge over the chunk,
/// each pass a branch-free select the compiler can vectorise — no square root, no branch,
/// and only as many passes as the bands have edges.
#[derive(Debug, Clone, Copy)]
pub struct SquaredBands {
    count: usize,
    edges2: [f64; SQUARED_EDGES],
    upper_owns: [bool; SQUARED_EDGES],
    values: [f64; SQUARED_EDGES + 1],
    /// r² passes edge k ⇔ r² ≥ at_least[k] (NaN beyond `count`: never), so the lanes need
    /// neither the owner nor the count.
    at_least: [f64; SQUARED_EDGES],
}

/// [`SquaredBands`] with one edge (a range limit, a planar radar horizon), its three
/// numbers held by value, so that a kernel's loop keeps them in registers.
#[derive(Debug, Clone, Copy)]
pub struct OneEdge {
    at_least: f64,
    below: f64,
    above: f64,
}

impl OneEdge {
    /// [`SquaredBands::lanes_at_squared`] of the bands it came from, the same bits.
    #[inline(always)]
    pub(crate) fn lanes_at_squared<L: Lanes>(self, r2: L) -> L {
        L::select(
            r2.ge(L::splat(self.at_least)),
            L::splat(self.above),
            L::splat(self.below),
        )
    }
}

impl SquaredBands {
    /// The bands as a [`OneEdge`], if they have one edge.
    pub fn one_edge(&self) -> Option<OneEdge> {
        (self.count == 1).then_some(OneEdge {
            at_least: self.at_least[0],
            below: self.values[0],
            above: self.values[1],
        })
    }

    #[inline(always)]
    pub fn at_squared(&self, r2: f64) -> f64 {
        let mut value = self.values[0];
        for k in 0..self.count {
            let passed = (r2 > self.edges2[k]) | (self.upper_owns[k] & (r2 == self.edges2[k]));
            value = select(passed, self.values[k + 1], value);
        }
        value
    }

    /// [`Self::at_squared`] for four squared ranges, the same bits.
    #[inline(always)]
    pub(crate) fn lanes_at_squared<L: Lanes>(&self, r2: L) -> L {
        // Two edges (both of the paper's sensors) or up to four, each unrolled.
        if self.count <= 2 {
            self.lanes_over::<L, 2>(r2)
        } else {
            self.lanes_over::<L, SQUARED_EDGES>(r2)
        }
    }

    #[inline(always)]
    fn lanes_over<L: Lanes, const EDGES: usize>(&self, r2: L) -> L {
        let mut value = L::splat(self.values[0]);
        for k in 0..EDGES {
            value = L::select(r2.ge(L::splat(self.at_least[k])), L::splat(self.values[k + 1]), value);
        }
        value
    }
}

impl RangeBands {
    /// The squared-range form, if the bands have at most [`SQUARED_EDGES`] edges.
    pub fn squared(&self) -> Option<SquaredBands> {
        if self.edges.len() > SQUARED_EDGES {
            return None;
        }
        let mut bands = SquaredBands {
            count: self.edges.len(),
            edges2: [f64::INFINITY; SQUARED_EDGES],
            upper_owns: [false; SQUARED_EDGES],
            // (values has edges + 1 ≥ 1 entries: checked in new)
            values: [*self.values.last().unwrap(); SQUARED_EDGES + 1],
            at_least: [f64::NAN; SQUARED_EDGES],
        };
        for (k, &e) in self.edges.iter().enumerate() {
            let e2 = e * e;
            bands.edges2[k] = e2;
            bands.upper_owns[k] = self.upper_owns[k];
            // r² > e² ⇔ r² ≥ the next float above e² (none lies between); above an infinite
            // e² there is nothing, so NaN (never passed).
            bands.at_least[k] = match (self.upper_owns[k], e2.is_finite()) {
                (true, _) => e2,
                (false, true) => e2.next_up(),
                (false, false) => f64::NAN,
            };
        }
        bands.values[..self.values.len()].copy_from_slice(&self.values);
        Some(bands)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lidar() -> RangeBands {
        RangeBands::new(vec![50.0, 80.0], vec![0.95, 0.2, 0.0], vec![true, true]).unwrap()
    }

    fn radar() -> RangeBands {
        RangeBands::new(vec![50.0, 1612.0], vec![0.0, 0.4, 0.0], vec![false, true]).unwrap()
    }

    #[test]
    fn paper_lidar_edges() {
        let b = lidar();
        assert_eq!(b.at(0.0), 0.95);
        assert_eq!(b.at(49.999), 0.95);
        assert_eq!(b.at(50.0), 0.2);
        assert_eq!(b.at(79.999), 0.2);
        assert_eq!(b.at(80.0), 0.0);
        assert_eq!(b.at(1e9), 0.0);
    }

    #[test]
    fn paper_radar_edges_are_open() {
        let b = radar();
        assert_eq!(b.at(50.0), 0.0);
        assert_eq!(b.at(50.000001), 0.4);
        assert_eq!(b.at(1611.9999), 0.4);
        assert_eq!(b.at(1612.0), 0.0);
    }

    #[test]
    fn rejects_bad_configuration() {
        assert_eq!(
            RangeBands::new(vec![80.0, 50.0], vec![1.0, 0.5, 0.0], vec![true, true])
                .unwrap_err()
                .argument(),
            "edges"
        );
        assert_eq!(
            RangeBands::new(vec![-1.0], vec![1.0, 0.5], vec![true])
                .unwrap_err()
                .argument(),
            "edges"
        );
        assert_eq!(
            RangeBands::new(vec![1.0], vec![1.0], vec![true])
                .unwrap_err()
                .argument(),
            "values"
        );
        assert_eq!(
            RangeBands::new(vec![1.0], vec![1.0, f64::NAN], vec![true])
                .unwrap_err()
                .argument(),
            "values"
        );
        assert_eq!(
            RangeBands::new(vec![1.0], vec![1.0, 0.0], vec![])
                .unwrap_err()
                .argument(),
            "upper_owns"
        );
    }

    #[test]
    fn squared_form_matches_range_form() {
        for bands in [lidar(), radar(), RangeBands::new(vec![], vec![0.3], vec![]).unwrap()] {
            let sq = bands.squared().unwrap();
            for r in [0.0, 10.0, 49.999, 50.0, 50.001, 79.0, 80.0, 1611.0, 1612.0, 1e5] {
                assert_eq!(sq.at_squared(r * r), bands.at(r), "r = {r}");
            }
        }
        let many = RangeBands::new(vec![1.0, 2.0, 3.0, 4.0, 5.0], vec![0.0; 6], vec![true; 5]).unwrap();
        assert!(many.squared().is_none());
    }

    /// The root thresholds decide every squared range exactly as the range would: at the
    /// threshold and the floats around it, for edges on and off the float grid of their
    /// squares, both owners, zero and edges whose square overflows.
    #[test]
    fn root_thresholds_decide_as_the_square_root_does() {
        let mut edges = vec![
            0.0,
            f64::MIN_POSITIVE,
            1e-160,
            0.1,
            1.0,
            3.0,
            50.0,
            80.0,
            1000.0,
            1612.0,
            1e154,
            1.5e154,
            f64::MAX,
        ];
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..2000 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            edges.push((state >> 11) as f64 / (1u64 << 53) as f64 * 5000.0);
        }
        for &e in &edges {
            for owns in [false, true] {
                let bands = RangeBands::new(vec![e], vec![1.0, 2.0], vec![owns]).unwrap();
                let t = bands.root_thresholds[0];
                let mut probes = vec![0.0, t, e * e, f64::INFINITY, f64::NAN];
                let (mut up, mut down) = (t, t);
                for _ in 0..4 {
                    up = up.next_up();
                    down = down.next_down();
                    probes.extend([up, down.max(0.0)]);
                }
                for s in probes {
                    let lanes = bands.lanes_at_root(crate::simd::Portable::splat(s)).to_array()[0];
                    assert_eq!(
                        lanes.to_bits(),
                        bands.at(s.sqrt()).to_bits(),
                        "edge {e}, upper owns {owns}, s {s:e}"
                    );
                }
            }
        }
    }

    #[test]
    fn no_edges_is_a_constant() {
        let b = RangeBands::new(vec![], vec![0.7], vec![]).unwrap();
        assert_eq!(b.at(0.0), 0.7);
        assert_eq!(b.at(1e6), 0.7);
    }
}
