//! Clutter spatial density λ(z; S): a product of factors evaluated per detection.
//!
//! Factors: constants, range bands over the detection's range from the sensor, threshold
//! rules on one column of detection metadata (the paper's lidar: segment `area < 10` →
//! 1e-1, otherwise 1e-3), and learned clutter maps ([`ClutterMap`], shared with the
//! estimator that updates them between scans). λ is a density in the detection's measurement
//! space, so it must be strictly positive: trackers divide by it.

use crate::batch::for_each_chunk;
use crate::clutter_map::ClutterMap;
use crate::coast::CoastalBand;
use crate::error::{ModelError, Result};
use crate::pose::Pose;
use crate::range_bands::RangeBands;
use crate::simd::{dispatch, LaneKernel, Lanes};
use std::sync::{Arc, RwLock, RwLockReadGuard};

/// λ factor from one metadata column: `below` when value < threshold, `at_or_above`
/// otherwise; `missing` (if given) when the detection has no such metadata (NaN).
#[derive(Debug, Clone, PartialEq)]
pub struct MetadataThreshold {
    pub column: usize,
    pub threshold: f64,
    pub below: f64,
    pub at_or_above: f64,
    pub missing: Option<f64>,
}

/// A learned map, shared between the models that read it and the estimator that updates it.
pub type SharedMap = Arc<RwLock<ClutterMap>>;

/// Reads a shared map (a panic while it was being written cannot have left it half-updated:
/// [`ClutterMap::update`] checks its inputs before changing anything).
pub fn read_map(map: &SharedMap) -> RwLockReadGuard<'_, ClutterMap> {
    map.read().unwrap_or_else(|poisoned| poisoned.into_inner())
}

#[derive(Debug, Clone)]
pub enum ClutterFactor {
    Constant(f64),
    Range(RangeBands),
    Metadata(MetadataThreshold),
    /// λ from the map as it stands when the model is evaluated.
    Map(SharedMap),
    /// A band along the coastline (seen from the sensor) with a higher λ.
    Coast(Arc<CoastalBand>),
}

