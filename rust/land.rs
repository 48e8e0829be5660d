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
//! Containment index: a uniform grid over the mask's bounding box. Each cell lists the
//! edges that touch it and knows, from a sweep done once, whether its centre is on land.
//! A query walks from the cell centre to the point — horizontally, then vertically — and
//! flips the centre's answer once per edge crossed, so a cell costs its own few edges and
//! an empty cell costs nothing. Where the walk meets an edge exactly at a vertex (integer
//! coordinates do this) it falls back to the exact crossing count over all edges.

use crate::error::{ModelError, Result};
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
#[derive(Debug, Clone)]
pub struct LandMask {
    polygons: Vec<Polygon>,
    edges: Vec<Edge>,
    grid: Grid,
}

impl LandMask {
    /// Builds and validates a mask. `polygons` as given by the user: rings of (x, y).
    pub fn new(polygons: Vec<Polygon>) -> Result<Self> {
        if polygons.is_empty() {
            return Err(ModelError::invalid("polygons", "a land mask needs at least one polygon"));
        }
        let mut cleaned = Vec::with_capacity(polygons.len());
        let mut edges = Vec::new();
        // (polygon index, ring index within polygon, first edge, edge count) per ring.
        let mut rings = Vec::new();
        for (pi, polygon) in polygons.iter().enumerate() {
            let shell = clean_ring(&polygon.shell, pi, None)?;
            let mut holes = Vec::with_capacity(polygon.holes.len());
            for (hi, hole) in polygon.holes.iter().enumerate() {
                holes.push(clean_ring(hole, pi, Some(hi))?);
            }
            for (ri, ring) in std::iter::once(&shell).chain(holes.iter()).enumerate() {
                let first = edges.len();
                for k in 0..ring.len() {
                    edges.push(Edge { a: ring[k], b: ring[(k + 1) % ring.len()] });
                }
                rings.push((pi, ri, first, ring.len()));
            }
            cleaned.push(Polygon { shell, holes });
        }
        check_no_crossings(&edges, &rings)?;
        check_nesting(&cleaned)?;
        let grid = Grid::build(&edges);
        Ok(LandMask { polygons: cleaned, edges, grid })
    }

    pub fn polygons(&self) -> &[Polygon] {
        &self.polygons
    }

    pub(crate) fn edges(&self) -> &[Edge] {
        &self.edges
    }

    pub fn vertex_count(&self) -> usize {
        self.edges.len()
    }

