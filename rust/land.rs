//! Land mask: polygons (shell + holes) in world coordinates; a point on land, boundary
//! included, gets P_D 0.
//!
//! Rings may be given in any orientation, closed (last vertex repeating the first) or
//! not; consecutive duplicate vertices are dropped. A mask is validated once when built:
//! every ring has ≥ 3 distinct vertices and non-zero area, no two edges cross or touch
//! (except neighbours at their shared vertex), holes lie inside their shell, and no polygon
//! lies on another's land. With those guarantees "on land" is the even–odd rule over all
//! rings, which is what the index below evaluates.
//!
//! Containment index: a two-level grid over the mask's bounding box. Each cell lists the
//! edges that touch it and knows, from a sweep done once, whether its centre is on land.
//! A query walks from the cell centre to the point — horizontally, then vertically — and
//! flips the centre's answer once per edge crossed, so a cell costs its own few edges. Two
//! bits per level-0 cell (water / land / has edges) answer the common edge-free cells from a
//! table that stays in L1. Cells with more than a few edges are split once into s × s
//! sub-cells (s the same for all, chosen within a memory budget of a few sub-cells per edge),
//! so folded or jagged coastlines keep short lists. Where the walk meets an edge exactly at
//! a vertex (integer coordinates do this) the query falls back to the exact crossing count
//! over the edges of the point's row of cells.

use crate::error::{ModelError, Result};
use crate::memory;
use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::Vector;
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy};

pub type Point = [f64; 2];

/// One polygon: a shell ring and zero or more hole rings.
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    pub shell: Vec<Point>,
    pub holes: Vec<Vec<Point>>,
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct Edge {
    pub a: Point,
    pub b: Point,
}

impl Edge {
    fn aabb(&self) -> Aabb {
        Aabb::new(
            Vector::new(self.a[0].min(self.b[0]), self.a[1].min(self.b[1])),
            Vector::new(self.a[0].max(self.b[0]), self.a[1].max(self.b[1])),
        )
    }

    /// Whether the horizontal line y = `y` crosses this edge (half-open in y, so a vertex
    /// on the line is counted once), and where.
    #[inline(always)]
    fn crossing_x(&self, y: f64) -> Option<f64> {
        if (self.a[1] > y) != (self.b[1] > y) {
            Some(self.a[0] + (y - self.a[1]) * (self.b[0] - self.a[0]) / (self.b[1] - self.a[1]))
        } else {
            None
        }
    }

    /// Whether `p` lies on this edge (exact orientation test).
    #[inline(always)]
    fn touches(&self, p: Point) -> bool {
        let cross = (self.b[0] - self.a[0]) * (p[1] - self.a[1]) - (self.b[1] - self.a[1]) * (p[0] - self.a[0]);
        cross == 0.0
            && p[0] >= self.a[0].min(self.b[0])
            && p[0] <= self.a[0].max(self.b[0])
            && p[1] >= self.a[1].min(self.b[1])
            && p[1] <= self.a[1].max(self.b[1])
    }
}

/// A validated land mask with its containment index.
///
/// A mask smaller than [`TINY`] or larger than [`HUGE`] is validated and indexed in a frame
/// scaled by a power of two (exact): at 1e-200 m the products of coordinate differences in
/// the area and orientation tests would underflow to 0, at 1e200 m overflow to infinity.
/// Masks of ordinary size use a scale of 1.
#[derive(Debug, Clone)]
pub struct LandMask {
    /// As given (cleaned), in world coordinates.
    polygons: Vec<Polygon>,
    /// In the index frame: world coordinates × `scale`.
    edges: Vec<Edge>,
    grid: Grid,
    scale: f64,
}

/// Masks whose largest coordinate is below this (2⁻²⁰⁰) are scaled up to it.
pub(crate) const TINY: f64 = f64::from_bits((1023 - 200) << 52);

/// Masks whose largest coordinate is above this (2²⁰⁰) are scaled down to it.
pub(crate) const HUGE: f64 = f64::from_bits((1023 + 200) << 52);

/// The power of two that brings `size` (the largest |coordinate|) up to about [`TINY`] or
/// down to about [`HUGE`], or 1 for sizes that need no scaling.
fn scale_for(size: f64) -> f64 {
    let exponent = if size > 0.0 && size < TINY {
        // size ≥ 2⁻¹⁰⁷⁴, so the exponent is at most 1074 − 200: a normal power of two.
        -200 - size.log2().floor() as i64
    } else if size > HUGE && size.is_finite() {
        // size < 2¹⁰²⁴, so the exponent is at least 200 − 1023: a normal power of two.
        200 - size.log2().floor() as i64
    } else {
        return 1.0;
    };
    f64::from_bits(((exponent + 1023) as u64) << 52)
}

fn scale_ring(ring: &[Point], scale: f64) -> Result<Vec<Point>> {
    memory::collected("polygons", ring.iter().map(|p| [p[0] * scale, p[1] * scale]))
}

/// Every ring of `polygon` scaled by `scale`.
fn scale_polygon(polygon: &Polygon, scale: f64) -> Result<Polygon> {
    let mut holes = memory::with_room("polygons", polygon.holes.len())?;
    for h in &polygon.holes {
        holes.push(scale_ring(h, scale)?);
    }
    Ok(Polygon {
        shell: scale_ring(&polygon.shell, scale)?,
        holes,
    })
}