impl PartialEq for ClutterFactor {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (ClutterFactor::Constant(a), ClutterFactor::Constant(b)) => a == b,
            (ClutterFactor::Range(a), ClutterFactor::Range(b)) => a == b,
            (ClutterFactor::Metadata(a), ClutterFactor::Metadata(b)) => a == b,
            (ClutterFactor::Map(a), ClutterFactor::Map(b)) => Arc::ptr_eq(a, b),
            (ClutterFactor::Coast(a), ClutterFactor::Coast(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct ClutterModel {
    factors: Vec<ClutterFactor>,
    metadata_columns: usize,
    uses_position: bool,
}

/// Whether `v` can be a clutter density: finite and at least the smallest normal double
/// (a product that underflowed to a subnormal would make 1/λ infinite).
#[inline]
fn is_density(v: f64) -> bool {
    v.is_finite() && v >= f64::MIN_POSITIVE
}

fn check_density(i: usize, v: f64) -> Result<()> {
    if !is_density(v) {
        return Err(ModelError::invalid(
            "factors",
            format!("factor {i} holds {v:e}, but clutter densities must be finite and > 0, at least {:e} (trackers divide by them)", f64::MIN_POSITIVE),
        ));
    }
    Ok(())
}

impl ClutterModel {
    pub fn new(factors: Vec<ClutterFactor>) -> Result<Self> {
        let mut metadata_columns = 0;
        let mut uses_position = false;
        for (i, f) in factors.iter().enumerate() {
            match f {
                ClutterFactor::Constant(v) => check_density(i, *v)?,
                // its values are posterior means with a prior > 0: finite and > 0
                ClutterFactor::Map(_) | ClutterFactor::Coast(_) => uses_position = true,
                ClutterFactor::Range(b) => {
                    uses_position = true;
                    for &v in b.values() {
                        check_density(i, v)?;
                    }
                }
                ClutterFactor::Metadata(rule) => {
                    if !rule.threshold.is_finite() {
                        return Err(ModelError::invalid(
                            "threshold",
                            format!("must be finite, got {}", rule.threshold),
                        ));
                    }
                    for v in [rule.below, rule.at_or_above].into_iter().chain(rule.missing) {
                        check_density(i, v)?;
                    }
                    let columns = rule.column.checked_add(1).ok_or_else(|| {
                        ModelError::invalid("column", format!("metadata column {} is out of range", rule.column))
                    })?;
                    metadata_columns = metadata_columns.max(columns);
                }
            }
        }
        Ok(ClutterModel {
            factors,
            metadata_columns,
            uses_position,
        })
    }

    /// How many metadata columns the caller must pass.
    pub fn metadata_columns(&self) -> usize {
        self.metadata_columns
    }

    /// Whether λ depends on where the detection is (so positions must be finite).
    pub fn uses_position(&self) -> bool {
        self.uses_position
    }

    /// λ for M detections: world `positions` (M, 2) row-major and `metadata`
    /// (M, metadata_columns) row-major with NaN for "not present".
    pub fn evaluate(&self, pose: &Pose, positions: &[f64], metadata: &[f64], out: &mut [f64]) -> Result<()> {
        self.evaluate_with_ranges(pose, positions, metadata, None, out)
    }

    /// As [`evaluate`](Self::evaluate), with the range bands read at `ranges[i]` where it is
    /// not NaN: a bearing–range sensor's measured range, so band edges are exact instead of
    /// depending on the polar → Cartesian → range round trip (which can land an ulp short).
    pub fn evaluate_with_ranges(
        &self,
        pose: &Pose,
        positions: &[f64],
        metadata: &[f64],
        ranges: Option<&[f64]>,
        out: &mut [f64],
    ) -> Result<()> {
        let m = out.len();
        if positions.len() != 2 * m {
            return Err(ModelError::shape(
                "positions",
                format!("must be ({m}, 2), got {} values", positions.len()),
            ));
        }
        if let Some(r) = ranges {
            if r.len() != m {
                return Err(ModelError::shape(
                    "ranges",
                    format!("must have {m} entries, got {}", r.len()),
                ));
            }
            if let Some(row) = r.iter().position(|v| v.is_infinite() || *v < 0.0) {
                return Err(ModelError::non_finite(
                    "ranges",
                    row,
                    "range is infinite or negative (NaN = use the position)",
                ));
            }
        }
        let k = self.metadata_columns;
        if metadata.len() != k * m {
            return Err(ModelError::shape(
                "metadata",
                format!("must be ({m}, {k}), got {} values", metadata.len()),
            ));
        }
        // The first row that cannot be evaluated; what is wrong with it, from its inputs and
        // the density the kernel left in `out`.
        let bad = for_each_chunk(out, |first, chunk| {
            dispatch(Densities {
                model: self,
                pose,
                positions,
                metadata,
                ranges,
                first,
                out: chunk,
            })
        });
        if let Some(row) = bad {
            let (argument, message) = self.problem(positions, metadata, row, out[row]);
            return Err(ModelError::non_finite(argument, row, message));
        }
        Ok(())
    }

    /// λ of one detection at (x, y) with its metadata row and measured range (NaN: none),
    /// one factor after another: the readable reference the lane kernel must match bit for
    /// bit. NaN when the detection cannot be evaluated.
    pub fn at_one(&self, pose: &Pose, [x, y]: [f64; 2], metadata: &[f64], measured: f64) -> f64 {
        let range = if measured.is_nan() {
            ((x - pose.x).powi(2) + (y - pose.y).powi(2)).sqrt()
        } else {
            measured
        };
        let mut density = if self.uses_position && !(x.is_finite() && y.is_finite()) {
            f64::NAN
        } else {
            1.0
        };
        for f in &self.factors {
            density *= match f {
                ClutterFactor::Constant(v) => *v,
                ClutterFactor::Range(bands) => bands.at(range),
                ClutterFactor::Map(map) => read_map(map).value_at(pose, x, y, measured),
                ClutterFactor::Coast(band) => band.value_at([pose.x, pose.y], x, y),
                ClutterFactor::Metadata(rule) => {
                    let value = metadata[rule.column];
                    if value.is_nan() {
                        rule.missing.unwrap_or(f64::NAN)
                    } else if value.is_infinite() {
                        // ±inf (an overflowed value) would pass as "at or above".
                        f64::NAN
                    } else if value < rule.threshold {
                        rule.below
                    } else {
                        rule.at_or_above
                    }
                }
            };
        }
        density
    }

    /// Why row `row` has no finite density > 0 (every factor value is one, so it could not
    /// be evaluated, or the product under/overflowed).
    fn problem(&self, positions: &[f64], metadata: &[f64], row: usize, density: f64) -> (&'static str, String) {
        let (x, y) = (positions[2 * row], positions[2 * row + 1]);
        if self.uses_position && !(x.is_finite() && y.is_finite()) {
            return ("positions", "position is NaN or infinite".to_string());
        }
        let k = self.metadata_columns;
        let metadata_problem = self.factors.iter().find_map(|f| match f {
            ClutterFactor::Metadata(rule) => {
                let value = metadata[row * k + rule.column];
                if value.is_infinite() {
                    Some(format!(
                        "metadata column {} is {value}; values must be finite (NaN = missing)",
                        rule.column
                    ))
                } else if rule.missing.is_none() && value.is_nan() {
                    Some(format!(
                        "metadata column {} is missing and the rule has no `missing` value",
                        rule.column
                    ))
                } else {
                    None
                }
            }
            _ => None,
        });
        match metadata_problem {
            Some(message) => ("metadata", message),
            None => ("factors", format!("the product of the clutter factors is {density:e}, not a finite density >= {:e} (factors too small or too large)", f64::MIN_POSITIVE)),
        }
    }
}

/// λ of detections `first..first + out.len()`: factor by factor over the whole chunk, four detections at a time — each pass a tight loop with no branch on
/// the factor kind — and a last partial block (< 4) through [`ClutterModel::at_one`], whose
/// bits the passes reproduce. The index (in `out`) of the first detection without a finite
/// λ > 0.
struct Densities<'a> {
    model: &'a ClutterModel,
    pose: &'a Pose,
    positions: &'a [f64],
    metadata: &'a [f64],
    ranges: Option<&'a [f64]>,
    first: usize,
    out: &'a mut [f64],
}

impl LaneKernel for Densities<'_> {
    type Output = Option<usize>;

    #[inline(always)]
    fn run<L: Lanes>(self) -> Option<usize> {
        let Densities {
            model,
            pose,
            positions,
            metadata,
            ranges,
            first,
            out,
        } = self;
        let k = model.metadata_columns;
        let full = out.len() / 4 * 4;
        // (a λ below the smallest normal double is refused: 1/λ would overflow)
        let (one, nan, normal) = (L::splat(1.0), L::splat(f64::NAN), L::splat(f64::MIN_POSITIVE));
        let (ox, oy) = (L::splat(pose.x), L::splat(pose.y));
        // Exact-size chunks, so the loads need no bounds checks. (No closure returns lanes
        // here: it would be compiled outside the AVX2 function.)
        let xy = &positions[2 * first..2 * (first + full)];
        let rows = &metadata[k * first..k * (first + full)];
        // λ starts at 1 (NaN where a position the bands read is not finite): in a pass of
        // its own, or, when the first factor is a range factor, in that factor's pass.
        let fused_start = matches!(model.factors.first(), Some(ClutterFactor::Range(_)));
        if !fused_start {
            if model.uses_position {
                for (o, p) in out[..full].chunks_exact_mut(4).zip(xy.chunks_exact(8)) {
                    let (x, y) = L::pairs(p);
                    L::select(L::or(x.non_finite(), y.non_finite()), nan, one).store(o);
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
                    for ((j, o), p) in blocks.enumerate().zip(xy.chunks_exact(8)) {
                        let (x, y) = L::pairs(p);
                        let (dx, dy) = (x - ox, y - oy);
                        let squared = dx * dx + dy * dy;
                        // With measured ranges the bands read a range; without, the squared
                        // range through their root thresholds: the same bits, no square root.
                        let value = match ranges {
                            Some(measured) => {
                                let measured = L::load(&measured[first + 4 * j..]);
                                bands.lanes_at(L::select(measured.is_nan(), squared.sqrt(), measured))
                            }
                            None => bands.lanes_at_root(squared),
                        };
                        let before = if fresh {
                            L::select(L::or(x.non_finite(), y.non_finite()), nan, one)
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
                    for ((j, o), p) in blocks.enumerate().zip(xy.chunks_exact(8)) {
                        let at = |i: usize| {
                            let measured = ranges.map_or(f64::NAN, |r| r[first + 4 * j + i]);
                            map.value_at(pose, p[2 * i], p[2 * i + 1], measured)
                        };
                        let density = L::load(o) * L::from_array([at(0), at(1), at(2), at(3)]);
                        if checks {
                            bad = L::or(bad, L::or(density.non_finite(), density.lt(normal)));
                        }
                        density.store(o);
                    }
                }
                ClutterFactor::Coast(band) => {
                    for (o, p) in blocks.zip(xy.chunks_exact(8)) {
                        let at = |i: usize| band.value_at([pose.x, pose.y], p[2 * i], p[2 * i + 1]);
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
                [positions[2 * row], positions[2 * row + 1]],
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_metadata_column_beyond_usize_is_an_error_not_an_overflow() {
        let rule = MetadataThreshold {
            column: usize::MAX,
            threshold: 10.0,
            below: 1e-1,
            at_or_above: 1e-3,
            missing: None,
        };
        assert!(ClutterModel::new(vec![ClutterFactor::Metadata(rule)]).is_err());
    }

    #[test]
    fn measured_ranges_take_the_place_of_the_position_range() {
        let bands = RangeBands::new(vec![1000.0], vec![1e-3, 1e-2], vec![true]).unwrap();
        let model = ClutterModel::new(vec![ClutterFactor::Range(bands)]).unwrap();
        let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
        // positions an ulp short of the edge; the measured range is exactly on it
        let short = 1000.0f64.next_down();
        let positions = [short, 0.0, short, 0.0, short, 0.0];
        let mut out = [0.0; 3];
        model
            .evaluate_with_ranges(&pose, &positions, &[], Some(&[1000.0, f64::NAN, 999.0]), &mut out)
            .unwrap();
        assert_eq!(out, [1e-2, 1e-3, 1e-3]);
        let err = model
            .evaluate_with_ranges(&pose, &positions, &[], Some(&[f64::INFINITY, 0.0, 0.0]), &mut out)
            .unwrap_err();
        assert_eq!(
            err,
            ModelError::non_finite("ranges", 0, "range is infinite or negative (NaN = use the position)")
        );
        // a negative measured range is no range: refused, naming its row
        let err = model
            .evaluate_with_ranges(&pose, &positions, &[], Some(&[0.0, -1.0, f64::NAN]), &mut out)
            .unwrap_err();
        assert_eq!(
            err,
            ModelError::non_finite("ranges", 1, "range is infinite or negative (NaN = use the position)")
        );
        assert!(model
            .evaluate_with_ranges(&pose, &positions, &[], Some(&[1.0]), &mut out)
            .is_err());
    }

    #[test]
    fn paper_lidar_area_rule() {
        let model = ClutterModel::new(vec![ClutterFactor::Metadata(MetadataThreshold {
            column: 0,
            threshold: 10.0,
            below: 1e-1,
            at_or_above: 1e-3,
            missing: None,
        })])
        .unwrap();
        let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
        let mut out = [0.0; 3];
        model
            .evaluate(&pose, &[0.0; 6], &[9.99, 10.0, 250.0], &mut out)
            .unwrap();
        assert_eq!(out, [1e-1, 1e-3, 1e-3]);
        let err = model
            .evaluate(&pose, &[0.0; 6], &[9.99, f64::NAN, 250.0], &mut out)
            .unwrap_err();
        assert_eq!(
            err,
            ModelError::non_finite(
                "metadata",
                1,
                "metadata column 0 is missing and the rule has no `missing` value"
            )
        );
    }

    #[test]
    fn infinite_metadata_is_an_error_naming_metadata() {
        let rule = MetadataThreshold {
            column: 0,
            threshold: 10.0,
            below: 1e-1,
            at_or_above: 1e-3,
            missing: Some(1.0),
        };
        let model = ClutterModel::new(vec![ClutterFactor::Metadata(rule)]).unwrap();
        let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
        let mut out = [0.0; 3];
        for bad in [f64::INFINITY, f64::NEG_INFINITY] {
            let err = model
                .evaluate(&pose, &[0.0; 6], &[1.0, f64::NAN, bad], &mut out)
                .unwrap_err();
            assert_eq!(
                err,
                ModelError::non_finite(
                    "metadata",
                    2,
                    format!("metadata column 0 is {bad}; values must be finite (NaN = missing)")
                )
            );
        }
    }

    #[test]
    fn paper_radar_range_rule() {
        let model = ClutterModel::new(vec![ClutterFactor::Range(
            RangeBands::new(vec![1000.0], vec![1e-3, 1e-2], vec![true]).unwrap(),
        )])
        .unwrap();
        let pose = Pose::new(10.0, 10.0, 0.0).unwrap();
        let mut out = [0.0; 3];
        model
            .evaluate(&pose, &[10.0, 1009.0, 10.0, 1010.0, 1010.0, 10.0], &[], &mut out)
            .unwrap();
        assert_eq!(out, [1e-3, 1e-2, 1e-2]);
    }

    #[test]
    fn zero_or_negative_density_is_rejected() {
        assert!(ClutterModel::new(vec![ClutterFactor::Constant(0.0)]).is_err());
        assert!(ClutterModel::new(vec![ClutterFactor::Constant(-1e-3)]).is_err());
    }

    fn learned_map() -> ClutterFactor {
        use crate::clutter_map::MapSpace;
        let bearings: Vec<f64> = (0..=12)
            .map(|i| -std::f64::consts::PI + i as f64 * std::f64::consts::PI / 6.0)
            .collect();
        let mut map = ClutterMap::new(
            MapSpace::BearingRange,
            [bearings, vec![0.0, 300.0, 1000.0, 1600.0]],
            1e-3,
            3.0,
            0.95,
        )
        .unwrap();
        let pose = Pose::new(3.0, -4.0, 0.7).unwrap();
        let clutter: Vec<f64> = (0..80)
            .map(|k| ((k as f64) * 1.618_033_988_749_895).sin() * 1500.0)
            .collect();
        for scan in 0..5 {
            map.update(
                &pose,
                &clutter[8 * scan..8 * scan + 16],
                None,
                &[clutter[scan], clutter[scan + 1], 150.0],
            )
            .unwrap();
        }
        ClutterFactor::Map(Arc::new(RwLock::new(map)))
    }

    #[test]
    fn a_model_reads_its_map_as_it_stands() {
        let factor = learned_map();
        let ClutterFactor::Map(shared) = &factor else {
            unreachable!()
        };
        let model = ClutterModel::new(vec![ClutterFactor::Constant(2.0), factor.clone()]).unwrap();
        assert!(model.uses_position());
        let pose = Pose::new(3.0, -4.0, 0.7).unwrap();
        let at = [500.0, 300.0];
        let mut before = [0.0];
        model.evaluate(&pose, &at, &[], &mut before).unwrap();
        assert_eq!(
            before[0],
            2.0 * read_map(shared).value_at(&pose, at[0], at[1], f64::NAN)
        );
        shared
            .write()
            .unwrap()
            .update(&pose, &[at, at, at].concat(), None, &[])
            .unwrap();
        let mut after = [0.0];
        model.evaluate(&pose, &at, &[], &mut after).unwrap();
        assert!(after[0] > before[0]);
        assert_eq!(after[0], 2.0 * read_map(shared).value_at(&pose, at[0], at[1], f64::NAN));
        // equal models share the map itself
        assert_eq!(
            model,
            ClutterModel::new(vec![ClutterFactor::Constant(2.0), factor]).unwrap()
        );
        assert_ne!(
            model,
            ClutterModel::new(vec![ClutterFactor::Constant(2.0), learned_map()]).unwrap()
        );
    }

    #[test]
    fn every_backend_gives_the_reference_bits() {
        use crate::simd::{run_on, Backend};
        let bands = |edges: Vec<f64>, values: Vec<f64>, owns: Vec<bool>| {
            ClutterFactor::Range(RangeBands::new(edges, values, owns).unwrap())
        };
        let rule = |column, threshold, missing| {
            ClutterFactor::Metadata(MetadataThreshold {
                column,
                threshold,
                below: 1e-1,
                at_or_above: 1e-3,
                missing,
            })
        };
        // Each pass order of the kernel: a constant first, a range factor first (its pass
        // also starts λ), a metadata rule first with range bands later, no factors, no
        // position at all.
        let models = [
            vec![
                ClutterFactor::Constant(0.7),
                bands(vec![100.0, 1000.0], vec![1e-3, 1e-2, 3e-2], vec![true, false]),
                rule(1, 10.0, Some(1e-2)),
                rule(0, 0.5, None),
            ],
            vec![
                bands(vec![1000.0], vec![1e-3, 1e-2], vec![true]),
                rule(0, 10.0, Some(1e-2)),
            ],
            vec![
                rule(0, 10.0, Some(1e-2)),
                bands(vec![100.0], vec![2.0, 3.0], vec![false]),
                ClutterFactor::Constant(1e-300),
                ClutterFactor::Constant(1e-300),
            ],
            vec![],
            vec![ClutterFactor::Constant(0.25), rule(2, 5.0, Some(4.0))],
            // a learned map with some evidence, between a range factor and a rule
            vec![
                bands(vec![1000.0], vec![1e-3, 1e-2], vec![true]),
                learned_map(),
                rule(0, 10.0, Some(1e-2)),
            ],
            vec![learned_map()],
        ];
        let origin = [3.0, -4.0];
        let pose = Pose::new(origin[0], origin[1], 0.7).unwrap();
        for model in models.map(|factors| ClutterModel::new(factors).unwrap()) {
            let k = model.metadata_columns();
            for m in [1, 3, 4, 5, 9, 130] {
                let mut positions: Vec<f64> = (0..2 * m)
                    .map(|k| ((k as f64) * 0.618_033_988_749_895).sin() * 1500.0)
                    .collect();
                // on the band edges exactly, far away, and positions that cannot be used
                positions[0] = origin[0] + 100.0;
                positions[1] = origin[1];
                if m > 4 {
                    positions[8] = origin[0] + 1000.0;
                    positions[9] = origin[1];
                    positions[6] = 1e300;
                }
                if m > 100 {
                    positions[2 * 77 + 1] = f64::NAN;
                    positions[2 * 90] = f64::NEG_INFINITY;
                }
                let metadata: Vec<f64> = (0..k * m)
                    .map(|k| match k % 7 {
                        0 => f64::NAN,
                        1 => 10.0,
                        2 => 0.5,
                        _ => (k % 23) as f64,
                    })
                    .collect();
                let ranges: Vec<f64> = (0..m).map(|i| if i % 3 == 0 { 1000.0 } else { f64::NAN }).collect();
                for ranges in [None, Some(&ranges[..])] {
                    let reference: Vec<u64> = (0..m)
                        .map(|i| {
                            model
                                .at_one(
                                    &pose,
                                    [positions[2 * i], positions[2 * i + 1]],
                                    &metadata[k * i..k * (i + 1)],
                                    ranges.map_or(f64::NAN, |r| r[i]),
                                )
                                .to_bits()
                        })
                        .collect();
                    let first_bad = reference.iter().position(|&v| !is_density(f64::from_bits(v)));
                    for backend in [Backend::Portable, Backend::Avx2].into_iter().filter(|b| b.available()) {
                        let mut out = vec![0.0; m];
                        let bad = run_on(
                            backend,
                            Densities {
                                model: &model,
                                pose: &pose,
                                positions: &positions,
                                metadata: &metadata,
                                ranges,
                                first: 0,
                                out: &mut out,
                            },
                        );
                        assert_eq!(
                            out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                            reference,
                            "{backend:?} m={m} {model:?}"
                        );
                        assert_eq!(bad, first_bad, "{backend:?} m={m} {model:?}");
                    }
                }
            }
        }
    }
}