    /// Whether `p` is on land (boundary included).
    #[inline]
    pub fn contains(&self, p: Point) -> bool {
        match self.grid.contains(&self.edges, p) {
            Some(inside) => inside,
            None => contains_exact(&self.edges, p),
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
    let mut out: Vec<Point> = Vec::with_capacity(ring.len());
    for (k, p) in ring.iter().enumerate() {
        if !p[0].is_finite() || !p[1].is_finite() {
            return Err(ModelError::invalid("polygons", format!("{name}: vertex {k} is not finite ({}, {})", p[0], p[1])));
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
        return Err(ModelError::invalid("polygons", format!("{name}: needs at least 3 distinct vertices, got {}", out.len())));
    }
    let area = signed_area(&out);
    if area == 0.0 || !area.is_finite() {
        return Err(ModelError::invalid("polygons", format!("{name}: has zero area (all vertices on a line)")));
    }
    Ok(out)
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
    let aabbs: Vec<Aabb> = edges.iter().map(Edge::aabb).collect();
    let bvh = Bvh::from_leaves(BvhBuildStrategy::default(), &aabbs);
    // Which ring each edge belongs to, and its position in the ring.
    let mut owner = vec![(0usize, 0usize, 0usize); edges.len()];
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
                orientation(p, shared, q) == 0.0 && ((q[0] - shared[0]) * (p[0] - shared[0]) + (q[1] - shared[1]) * (p[1] - shared[1])) > 0.0
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

fn ring_edges(ring: &[Point]) -> Vec<Edge> {
    (0..ring.len()).map(|k| Edge { a: ring[k], b: ring[(k + 1) % ring.len()] }).collect()
}

/// Holes inside their shell and not inside each other; no polygon on another's land.
/// Rings do not meet (checked before), so one vertex decides where a whole ring lies.
fn check_nesting(polygons: &[Polygon]) -> Result<()> {
    let land_edges: Vec<Vec<Edge>> = polygons
        .iter()
        .map(|p| {
            let mut e = ring_edges(&p.shell);
            for h in &p.holes {
                e.extend(ring_edges(h));
            }
            e
        })
        .collect();
    let bounds: Vec<[f64; 4]> = polygons.iter().map(|p| ring_bounds(&p.shell)).collect();
    for (pi, polygon) in polygons.iter().enumerate() {
        let shell_edges = ring_edges(&polygon.shell);
        for (hi, hole) in polygon.holes.iter().enumerate() {
            if !contains_exact(&shell_edges, hole[0]) {
                return Err(ModelError::invalid("polygons", format!("polygon {pi} hole {hi} lies outside its shell")));
            }
            for (hj, other) in polygon.holes.iter().enumerate() {
                if hj != hi && contains_exact(&ring_edges(other), hole[0]) {
                    return Err(ModelError::invalid("polygons", format!("polygon {pi} hole {hi} lies inside hole {hj}")));
                }
            }
        }
        let v = polygon.shell[0];
        for (pj, b) in bounds.iter().enumerate() {
            let in_box = v[0] >= b[0] && v[0] <= b[2] && v[1] >= b[1] && v[1] <= b[3];
            if pj != pi && in_box && contains_exact(&land_edges[pj], v) {
                return Err(ModelError::invalid("polygons", format!("polygon {pi} lies on the land of polygon {pj} (overlapping polygons: merge them)")));
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

/// Uniform grid over the edges' bounding box (see the module docs).
#[derive(Debug, Clone)]
struct Grid {
    min: Point,
    max: Point,
    cell: [f64; 2],
    inv_cell: [f64; 2],
    nx: usize,
    ny: usize,
    /// CSR: edges of cell c are `cell_edges[cell_start[c]..cell_start[c + 1]]`.
    cell_start: Vec<u32>,
    cell_edges: Vec<u32>,
    centre_on_land: Vec<bool>,
}

impl Grid {
    fn build(edges: &[Edge]) -> Grid {
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for e in edges {
            for p in [e.a, e.b] {
                min = [min[0].min(p[0]), min[1].min(p[1])];
                max = [max[0].max(p[0]), max[1].max(p[1])];
            }
        }
        // About two cells per edge keeps a cell's edge list short without a huge grid.
        let target_cells = (2 * edges.len()).clamp(16, 1 << 22) as f64;
        let (w, h) = ((max[0] - min[0]).max(f64::MIN_POSITIVE), (max[1] - min[1]).max(f64::MIN_POSITIVE));
        let nx = ((target_cells * w / h).sqrt().round() as usize).clamp(1, 1 << 14);
        let ny = ((target_cells / nx as f64).round() as usize).clamp(1, 1 << 14);
        let cell = [w / nx as f64, h / ny as f64];
        let inv_cell = [1.0 / cell[0], 1.0 / cell[1]];
        let mut grid = Grid { min, max, cell, inv_cell, nx, ny, cell_start: vec![], cell_edges: vec![], centre_on_land: vec![] };
        grid.register(edges);
        grid.sweep_centres(edges);
        grid
    }

    fn cell_of(&self, p: Point) -> (usize, usize) {
        let i = ((p[0] - self.min[0]) * self.inv_cell[0]).floor();
        let j = ((p[1] - self.min[1]) * self.inv_cell[1]).floor();
        ((i.max(0.0) as usize).min(self.nx - 1), (j.max(0.0) as usize).min(self.ny - 1))
    }

    fn cell_box(&self, i: usize, j: usize) -> [f64; 4] {
        let x0 = self.min[0] + i as f64 * self.cell[0];
        let y0 = self.min[1] + j as f64 * self.cell[1];
        [x0, y0, x0 + self.cell[0], y0 + self.cell[1]]
    }

    fn centre(&self, i: usize, j: usize) -> Point {
        [self.min[0] + (i as f64 + 0.5) * self.cell[0], self.min[1] + (j as f64 + 0.5) * self.cell[1]]
    }

    /// Lists each edge in every cell it touches (conservatively: boxes grown by a hair so
    /// rounding never loses an edge from a cell it passes through).
    fn register(&mut self, edges: &[Edge]) {
        let margin = [self.cell[0] * 1e-9, self.cell[1] * 1e-9];
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(edges.len() * 3);
        for (k, e) in edges.iter().enumerate() {
            let (i0, j0) = self.cell_of([e.a[0].min(e.b[0]) - margin[0], e.a[1].min(e.b[1]) - margin[1]]);
            let (i1, j1) = self.cell_of([e.a[0].max(e.b[0]) + margin[0], e.a[1].max(e.b[1]) + margin[1]]);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let b = self.cell_box(i, j);
                    let grown = [b[0] - margin[0], b[1] - margin[1], b[2] + margin[0], b[3] + margin[1]];
                    if segment_touches_box(e, grown) {
                        pairs.push(((j * self.nx + i) as u32, k as u32));
                    }
                }
            }
        }
        pairs.sort_unstable();
        let n_cells = self.nx * self.ny;
        self.cell_start = vec![0; n_cells + 1];
        for &(c, _) in &pairs {
            self.cell_start[c as usize + 1] += 1;
        }
        for c in 0..n_cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.cell_edges = pairs.into_iter().map(|(_, k)| k).collect();
    }

    /// Whether each cell centre is on land: one horizontal sweep per row of cells. Every
    /// edge crossing a row's centre line is listed in one of that row's cells.
    fn sweep_centres(&mut self, edges: &[Edge]) {
        self.centre_on_land = vec![false; self.nx * self.ny];
        let mut seen_in_row = vec![usize::MAX; edges.len()];
        let mut xs: Vec<f64> = Vec::new();
        for j in 0..self.ny {
            let y = self.centre(0, j)[1];
            xs.clear();
            for i in 0..self.nx {
                let c = j * self.nx + i;
                for &k in &self.cell_edges[self.cell_start[c] as usize..self.cell_start[c + 1] as usize] {
                    if seen_in_row[k as usize] != j {
                        seen_in_row[k as usize] = j;
                        if let Some(x) = edges[k as usize].crossing_x(y) {
                            xs.push(x);
                        }
                    }
                }
            }
            xs.sort_unstable_by(|a, b| a.total_cmp(b));
            // Even–odd: the centre is on land when an odd number of crossings lie right of it.
            let mut left = 0; // crossings with x <= centre x
            for i in 0..self.nx {
                let cx = self.centre(i, j)[0];
                while left < xs.len() && xs[left] <= cx {
                    left += 1;
                }
                self.centre_on_land[j * self.nx + i] = (xs.len() - left) % 2 == 1;
            }
        }
    }

    /// `Some(on land)`, or `None` when the walk is degenerate and the caller must use the
    /// exact count.
    #[inline]
    fn contains(&self, edges: &[Edge], p: Point) -> Option<bool> {
        if !(p[0] >= self.min[0] && p[0] <= self.max[0] && p[1] >= self.min[1] && p[1] <= self.max[1]) {
            return Some(false);
        }
        let (i, j) = self.cell_of(p);
        let c = j * self.nx + i;
        let centre_on_land = self.centre_on_land[c];
        let list = &self.cell_edges[self.cell_start[c] as usize..self.cell_start[c + 1] as usize];
        if list.is_empty() {
            return Some(centre_on_land);
        }
        let centre = self.centre(i, j);
        let (lo, hi) = if p[0] < centre[0] { (p[0], centre[0]) } else { (centre[0], p[0]) };
        let (ylo, yhi) = if p[1] < centre[1] { (p[1], centre[1]) } else { (centre[1], p[1]) };
        let tol = self.cell[1] * 1e-9;
        let mut flips = false;
        for &k in list {
            let e = &edges[k as usize];
            if e.touches(p) {
                return Some(true);
            }
            // Horizontal leg, centre → (p.x, centre.y): the same half-open rule the sweep used.
            if let Some(x) = e.crossing_x(centre[1]) {
                if x > lo && x <= hi {
                    flips = !flips;
                }
            }
            // Vertical leg, (p.x, centre.y) → p.
            let (ax, bx) = (e.a[0], e.b[0]);
            let spans_leg = e.a[1].max(e.b[1]) >= ylo && e.a[1].min(e.b[1]) <= yhi;
            if spans_leg && (ax == p[0] || bx == p[0]) {
                return None;
            }
            if (ax > p[0]) != (bx > p[0]) {
                let y = e.a[1] + (p[0] - ax) * (e.b[1] - e.a[1]) / (bx - ax);
                if (y - centre[1]).abs() <= tol || (y - p[1]).abs() <= tol {
                    return None;
                }
                if y > ylo && y < yhi {
                    flips = !flips;
                }
            }
        }
        Some(centre_on_land != flips)
    }
}

fn segment_touches_box(e: &Edge, b: [f64; 4]) -> bool {
    if e.a[0].max(e.b[0]) < b[0] || e.a[0].min(e.b[0]) > b[2] || e.a[1].max(e.b[1]) < b[1] || e.a[1].min(e.b[1]) > b[3] {
        return false;
    }
    // The segment's line must separate neither all four corners to one side.
    let corners = [[b[0], b[1]], [b[2], b[1]], [b[2], b[3]], [b[0], b[3]]];
    let signs: Vec<f64> = corners.iter().map(|&c| orientation(e.a, e.b, c)).collect();
    let all_pos = signs.iter().all(|&s| s > 0.0);
    let all_neg = signs.iter().all(|&s| s < 0.0);
    !(all_pos || all_neg)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, size: f64) -> Vec<Point> {
        vec![[x0, y0], [x0 + size, y0], [x0 + size, y0 + size], [x0, y0 + size]]
    }

    #[test]
    fn square_with_hole() {
        let mask = LandMask::new(vec![Polygon { shell: square(0.0, 0.0, 10.0), holes: vec![square(4.0, 4.0, 2.0)] }]).unwrap();
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
        let mask = LandMask::new(vec![Polygon { shell: cw, holes: vec![] }]).unwrap();
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

    #[test]
    fn invalid_polygons_are_rejected() {
        let bowtie = vec![[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 6.0]];
        let err = LandMask::new(vec![Polygon { shell: bowtie, holes: vec![] }]).unwrap_err();
        assert_eq!(err.argument(), "polygons");
        assert!(err.to_string().contains("cross"));
        let two = vec![[0.0, 0.0], [1.0, 1.0], [0.0, 0.0]];
        assert!(LandMask::new(vec![Polygon { shell: two, holes: vec![] }]).unwrap_err().to_string().contains("3 distinct"));
        let line = vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
        assert!(LandMask::new(vec![Polygon { shell: line, holes: vec![] }]).unwrap_err().to_string().contains("zero area"));
        let touching_hole = Polygon { shell: square(0.0, 0.0, 10.0), holes: vec![square(0.0, 4.0, 2.0)] };
        assert!(LandMask::new(vec![touching_hole]).is_err());
        let outside_hole = Polygon { shell: square(0.0, 0.0, 10.0), holes: vec![square(20.0, 4.0, 2.0)] };
        assert!(LandMask::new(vec![outside_hole]).unwrap_err().to_string().contains("outside its shell"));
        let overlapping = vec![
            Polygon { shell: square(0.0, 0.0, 10.0), holes: vec![] },
            Polygon { shell: square(2.0, 2.0, 2.0), holes: vec![] },
        ];
        assert!(LandMask::new(overlapping).unwrap_err().to_string().contains("lies on the land"));
        let nan = vec![[0.0, 0.0], [f64::NAN, 1.0], [2.0, 0.0]];
        assert!(LandMask::new(vec![Polygon { shell: nan, holes: vec![] }]).unwrap_err().to_string().contains("not finite"));
    }

    #[test]
    fn island_in_a_lake_is_land() {
        let polygons = vec![
            Polygon { shell: square(0.0, 0.0, 10.0), holes: vec![square(2.0, 2.0, 6.0)] },
            Polygon { shell: square(4.0, 4.0, 2.0), holes: vec![] },
        ];
        let mask = LandMask::new(polygons).unwrap();
        assert!(mask.contains([5.0, 5.0]));
        assert!(!mask.contains([3.0, 3.0]));
        assert!(mask.contains([1.0, 1.0]));
    }
}