impl LandMask {
    /// Builds and validates a mask. `polygons` as given by the user: rings of (x, y).
    pub fn new(polygons: Vec<Polygon>) -> Result<Self> {
        if polygons.is_empty() {
            return Err(ModelError::invalid(
                "polygons",
                "a land mask needs at least one polygon",
            ));
        }
        // NaN/inf fail validation below; unscaled, so its message quotes the vertex as given.
        let size = polygons
            .iter()
            .flat_map(|p| p.shell.iter().chain(p.holes.iter().flatten()))
            .flat_map(|v| [v[0].abs(), v[1].abs()])
            .fold(0.0f64, |m, c| {
                if c.is_finite() && m.is_finite() {
                    m.max(c)
                } else {
                    f64::INFINITY
                }
            });
        let scale = scale_for(size);
        let polygons: Vec<Polygon> = if scale == 1.0 {
            polygons
        } else {
            let mut scaled = memory::with_room("polygons", polygons.len())?;
            for p in &polygons {
                scaled.push(scale_polygon(p, scale)?);
            }
            scaled
        };
        let vertices = polygons
            .iter()
            .map(|p| p.shell.len() + p.holes.iter().map(Vec::len).sum::<usize>())
            .sum();
        let mut cleaned = memory::with_room("polygons", polygons.len())?;
        let mut edges = memory::with_room("polygons", vertices)?; // (at most one edge per vertex)
                                                                  // (polygon index, ring index within polygon, first edge, edge count) per ring.
        let mut rings = memory::with_room("polygons", polygons.iter().map(|p| 1 + p.holes.len()).sum())?;
        for (pi, polygon) in polygons.iter().enumerate() {
            let shell = clean_ring(&polygon.shell, pi, None)?;
            let mut holes = memory::with_room("polygons", polygon.holes.len())?;
            for (hi, hole) in polygon.holes.iter().enumerate() {
                holes.push(clean_ring(hole, pi, Some(hi))?);
            }
            for (ri, ring) in std::iter::once(&shell).chain(holes.iter()).enumerate() {
                let first = edges.len();
                for k in 0..ring.len() {
                    edges.push(Edge {
                        a: ring[k],
                        b: ring[(k + 1) % ring.len()],
                    });
                }
                rings.push((pi, ri, first, ring.len()));
            }
            cleaned.push(Polygon { shell, holes });
        }
        check_no_crossings(&edges, &rings)?;
        check_nesting(&cleaned)?;
        let grid = Grid::build(&edges)?;
        if scale != 1.0 {
            // Back to world coordinates: dividing by a power of two undoes the scaling
            // exactly (in place: nothing to allocate).
            for ring in cleaned
                .iter_mut()
                .flat_map(|p| std::iter::once(&mut p.shell).chain(p.holes.iter_mut()))
            {
                for v in ring.iter_mut() {
                    *v = [v[0] / scale, v[1] / scale];
                }
            }
        }
        Ok(LandMask {
            polygons: cleaned,
            edges,
            grid,
            scale,
        })
    }

    pub fn polygons(&self) -> &[Polygon] {
        &self.polygons
    }

    /// The edges in the index frame (world coordinates × [`scale`](Self::scale)).
    pub(crate) fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// World → index frame factor: a power of two, 1 unless the mask is tiny.
    pub(crate) fn scale(&self) -> f64 {
        self.scale
    }

    pub fn vertex_count(&self) -> usize {
        self.edges.len()
    }

    /// Whether `p` is on land (boundary included).
    #[inline]
    pub fn contains(&self, p: Point) -> bool {
        self.contains_scaled([p[0] * self.scale, p[1] * self.scale])
    }

    /// [`contains`](Self::contains) for a point already in the index frame.
    #[inline]
    pub(crate) fn contains_scaled(&self, p: Point) -> bool {
        match self.grid.contains(&self.edges, p) {
            Some(inside) => inside,
            None => self.grid.contains_row_exact(&self.edges, p),
        }
    }
}

/// Exact even–odd test over all edges (boundary counts as land): the reference the index
/// must agree with, and its fallback for degenerate walks.
pub(crate) fn contains_exact(edges: &[Edge], p: Point) -> bool {
    let mut inside = false;
    for e in edges {
        if e.touches(p) {
            return true;
        }
        if let Some(x) = e.crossing_x(p[1]) {
            if x > p[0] {
                inside = !inside;
            }
        }
    }
    inside
}

fn ring_name(polygon: usize, hole: Option<usize>) -> String {
    match hole {
        None => format!("polygon {polygon} shell"),
        Some(h) => format!("polygon {polygon} hole {h}"),
    }
}

fn clean_ring(ring: &[Point], polygon: usize, hole: Option<usize>) -> Result<Vec<Point>> {
    let name = ring_name(polygon, hole);
    let mut out: Vec<Point> = memory::with_room("polygons", ring.len())?;
    for (k, p) in ring.iter().enumerate() {
        if !p[0].is_finite() || !p[1].is_finite() {
            return Err(ModelError::invalid(
                "polygons",
                format!("{name}: vertex {k} is not finite ({}, {})", p[0], p[1]),
            ));
        }
        if out.last() != Some(p) {
            out.push(*p);
        }
    }
    // A closed ring repeats its first vertex at the end: drop the repeat.
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    if out.len() < 3 {
        return Err(ModelError::invalid(
            "polygons",
            format!("{name}: needs at least 3 distinct vertices, got {}", out.len()),
        ));
    }
    let area = signed_area(&out);
    if area == 0.0 {
        // Exactly 0 is collinear, or a ring so much smaller than the rest of the mask that
        // its area underflows: tell which, from the area at the ring's own scale.
        let own = signed_area(&scale_ring(&out, scale_for(ring_size(&out)))?);
        if own == 0.0 {
            return Err(ModelError::invalid(
                "polygons",
                format!("{name}: has zero area (all vertices on a line)"),
            ));
        }
        return Err(ModelError::invalid(
            "polygons",
            format!("{name}: is too small next to the rest of the mask (its area underflows at the mask's scale)"),
        ));
    }
    if !area.is_finite() {
        return Err(ModelError::invalid(
            "polygons",
            format!("{name}: its area overflows (coordinates too large)"),
        ));
    }
    Ok(out)
}

/// The largest |coordinate| of a ring.
fn ring_size(ring: &[Point]) -> f64 {
    ring.iter().fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()))
}

