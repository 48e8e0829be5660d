//! The λ kernel, four detections at a time: factor by factor over a chunk of detections,
//! written once over [`Lanes`]; [`crate::simd::dispatch`] picks the CPU's build. It gives
//! the bits of [`ClutterModel::at_one`] (tested for every backend).

use super::{is_density, read_map, ClutterFactor, ClutterModel};
use crate::pose::Pose;
use crate::simd::{LaneKernel, Lanes};

/// λ of detections `first..first + out.len()`: factor by factor over the whole chunk, four detections at a time — each pass a tight loop with no branch on
/// the factor kind — and a last partial block (< 4) through [`ClutterModel::at_one`], whose
/// bits the passes reproduce. The index (in `out`) of the first detection without a finite
/// λ > 0.
pub(super) struct Densities<'a> {
    pub model: &'a ClutterModel,
    pub pose: &'a Pose,
    /// World positions, (M, 2) rows (x, y), or (M, 3) rows (x, y, z) of detections with a
    /// height (slant ranges and elevations).
    pub positions: &'a [f64],
    /// 2 or 3: the columns of `positions`.
    pub ncols: usize,
    pub metadata: &'a [f64],
    pub ranges: Option<&'a [f64]>,
    pub first: usize,
    pub out: &'a mut [f64],
}

impl LaneKernel for Densities<'_> {
    type Output = Option<usize>;

    #[inline(always)]
    fn run<L: Lanes>(self) -> Option<usize> {
        if self.ncols == 3 {
            self.run_with::<L, true>()
        } else {
            self.run_with::<L, false>()
        }
    }
}

