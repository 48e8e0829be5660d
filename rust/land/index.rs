//! The containment index of a [`LandMask`](super::LandMask): the two-level grid the parent
//! module's docs describe, built once over the mask's validated edges (in the index frame),
//! and the per-point walk that answers from it.
//!
//! One file, though long: the build (the sweep that marks each cell centre) and the query
//! (the walk from a centre) share one cell layout and one half-open crossing rule, and
//! their answers agree only while both use them alike.

use super::{orientation, Edge, Point};
use crate::error::{ModelError, Result};
use crate::memory;

/// One cell of the index: `meta` = edge count << 2 | [`SUBDIVIDED`] | [`CENTRE_ON_LAND`].
/// A leaf's edges are `cell_edges[start..start + count]`; a subdivided cell's s × s
/// sub-cells are `sub_slots[start..start + s²]`.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Slot {
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

/// Two-level grid over the edges' bounding box (see the parent module's docs).
#[derive(Debug, Clone)]
pub(super) struct Grid {
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
    pub(super) split: usize,
    sub_cell: [f64; 2],
    inv_sub_cell: [f64; 2],
    pub(super) sub_slots: Vec<Slot>,
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
    pub(super) fn build(edges: &[Edge]) -> Result<Grid> {
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
    pub(super) fn contains(&self, edges: &[Edge], p: Point) -> Option<bool> {
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
    pub(super) fn contains_row_exact(&self, edges: &[Edge], p: Point) -> bool {
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