pub(crate) fn signed_area(ring: &[Point]) -> f64 {
    let n = ring.len();
    let mut twice = 0.0;
    for k in 0..n {
        let (a, b) = (ring[k], ring[(k + 1) % n]);
        twice += a[0] * b[1] - b[0] * a[1];
    }
    twice / 2.0
}

fn orientation(a: Point, b: Point, c: Point) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn on_segment(a: Point, b: Point, p: Point) -> bool {
    p[0] >= a[0].min(b[0]) && p[0] <= a[0].max(b[0]) && p[1] >= a[1].min(b[1]) && p[1] <= a[1].max(b[1])
}

/// Whether closed segments ab and cd share any point.
pub(crate) fn segments_meet(a: Point, b: Point, c: Point, d: Point) -> bool {
    let (o1, o2) = (orientation(a, b, c), orientation(a, b, d));
    let (o3, o4) = (orientation(c, d, a), orientation(c, d, b));
    if ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0)) && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0)) {
        return true;
    }
    (o1 == 0.0 && on_segment(a, b, c))
        || (o2 == 0.0 && on_segment(a, b, d))
        || (o3 == 0.0 && on_segment(c, d, a))
        || (o4 == 0.0 && on_segment(c, d, b))
}

/// No two edges may meet, except consecutive edges of one ring at their shared vertex.
/// Candidate pairs come from a parry BVH over the edges' bounding boxes.
fn check_no_crossings(edges: &[Edge], rings: &[(usize, usize, usize, usize)]) -> Result<()> {
    let aabbs: Vec<Aabb> = memory::collected("polygons", edges.iter().map(Edge::aabb))?;
    // (parry's tree allocates infallibly, a few nodes per edge: as large as the boxes just
    // allocated, so a mask whose size fails fails above, before it)
    let bvh = Bvh::from_leaves(BvhBuildStrategy::default(), &aabbs);
    // Which ring each edge belongs to, and its position in the ring.
    let mut owner = memory::filled("polygons", edges.len(), (0usize, 0usize, 0usize))?;
    for (ring_id, &(_, _, first, count)) in rings.iter().enumerate() {
        for k in 0..count {
            owner[first + k] = (ring_id, k, count);
        }
    }
    for (i, e) in edges.iter().enumerate() {
        for j in bvh.intersect_aabb(&aabbs[i]) {
            let j = j as usize;
            if j <= i {
                continue;
            }
            let f = &edges[j];
            let (ri, ki, n) = owner[i];
            let (rj, kj, _) = owner[j];
            let neighbours = ri == rj && (kj == (ki + 1) % n || ki == (kj + 1) % n);
            let meets = if neighbours {
                // Neighbours share one vertex; they are wrong only if they fold back over
                // each other (collinear and overlapping beyond the shared vertex).
                let (shared, p, q) = if e.b == f.a { (e.b, e.a, f.b) } else { (e.a, e.b, f.a) };
                orientation(p, shared, q) == 0.0
                    && ((q[0] - shared[0]) * (p[0] - shared[0]) + (q[1] - shared[1]) * (p[1] - shared[1])) > 0.0
            } else {
                segments_meet(e.a, e.b, f.a, f.b)
            };
            if meets {
                let (pi, ringi, _, _) = rings[ri];
                let (pj, ringj, _, _) = rings[rj];
                let name = |p: usize, r: usize| ring_name(p, r.checked_sub(1));
                return Err(ModelError::invalid(
                    "polygons",
                    format!(
                        "{} edge {} and {} edge {} cross or touch (self-intersecting or touching rings are not valid land)",
                        name(pi, ringi), ki, name(pj, ringj), kj
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn ring_edges(ring: &[Point]) -> Result<Vec<Edge>> {
    memory::collected(
        "polygons",
        (0..ring.len()).map(|k| Edge {
            a: ring[k],
            b: ring[(k + 1) % ring.len()],
        }),
    )
}

/// Holes inside their shell and not inside each other; no polygon on another's land.
/// Rings do not meet (checked before), so one vertex decides where a whole ring lies.
fn check_nesting(polygons: &[Polygon]) -> Result<()> {
    let mut land_edges: Vec<Vec<Edge>> = memory::with_room("polygons", polygons.len())?;
    for p in polygons {
        let mut e = ring_edges(&p.shell)?;
        for h in &p.holes {
            e.try_reserve_exact(h.len())
                .map_err(|_| ModelError::memory("polygons", (e.len() + h.len()) as u128 * 32))?;
            e.extend(ring_edges(h)?);
        }
        land_edges.push(e);
    }
    let bounds: Vec<[f64; 4]> = memory::collected("polygons", polygons.iter().map(|p| ring_bounds(&p.shell)))?;
    for (pi, polygon) in polygons.iter().enumerate() {
        let shell_edges = ring_edges(&polygon.shell)?;
        for (hi, hole) in polygon.holes.iter().enumerate() {
            if !contains_exact(&shell_edges, hole[0]) {
                return Err(ModelError::invalid(
                    "polygons",
                    format!("polygon {pi} hole {hi} lies outside its shell"),
                ));
            }
            for (hj, other) in polygon.holes.iter().enumerate() {
                if hj != hi && contains_exact(&ring_edges(other)?, hole[0]) {
                    return Err(ModelError::invalid(
                        "polygons",
                        format!("polygon {pi} hole {hi} lies inside hole {hj}"),
                    ));
                }
            }
        }
        let v = polygon.shell[0];
        for (pj, b) in bounds.iter().enumerate() {
            let in_box = v[0] >= b[0] && v[0] <= b[2] && v[1] >= b[1] && v[1] <= b[3];
            if pj != pi && in_box && contains_exact(&land_edges[pj], v) {
                return Err(ModelError::invalid(
                    "polygons",
                    format!("polygon {pi} lies on the land of polygon {pj} (overlapping polygons: merge them)"),
                ));
            }
        }
    }
    Ok(())
}

fn ring_bounds(ring: &[Point]) -> [f64; 4] {
    let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    for p in ring {
        b[0] = b[0].min(p[0]);
        b[1] = b[1].min(p[1]);
        b[2] = b[2].max(p[0]);
        b[3] = b[3].max(p[1]);
    }
    b
}

/// One cell of the index: `meta` = edge count << 2 | [`SUBDIVIDED`] | [`CENTRE_ON_LAND`].
/// A leaf's edges are `cell_edges[start..start + count]`; a subdivided cell's s × s
/// sub-cells are `sub_slots[start..start + s²]`.
#[derive(Debug, Clone, Copy, Default)]
struct Slot {
    start: u32,
    meta: u32,
}

const CENTRE_ON_LAND: u32 = 1;
const WATER: u64 = 0;
const LAND: u64 = 1;
const EDGES: u64 = 2;
const SUBDIVIDED: u32 = 2;

impl Slot {
    fn leaf(start: usize, count: usize, centre_on_land: bool) -> Slot {
        Slot {
            start: start as u32,
            meta: ((count as u32) << 2) | centre_on_land as u32,
        }
    }

    #[inline(always)]
    fn count(self) -> usize {
        (self.meta >> 2) as usize
    }

    #[inline(always)]
    fn range(self) -> std::ops::Range<usize> {
        self.start as usize..self.start as usize + self.count()
    }
}

/// Level-0 cells have more edges than this are split into sub-cells.
const DENSE: usize = 6;
/// Sub-cells per side of a split cell, at most.
const MAX_SPLIT: usize = 16;

/// Two-level grid over the edges' bounding box (see the module docs).
#[derive(Debug, Clone)]
struct Grid {
    min: Point,
    max: Point,
    cell: [f64; 2],
    inv_cell: [f64; 2],
    nx: usize,
    ny: usize,
    /// (nx − 1, ny − 1) as floats, for clamping.
    last: [f64; 2],
    slots: Vec<Slot>,
    /// Two bits per level-0 cell, 32 cells a word: [`WATER`], [`LAND`] (no edge in the
    /// cell) or [`EDGES`]. Small enough to stay in L1 for the common edge-free cells.
    kinds: Vec<u64>,
    /// Sub-cells per side of every split cell (0 when no cell is split).
    split: usize,
    sub_cell: [f64; 2],
    inv_sub_cell: [f64; 2],
    sub_slots: Vec<Slot>,
    cell_edges: Vec<u32>,
    /// CSR: the edges touching row j of level-0 cells, each once, for the exact fallback.
    row_start: Vec<u32>,
    row_edges: Vec<u32>,
}

/// Smallest and largest coordinate of all edges.
fn edge_bounds(edges: &[Edge]) -> (Point, Point) {
    let mut min = [f64::INFINITY; 2];
    let mut max = [f64::NEG_INFINITY; 2];
    for e in edges {
        for p in [e.a, e.b] {
            min = [min[0].min(p[0]), min[1].min(p[1])];
            max = [max[0].max(p[0]), max[1].max(p[1])];
        }
    }
    (min, max)
}

/// Lists each edge of `candidates` in every cell of an `n[0]` × `n[1]` grid (origin
/// `origin`, cell size `cell`) that its segment touches. Boxes are grown by `margin`, so
/// rounding in the query's cell lookup never loses an edge from the cell a point lands in.
/// Returns (cell id, edge) pairs sorted by cell.
fn register(
    edges: &[Edge],
    candidates: &[u32],
    origin: Point,
    cell: [f64; 2],
    n: [usize; 2],
    margin: [f64; 2],
) -> Result<Vec<(u32, u32)>> {
    let index = |v: f64, axis: usize| (((v - origin[axis]) / cell[axis]).floor().max(0.0) as usize).min(n[axis] - 1);
    let mut pairs = memory::with_room("polygons", memory::product("polygons", &[candidates.len(), 3])?)?;
    for &k in candidates {
        let e = &edges[k as usize];
        let (i0, i1) = (
            index(e.a[0].min(e.b[0]) - margin[0], 0),
            index(e.a[0].max(e.b[0]) + margin[0], 0),
        );
        let (j0, j1) = (
            index(e.a[1].min(e.b[1]) - margin[1], 1),
            index(e.a[1].max(e.b[1]) + margin[1], 1),
        );
        let most = (i1 - i0 + 1) * (j1 - j0 + 1); // (cells within 2^14 × 2^14: no overflow)
        pairs
            .try_reserve(most)
            .map_err(|_| ModelError::memory("polygons", (pairs.len() + most) as u128 * 8))?;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let x0 = origin[0] + i as f64 * cell[0];
                let y0 = origin[1] + j as f64 * cell[1];
                let grown = [
                    x0 - margin[0],
                    y0 - margin[1],
                    x0 + cell[0] + margin[0],
                    y0 + cell[1] + margin[1],
                ];
                if segment_touches_box(e, grown) {
                    pairs.push(((j * n[0] + i) as u32, k));
                }
            }
        }
    }
    pairs.sort_unstable();
    Ok(pairs)
}

/// Even–odd parity of the horizontal ray from (x, y) to +∞ for each x of `xs` (ascending),
/// over `candidates` (which must hold every edge crossing y = `y` right of xs[0]). The same
/// half-open rule as [`Edge::crossing_x`], so parities agree with the query's walk.
fn row_parities(edges: &[Edge], candidates: &[u32], y: f64, xs: &[f64], crossings: &mut Vec<f64>, out: &mut Vec<bool>) {
    crossings.clear();
    crossings.extend(candidates.iter().filter_map(|&k| edges[k as usize].crossing_x(y)));
    crossings.sort_unstable_by(|a, b| a.total_cmp(b));
    out.clear();
    let mut left = 0; // crossings with x <= the current x
    for &x in xs {
        while left < crossings.len() && crossings[left] <= x {
            left += 1;
        }
        out.push((crossings.len() - left) % 2 == 1);
    }
}

impl Grid {
    fn build(edges: &[Edge]) -> Result<Grid> {
        let (min, max) = edge_bounds(edges);
        // About one level-0 cell per edge keeps that table small (it is touched by every
        // query); dense cells are split below.
        let target_cells = edges.len().clamp(1 << 12, 1 << 22) as f64;
        let (w, h) = (
            (max[0] - min[0]).max(f64::MIN_POSITIVE),
            (max[1] - min[1]).max(f64::MIN_POSITIVE),
        );
        let nx = ((target_cells * w / h).sqrt().round() as usize).clamp(1, 1 << 14);
        let ny = ((target_cells / nx as f64).round() as usize).clamp(1, 1 << 14);
        let cell = [w / nx as f64, h / ny as f64];
        // Generous margins: an edge listed in a cell it misses costs a test, never an error.
        let scale = min[0].abs().max(min[1].abs()).max(max[0].abs()).max(max[1].abs());
        let margin_for = |c: [f64; 2]| [c[0] * 1e-7 + scale * 1e-13, c[1] * 1e-7 + scale * 1e-13];

        let all: Vec<u32> = memory::collected("polygons", 0..edges.len() as u32)?;
        let pairs = register(edges, &all, min, cell, [nx, ny], margin_for(cell))?;
        let mut cell_start = memory::filled("polygons", nx * ny + 1, 0usize)?; // (nx, ny ≤ 2^14)
        for &(c, _) in &pairs {
            cell_start[c as usize + 1] += 1;
        }
        for c in 0..nx * ny {
            cell_start[c + 1] += cell_start[c];
        }
        let level0_edges: Vec<u32> = memory::collected("polygons", pairs.into_iter().map(|(_, k)| k))?;
        let cell_list = |c: usize| &level0_edges[cell_start[c]..cell_start[c + 1]];

        // Split dense cells, all into the same s × s, within a memory budget of a few
        // sub-cells per edge.
        let dense = (0..nx * ny).filter(|&c| cell_list(c).len() > DENSE).count();
        let split = if dense == 0 {
            0
        } else {
            let budget = (8 * edges.len()).max(1 << 12) as f64;
            ((budget / dense as f64).sqrt() as usize).clamp(2, MAX_SPLIT)
        };
        let sub_cell = if split > 0 {
            [cell[0] / split as f64, cell[1] / split as f64]
        } else {
            cell
        };
        let mut grid = Grid {
            min,
            max,
            cell,
            inv_cell: [1.0 / cell[0], 1.0 / cell[1]],
            nx,
            ny,
            last: [(nx - 1) as f64, (ny - 1) as f64],
            slots: memory::filled("polygons", nx * ny, Slot::default())?,
            kinds: memory::filled("polygons", (nx * ny).div_ceil(32), 0)?,
            split,
            sub_cell,
            inv_sub_cell: [1.0 / sub_cell[0], 1.0 / sub_cell[1]],
            sub_slots: memory::with_room("polygons", memory::product("polygons", &[dense, split, split])?)?,
            cell_edges: memory::with_room("polygons", memory::product("polygons", &[level0_edges.len(), 2])?)?,
            row_start: Vec::new(),
            row_edges: Vec::new(),
        };

        let mut seen_in_row = memory::filled("polygons", edges.len(), usize::MAX)?;
        // (row_edges holds each edge once per row it touches: at most the level-0 pairs)
        grid.row_edges = memory::with_room("polygons", level0_edges.len())?;
        grid.row_start = memory::with_room("polygons", ny + 1)?;
        grid.row_start.push(0);
        let (mut crossings, mut parities) = (Vec::new(), Vec::new());
        let mut xs = Vec::new();
        for j in 0..ny {
            // This row's edges, each once: every edge crossing a horizontal line inside the
            // row is among them.
            let row_first = grid.row_edges.len();
            for c in j * nx..(j + 1) * nx {
                for &k in cell_list(c) {
                    if seen_in_row[k as usize] != j {
                        seen_in_row[k as usize] = j;
                        grid.row_edges.push(k);
                    }
                }
            }
            grid.row_start.push(grid.row_edges.len() as u32);
            let row = memory::copied("polygons", &grid.row_edges[row_first..])?;

            xs.clear();
            xs.extend((0..nx).map(|i| grid.centre(i, j)[0]));
            row_parities(edges, &row, grid.centre(0, j)[1], &xs, &mut crossings, &mut parities);
            let level0_land = parities.clone();

            let dense_in_row: Vec<usize> =
                memory::collected("polygons", (0..nx).filter(|&i| cell_list(j * nx + i).len() > DENSE))?;
            // Sub-cell centre parities of this row's split cells, one sweep per sub-row.
            let mut sub_land = memory::filled(
                "polygons",
                memory::product("polygons", &[dense_in_row.len(), split, split])?,
                false,
            )?;
            if !dense_in_row.is_empty() {
                for sj in 0..split {
                    xs.clear();
                    for &i in &dense_in_row {
                        xs.extend((0..split).map(|si| grid.sub_centre(i, j, si, sj)[0]));
                    }
                    let y = grid.sub_centre(0, j, 0, sj)[1];
                    row_parities(edges, &row, y, &xs, &mut crossings, &mut parities);
                    for (d, chunk) in parities.chunks(split).enumerate() {
                        sub_land[(d * split + sj) * split..(d * split + sj + 1) * split].copy_from_slice(chunk);
                    }
                }
            }

            let mut d = 0;
            for (i, &centre_land) in level0_land.iter().enumerate() {
                let c = j * nx + i;
                let list = cell_list(c);
                if list.len() > DENSE {
                    let origin = [min[0] + i as f64 * cell[0], min[1] + j as f64 * cell[1]];
                    let sub_pairs = register(edges, list, origin, sub_cell, [split, split], margin_for(sub_cell))?;
                    let room = sub_pairs.len();
                    grid.cell_edges
                        .try_reserve(room)
                        .map_err(|_| ModelError::memory("polygons", (grid.cell_edges.len() + room) as u128 * 4))?;
                    let first_slot = grid.sub_slots.len();
                    let mut p = 0;
                    for s in 0..split * split {
                        let start = grid.cell_edges.len();
                        while p < sub_pairs.len() && sub_pairs[p].0 as usize == s {
                            grid.cell_edges.push(sub_pairs[p].1);
                            p += 1;
                        }
                        let (sj, si) = (s / split, s % split);
                        let land = sub_land[(d * split + sj) * split + si];
                        grid.sub_slots
                            .push(Slot::leaf(start, grid.cell_edges.len() - start, land));
                    }
                    grid.slots[c] = Slot {
                        start: first_slot as u32,
                        meta: SUBDIVIDED,
                    };
                    d += 1;
                } else {
                    let start = grid.cell_edges.len();
                    grid.cell_edges
                        .try_reserve(list.len())
                        .map_err(|_| ModelError::memory("polygons", (start + list.len()) as u128 * 4))?;
                    grid.cell_edges.extend_from_slice(list);
                    grid.slots[c] = Slot::leaf(start, list.len(), centre_land);
                }
            }
        }
        for c in 0..nx * ny {
            let slot = grid.slots[c];
            let kind = if slot.meta == 0 {
                WATER
            } else if slot.meta == CENTRE_ON_LAND {
                LAND
            } else {
                EDGES
            };
            grid.kinds[c / 32] |= kind << (2 * (c % 32));
        }
        if !(grid.cell_edges.len() < u32::MAX as usize && grid.sub_slots.len() < u32::MAX as usize) {
            return Err(ModelError::invalid(
                "polygons",
                "the land index would need more than 2^32 entries (too many edges)",
            ));
        }
        Ok(grid)
    }

    #[inline(always)]
    fn centre(&self, i: usize, j: usize) -> Point {
        [
            self.min[0] + (i as f64 + 0.5) * self.cell[0],
            self.min[1] + (j as f64 + 0.5) * self.cell[1],
        ]
    }

    #[inline(always)]
    fn sub_centre(&self, i: usize, j: usize, si: usize, sj: usize) -> Point {
        [
            (self.min[0] + i as f64 * self.cell[0]) + (si as f64 + 0.5) * self.sub_cell[0],
            (self.min[1] + j as f64 * self.cell[1]) + (sj as f64 + 0.5) * self.sub_cell[1],
        ]
    }

    /// `Some(on land)`, or `None` when the walk is degenerate and the caller must count
    /// exactly.
    #[inline(always)]
    fn contains(&self, edges: &[Edge], p: Point) -> Option<bool> {
        // Clamped into the grid (NaN → 0). A point outside the box lands in a border cell:
        // an edge-free border cell is water (land reaching the box's side has an edge
        // there), so only edge cells need the box test.
        let i = ((p[0] - self.min[0]) * self.inv_cell[0]).max(0.0).min(self.last[0]) as u32 as usize;
        let j = ((p[1] - self.min[1]) * self.inv_cell[1]).max(0.0).min(self.last[1]) as u32 as usize;
        let c = j * self.nx + i;
        // Most cells of a coastline's box hold no edge: two bits answer.
        let kind = (self.kinds[c / 32] >> (2 * (c % 32))) & 3;
        if kind != EDGES {
            return Some(kind == LAND);
        }
        let in_box = (p[0] >= self.min[0]) & (p[0] <= self.max[0]) & (p[1] >= self.min[1]) & (p[1] <= self.max[1]);
        if !in_box {
            return Some(false);
        }
        let mut slot = self.slots[c];
        let centre;
        let tol;
        if slot.meta & SUBDIVIDED != 0 {
            let x0 = self.min[0] + i as f64 * self.cell[0];
            let y0 = self.min[1] + j as f64 * self.cell[1];
            let si = (((p[0] - x0) * self.inv_sub_cell[0]) as usize).min(self.split - 1);
            let sj = (((p[1] - y0) * self.inv_sub_cell[1]) as usize).min(self.split - 1);
            slot = self.sub_slots[slot.start as usize + sj * self.split + si];
            if slot.count() == 0 {
                return Some(slot.meta & CENTRE_ON_LAND != 0);
            }
            centre = self.sub_centre(i, j, si, sj);
            tol = self.sub_cell[1] * 1e-9;
        } else {
            centre = self.centre(i, j);
            tol = self.cell[1] * 1e-9;
        }
        walk(
            edges,
            &self.cell_edges[slot.range()],
            centre,
            slot.meta & CENTRE_ON_LAND != 0,
            p,
            tol,
        )
    }

    /// Exact even–odd count for `p`, using only the edges of its row (every edge that can
    /// cross the ray from `p` to +x) — the fallback for degenerate walks.
    fn contains_row_exact(&self, edges: &[Edge], p: Point) -> bool {
        let j = (((p[1] - self.min[1]) * self.inv_cell[1]) as usize).min(self.ny - 1);
        let row = &self.row_edges[self.row_start[j] as usize..self.row_start[j + 1] as usize];
        let mut inside = false;
        for &k in row {
            let e = &edges[k as usize];
            if e.touches(p) {
                return true;
            }
            if let Some(x) = e.crossing_x(p[1]) {
                inside ^= x > p[0];
            }
        }
        inside
    }
}

/// Parity walk inside one cell: from the cell centre (whose answer is known) horizontally
/// to (p.x, centre.y), then vertically to p, flipping once per edge crossed. The path stays
/// inside the cell, so the cell's edge list holds every edge it can cross. Branch-free over
/// the edges; `None` when an edge meets the path at a vertex or a leg's end (exact count
/// needed).
#[inline(always)]
fn walk(edges: &[Edge], list: &[u32], centre: Point, centre_on_land: bool, p: Point, tol: f64) -> Option<bool> {
    let (lo, hi) = if p[0] < centre[0] {
        (p[0], centre[0])
    } else {
        (centre[0], p[0])
    };
    let (ylo, yhi) = if p[1] < centre[1] {
        (p[1], centre[1])
    } else {
        (centre[1], p[1])
    };
    let mut flips = false;
    let mut touch = false;
    let mut degenerate = false;
    for &k in list {
        let e = &edges[k as usize];
        touch |= e.touches(p);
        // Horizontal leg, centre → (p.x, centre.y): the half-open rule of the row sweep.
        let crosses_h = (e.a[1] > centre[1]) != (e.b[1] > centre[1]);
        let x = e.a[0] + (centre[1] - e.a[1]) * (e.b[0] - e.a[0]) / (e.b[1] - e.a[1]);
        flips ^= crosses_h & (x > lo) & (x <= hi);
        // Vertical leg, (p.x, centre.y) → p.
        let (ax, bx) = (e.a[0], e.b[0]);
        let spans_leg = (e.a[1].max(e.b[1]) >= ylo) & (e.a[1].min(e.b[1]) <= yhi);
        degenerate |= spans_leg & ((ax == p[0]) | (bx == p[0]));
        let crosses_v = (ax > p[0]) != (bx > p[0]);
        let y = e.a[1] + (p[0] - ax) * (e.b[1] - e.a[1]) / (bx - ax);
        degenerate |= crosses_v & (((y - centre[1]).abs() <= tol) | ((y - p[1]).abs() <= tol));
        flips ^= crosses_v & (y > ylo) & (y < yhi);
    }
    if touch {
        Some(true)
    } else if degenerate {
        None
    } else {
        Some(centre_on_land != flips)
    }
}

fn segment_touches_box(e: &Edge, b: [f64; 4]) -> bool {
    if e.a[0].max(e.b[0]) < b[0] || e.a[0].min(e.b[0]) > b[2] || e.a[1].max(e.b[1]) < b[1] || e.a[1].min(e.b[1]) > b[3]
    {
        return false;
    }
    // The segment's line must not leave all four corners strictly on one side.
    let corners = [[b[0], b[1]], [b[2], b[1]], [b[2], b[3]], [b[0], b[3]]];
    let signs = corners.map(|c| orientation(e.a, e.b, c));
    !(signs.iter().all(|&s| s > 0.0) || signs.iter().all(|&s| s < 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, size: f64) -> Vec<Point> {
        vec![[x0, y0], [x0 + size, y0], [x0 + size, y0 + size], [x0, y0 + size]]
    }

    #[test]
    fn square_with_hole() {
        let mask = LandMask::new(vec![Polygon {
            shell: square(0.0, 0.0, 10.0),
            holes: vec![square(4.0, 4.0, 2.0)],
        }])
        .unwrap();
        assert!(mask.contains([1.0, 1.0]));
        assert!(!mask.contains([5.0, 5.0]));
        assert!(!mask.contains([11.0, 5.0]));
        assert!(mask.contains([0.0, 5.0]), "boundary is land");
        assert!(mask.contains([4.0, 5.0]), "hole boundary is land");
        assert!(mask.contains([10.0, 10.0]), "vertex is land");
    }

    #[test]
    fn orientation_and_closing_vertex_do_not_matter() {
        let mut cw = square(0.0, 0.0, 10.0);
        cw.reverse();
        cw.push(cw[0]);
        let mask = LandMask::new(vec![Polygon {
            shell: cw,
            holes: vec![],
        }])
        .unwrap();
        assert!(mask.contains([3.0, 3.0]));
        assert_eq!(mask.polygons()[0].shell.len(), 4);
    }

    #[test]
    fn index_agrees_with_exact_count_on_a_jagged_ring() {
        // A star with many spikes, queried on a dense lattice that hits vertex x's exactly.
        let n = 400;
        let shell: Vec<Point> = (0..n)
            .map(|k| {
                let t = k as f64 / n as f64 * std::f64::consts::TAU;
                let r = if k % 2 == 0 { 100.0 } else { 40.0 + (k % 7) as f64 };
                [r * t.cos(), r * t.sin()]
            })
            .collect();
        let mask = LandMask::new(vec![Polygon { shell, holes: vec![] }]).unwrap();
        let mut land = 0;
        for xi in -110..=110 {
            for yi in -110..=110 {
                let p = [xi as f64 * 1.0 + 0.25, yi as f64 * 1.0];
                let got = mask.contains(p);
                assert_eq!(got, contains_exact(mask.edges(), p), "at {p:?}");
                land += got as usize;
            }
        }
        assert!(land > 1000);
    }

    /// Integer vertices and integer queries put walks exactly through vertices (the exact
    /// row fallback); a dense zigzag makes cells split into sub-cells.
    #[test]
    fn index_agrees_with_exact_count_on_integer_coastline_with_split_cells() {
        // A comb: 400 teeth 0.25 wide and 40 tall on top of a 60-high block, plus a hole.
        let mut shell = vec![[0.0, 0.0], [100.0, 0.0]];
        for k in (0..400).rev() {
            let x = 0.25 * k as f64;
            shell.push([x + 0.25, 60.0]);
            shell.push([x + 0.125, 100.0]);
        }
        shell.push([0.0, 60.0]);
        let hole = vec![[10.0, 10.0], [30.0, 10.0], [30.0, 30.0], [10.0, 30.0]];
        let mask = LandMask::new(vec![Polygon {
            shell,
            holes: vec![hole],
        }])
        .unwrap();
        assert!(
            mask.grid.split > 0 && !mask.grid.sub_slots.is_empty(),
            "the comb should split cells"
        );
        let mut land = 0;
        for xi in -2..=402 {
            for yi in -2..=410 {
                let p = [xi as f64 * 0.25, yi as f64 * 0.25];
                let got = mask.contains(p);
                assert_eq!(got, contains_exact(mask.edges(), p), "at {p:?}");
                land += got as usize;
            }
        }
        assert!(land > 80_000, "{land}");
        for p in [
            [-1e9, 5.0],
            [5.0, 1e9],
            [1e300, -1e300],
            [f64::INFINITY, 5.0],
            [f64::NAN, 5.0],
            [5.0, f64::NAN],
        ] {
            assert!(!mask.contains(p), "{p:?}");
        }
    }

    #[test]
    fn invalid_polygons_are_rejected() {
        let bowtie = vec![[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 6.0]];
        let err = LandMask::new(vec![Polygon {
            shell: bowtie,
            holes: vec![],
        }])
        .unwrap_err();
        assert_eq!(err.argument(), "polygons");
        assert!(err.to_string().contains("cross"));
        let two = vec![[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]];
        assert!(LandMask::new(vec![Polygon {
            shell: two,
            holes: vec![]
        }])
        .unwrap_err()
        .to_string()
        .contains("3 distinct"));
        let line = vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
        assert!(LandMask::new(vec![Polygon {
            shell: line,
            holes: vec![]
        }])
        .unwrap_err()
        .to_string()
        .contains("zero area"));
        let touching_hole = Polygon {
            shell: square(0.0, 0.0, 10.0),
            holes: vec![square(0.0, 4.0, 2.0)],
        };
        assert!(LandMask::new(vec![touching_hole]).is_err());
        let outside_hole = Polygon {
            shell: square(0.0, 0.0, 10.0),
            holes: vec![square(20.0, 4.0, 2.0)],
        };
        assert!(LandMask::new(vec![outside_hole])
            .unwrap_err()
            .to_string()
            .contains("outside its shell"));
        let overlapping = vec![
            Polygon {
                shell: square(0.0, 0.0, 10.0),
                holes: vec![],
            },
            Polygon {
                shell: square(2.0, 2.0, 2.0),
                holes: vec![],
            },
        ];
        assert!(LandMask::new(overlapping)
            .unwrap_err()
            .to_string()
            .contains("lies on the land"));
        let nan = vec![[0.0, 0.0], [f64::NAN, 1.0], [2.0, 0.0]];
        assert!(LandMask::new(vec![Polygon {
            shell: nan,
            holes: vec![]
        }])
        .unwrap_err()
        .to_string()
        .contains("not finite"));
    }

    #[test]
    fn tiny_rings_are_valid_land() {
        for size in [1e-200, 1e-300, 5e-320, 2.0 * TINY] {
            let mask = LandMask::new(vec![Polygon {
                shell: vec![[0.0, 0.0], [size, 0.0], [0.0, size]],
                holes: vec![],
            }])
            .unwrap();
            assert_eq!(
                mask.polygons()[0].shell,
                vec![[0.0, 0.0], [size, 0.0], [0.0, size]],
                "world coordinates kept"
            );
            assert!(mask.contains([size / 4.0, size / 4.0]));
            assert!(mask.contains([size, 0.0]), "vertex is land");
            assert!(!mask.contains([0.75 * size, 0.75 * size]));
            assert!(!mask.contains([-size, 0.0]));
            assert!(!mask.contains([1.0, 1.0]) && !mask.contains([1e300, 0.0]));
        }
        let line = vec![[0.0, 0.0], [1e-200, 1e-200], [2e-200, 2e-200]];
        assert!(LandMask::new(vec![Polygon {
            shell: line,
            holes: vec![]
        }])
        .unwrap_err()
        .to_string()
        .contains("zero area"));
        // Next to a 1 km island a 1e-200 m rock cannot be represented: said so, not "zero area".
        let rock = Polygon {
            shell: vec![[0.0, 0.0], [1e-200, 0.0], [0.0, 1e-200]],
            holes: vec![],
        };
        let err = LandMask::new(vec![
            Polygon {
                shell: square(500.0, 500.0, 1000.0),
                holes: vec![],
            },
            rock,
        ])
        .unwrap_err();
        assert!(err.to_string().contains("too small"), "{err}");
    }

    #[test]
    fn huge_rings_are_valid_land() {
        for size in [1e160, 1e300, f64::MAX / 2.0, 2.0 * HUGE] {
            let mask = LandMask::new(vec![Polygon {
                shell: vec![[0.0, 0.0], [size, 0.0], [0.0, size]],
                holes: vec![],
            }])
            .unwrap();
            assert_eq!(
                mask.polygons()[0].shell,
                vec![[0.0, 0.0], [size, 0.0], [0.0, size]],
                "world coordinates kept"
            );
            assert!(mask.contains([size / 4.0, size / 4.0]));
            assert!(mask.contains([size, 0.0]), "vertex is land");
            assert!(!mask.contains([0.75 * size, 0.75 * size]));
            assert!(!mask.contains([-size, 0.0]) && !mask.contains([1.0, -1.0]));
        }
        let bowtie = vec![[0.0, 0.0], [1e300, 1e300], [1e300, 0.0], [0.0, 1e300]];
        assert!(LandMask::new(vec![Polygon {
            shell: bowtie,
            holes: vec![]
        }])
        .is_err());
    }

    #[test]
    fn island_in_a_lake_is_land() {
        let polygons = vec![
            Polygon {
                shell: square(0.0, 0.0, 10.0),
                holes: vec![square(2.0, 2.0, 6.0)],
            },
            Polygon {
                shell: square(4.0, 4.0, 2.0),
                holes: vec![],
            },
        ];
        let mask = LandMask::new(polygons).unwrap();
        assert!(mask.contains([5.0, 5.0]));
        assert!(!mask.contains([3.0, 3.0]));
        assert!(mask.contains([1.0, 1.0]));
    }
}