impl Densities<'_> {
    /// The kernel for rows of 2 columns, or of 3 (`RAISED`), fixed at compile time.
    #[inline(always)]
    fn run_with<L: Lanes, const RAISED: bool>(self) -> Option<usize> {
        let Densities {
            model,
            pose,
            positions,
            ncols,
            metadata,
            ranges,
            first,
            out,
        } = self;
        let k = model.metadata_columns;
        let full = out.len() / 4 * 4;
        // (a λ below the smallest normal double is refused: 1/λ would overflow)
        let (one, nan, normal) = (L::splat(1.0), L::splat(f64::NAN), L::splat(f64::MIN_POSITIVE));
        let (ox, oy, oz) = (L::splat(pose.x), L::splat(pose.y), L::splat(pose.z));
        // Exact-size chunks, so the loads need no bounds checks. (No closure returns lanes
        // here: it would be compiled outside the AVX2 function.)
        let xy = &positions[ncols * first..ncols * (first + full)];
        let block = 4 * ncols;
        let rows = &metadata[k * first..k * (first + full)];
        // λ starts at 1 (NaN where a position the bands read is not finite): in a pass of
        // its own, or, when the first factor is a range factor, in that factor's pass.
        let fused_start = matches!(model.factors.first(), Some(ClutterFactor::Range(_)));
        if !fused_start {
            if model.uses_position {
                for (o, p) in out[..full].chunks_exact_mut(4).zip(xy.chunks_exact(block)) {
                    let (x, y, dz) = place::<L, RAISED>(p, oz);
                    let bad_position = L::or(L::or(x.non_finite(), y.non_finite()), dz.non_finite());
                    L::select(bad_position, nan, one).store(o);
                }
            } else {
                out[..full].fill(1.0);
            }
        }
        // Detections without a finite λ > 0, noted in the last factor's pass.
        let mut bad = L::none();
        let last = model.factors.len().wrapping_sub(1);
        for (i, f) in model.factors.iter().enumerate() {
            let blocks = out[..full].chunks_exact_mut(4);
            let checks = i == last;
            match f {
                ClutterFactor::Constant(v) => {
                    let v = L::splat(*v);
                    for o in blocks {
                        let density = L::load(o) * v;
                        if checks {
                            bad = L::or(bad, L::or(density.non_finite(), density.lt(normal)));
                        }
                        density.store(o);
                    }
                }
                ClutterFactor::Range(bands) => {
                    let fresh = i == 0 && fused_start;
                    // (a lone edge, a range limit say, kept in registers for the pass)
                    let one_edge = bands.one_root_edge();
                    for ((j, o), p) in blocks.enumerate().zip(xy.chunks_exact(block)) {
                        let (x, y, dz) = place::<L, RAISED>(p, oz);
                        let (dx, dy) = (x - ox, y - oy);
                        let squared = if RAISED {
                            dx * dx + dy * dy + dz * dz
                        } else {
                            dx * dx + dy * dy
                        };
                        // With measured ranges the bands read a range; without, the squared
                        // range through their root thresholds: the same bits, no square root.
                        let value = match ranges {
                            Some(measured) => {
                                let measured = L::load(&measured[first + 4 * j..]);
                                bands.lanes_at(L::select(measured.is_nan(), squared.sqrt(), measured))
                            }
                            None => match one_edge {
                                Some(edge) => edge.lanes_at_squared(squared),
                                None => bands.lanes_at_root(squared),
                            },
                        };
                        let before = if fresh {
                            L::select(L::or(L::or(x.non_finite(), y.non_finite()), dz.non_finite()), nan, one)
                        } else {
                            L::load(o)
                        };
                        let density = before * value;
                        if checks {
                            bad = L::or(bad, L::or(density.non_finite(), density.lt(normal)));
                        }
                        density.store(o);
                    }
                }
                ClutterFactor::Map(map) => {
                    // a gather per detection: the map is read once for the whole pass
                    let map = read_map(map);
                    for ((j, o), p) in blocks.enumerate().zip(xy.chunks_exact(block)) {
                        let at = |i: usize| {
                            // (a map is of the plane: a 3-D detection's range is a slant one)
                            let measured = match ranges {
                                Some(r) if !RAISED => r[first + 4 * j + i],
                                _ => f64::NAN,
                            };
                            map.value_at(pose, p[ncols * i], p[ncols * i + 1], measured)
                        };
                        let density = L::load(o) * L::from_array([at(0), at(1), at(2), at(3)]);
                        if checks {
                            bad = L::or(bad, L::or(density.non_finite(), density.lt(normal)));
                        }
                        density.store(o);
                    }
                }
                ClutterFactor::Elevation(sector) => {
                    for (o, p) in blocks.zip(xy.chunks_exact(block)) {
                        let (x, y, dz) = place::<L, RAISED>(p, oz);
                        let (dx, dy) = (x - ox, y - oy);
                        let density = L::load(o) * sector.lanes_at(dz, dx * dx + dy * dy + dz * dz);
                        if checks {
                            bad = L::or(bad, L::or(density.non_finite(), density.lt(normal)));
                        }
                        density.store(o);
                    }
                }
                ClutterFactor::Coast(_) | ClutterFactor::Zone(_) => {
                    for (o, p) in blocks.zip(xy.chunks_exact(block)) {
                        let at = |i: usize| f.point_value(pose, p[ncols * i], p[ncols * i + 1]);
                        let density = L::load(o) * L::from_array([at(0), at(1), at(2), at(3)]);
                        if checks {
                            bad = L::or(bad, L::or(density.non_finite(), density.lt(normal)));
                        }
                        density.store(o);
                    }
                }
                ClutterFactor::Metadata(rule) => {
                    let (threshold, below, above) = (
                        L::splat(rule.threshold),
                        L::splat(rule.below),
                        L::splat(rule.at_or_above),
                    );
                    let missing = L::splat(rule.missing.unwrap_or(f64::NAN));
                    for (o, r) in blocks.zip(rows.chunks_exact(4 * k)) {
                        let value = if k == 1 {
                            L::load(r)
                        } else {
                            let at = |i: usize| r[i * k + rule.column];
                            L::from_array([at(0), at(1), at(2), at(3)])
                        };
                        let known = L::select(value.lt(threshold), below, above);
                        let finite = L::select(value.non_finite(), nan, known);
                        let density = L::load(o) * L::select(value.is_nan(), missing, finite);
                        if checks {
                            bad = L::or(bad, L::or(density.non_finite(), density.lt(normal)));
                        }
                        density.store(o);
                    }
                }
            }
        }
        if model.factors.is_empty() {
            for o in out[..full].chunks_exact(4) {
                let density = L::load(o);
                bad = L::or(bad, L::or(density.non_finite(), density.lt(normal)));
            }
        }
        for (i, density) in out.iter_mut().enumerate().skip(full) {
            let row = first + i;
            let measured = ranges.map_or(f64::NAN, |r| r[row]);
            *density = model.at_one(
                pose,
                [positions[ncols * row], positions[ncols * row + 1]],
                RAISED.then(|| positions[3 * row + 2]),
                &metadata[row * k..(row + 1) * k],
                measured,
            );
        }
        if !L::any(bad) && out[full..].iter().all(|v| is_density(*v)) {
            return None;
        }
        out.iter().position(|v| !is_density(*v))
    }
}

/// x, y and z − z_sensor of a block's four detections: from (x, y) pairs (dz 0: the same bits,
/// as the scalar reference adds dz² = 0), or from (x, y, z) rows.
#[inline(always)]
fn place<L: Lanes, const RAISED: bool>(p: &[f64], oz: L) -> (L, L, L) {
    if RAISED {
        let (x, y, z) = L::triples(p);
        (x, y, z - oz)
    } else {
        let (x, y) = L::pairs(p);
        (x, y, L::splat(0.0))
    }
}
