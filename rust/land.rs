//! Land mask: polygons (shell + holes) in world coordinates; a point on land, boundary
//! included, gets P_D 0.
//!
//! Rings may be given in any orientation, closed (last vertex repeating the first) or
//! not; consecutive duplicate vertices are dropped. A mask is validated once when built:
//! every ring has ≥ 3 distinct vertices and non-zero area, no two edges cross or touch
//! (except neighbours at their shared vertex), holes lie inside their shell, and no polygon
//! lies on another's land. With those guarantees "on land" is the even–odd rule over all
//! rings, which is what the index below evaluates. The checks are in `land/validation.rs`.
//!
//! Containment index (`land/index.rs`): a two-level grid over the mask's bounding box. Each
//! cell lists the edges that touch it and knows, from a sweep done once, whether its centre
//! is on land. A query walks from the cell centre to the point — horizontally, then
//! vertically — and flips the centre's answer once per edge crossed, so a cell costs its own
//! few edges. Two bits per level-0 cell (water / land / has edges) answer the common
//! edge-free cells from a table that stays in L1. Cells with more than a few edges are split
//! once into s × s sub-cells (s the same for all, chosen within a memory budget of a few
//! sub-cells per edge), so folded or jagged coastlines keep short lists. Where the walk meets
//! an edge exactly at a vertex (integer coordinates do this) the query falls back to the
//! exact crossing count over the edges of the point's row of cells.

use crate::error::{ModelError, Result};
use crate::memory;
use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::Vector;

mod index;
mod validation;
use index::Grid;
use validation::{check_nesting, check_no_crossings, clean_ring};

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
            let shell = clean_ring(&polygon.shell, pi, 0)?;
            let mut holes = memory::with_room("polygons", polygon.holes.len())?;
            for (hi, hole) in polygon.holes.iter().enumerate() {
                holes.push(clean_ring(hole, pi, hi + 1)?);
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

#[cfg(test)]
mod tests;
