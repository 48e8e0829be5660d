//! Clutter spatial density λ(z; S): a product of factors evaluated per detection.
//!
//! Factors: constants, range bands over the detection's range from the sensor, threshold
//! rules on one column of detection metadata (the paper's lidar: segment `area < 10` →
//! 1e-1, otherwise 1e-3), learned clutter maps ([`ClutterMap`], shared with the
//! estimator that updates them between scans), coastal bands, zones and, for detections
//! with a height, elevation sectors. λ is a density in the detection's measurement
//! space, so it must be strictly positive: trackers divide by it.
//!
//! Detections with a height (a 3-D radar's) have range bands read on the slant range from
//! the sensor's height and elevation sectors on their world elevation above it (whatever a
//! pose's pitch and roll: the sea is level); maps, coastal bands and zones read the plane
//! below them.

use crate::batch::for_each_chunk;
use crate::clutter_map::ClutterMap;
use crate::coast::CoastalBand;
use crate::elevation::ElevationSector;
use crate::error::{ModelError, Result};
use crate::pose::Pose;
use crate::range_bands::RangeBands;
use crate::simd::dispatch;
use crate::zone::Zone;
use std::sync::{Arc, RwLock, RwLockReadGuard};

mod lanes;
use lanes::Densities;

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
    /// One value inside a set of polygons, another outside.
    Zone(Arc<Zone>),
    /// One value between two elevations above the sensor, another outside (detections
    /// with a height only).
    Elevation(ElevationSector),
}

impl ClutterFactor {
    /// The value at (x, y) of a factor evaluated point by point (a coastal band, a zone);
    /// NaN for the others, which the kernels evaluate in lanes.
    #[inline]
    pub(crate) fn point_value(&self, pose: &Pose, x: f64, y: f64) -> f64 {
        match self {
            ClutterFactor::Coast(band) => band.value_at([pose.x, pose.y], x, y),
            ClutterFactor::Zone(zone) => zone.value_at(x, y),
            _ => f64::NAN,
        }
    }
}

impl PartialEq for ClutterFactor {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (ClutterFactor::Constant(a), ClutterFactor::Constant(b)) => a == b,
            (ClutterFactor::Range(a), ClutterFactor::Range(b)) => a == b,
            (ClutterFactor::Metadata(a), ClutterFactor::Metadata(b)) => a == b,
            (ClutterFactor::Map(a), ClutterFactor::Map(b)) => Arc::ptr_eq(a, b),
            (ClutterFactor::Coast(a), ClutterFactor::Coast(b)) => Arc::ptr_eq(a, b),
            (ClutterFactor::Zone(a), ClutterFactor::Zone(b)) => Arc::ptr_eq(a, b),
            (ClutterFactor::Elevation(a), ClutterFactor::Elevation(b)) => a == b,
            _ => false,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct ClutterModel {
    factors: Vec<ClutterFactor>,
    metadata_columns: usize,
    uses_position: bool,
    uses_height: bool,
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
        let (mut uses_position, mut uses_height) = (false, false);
        for (i, f) in factors.iter().enumerate() {
            match f {
                ClutterFactor::Constant(v) => check_density(i, *v)?,
                // its values are posterior means with a prior > 0: finite and > 0
                ClutterFactor::Map(_) | ClutterFactor::Coast(_) => uses_position = true,
                ClutterFactor::Zone(zone) => {
                    uses_position = true;
                    check_density(i, zone.inside())?;
                    check_density(i, zone.outside())?;
                }
                ClutterFactor::Range(b) => {
                    uses_position = true;
                    for &v in b.values() {
                        check_density(i, v)?;
                    }
                }
                ClutterFactor::Elevation(e) => {
                    (uses_position, uses_height) = (true, true);
                    for v in e.values() {
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
            uses_height,
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

    /// Whether λ reads the detections' heights (an elevation sector among the factors).
    pub fn uses_height(&self) -> bool {
        self.uses_height
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
        self.evaluate_rows(pose, positions, 2, metadata, ranges, out)
    }

    /// As [`evaluate_with_ranges`](Self::evaluate_with_ranges), for `positions` of `ncols`
    /// columns: (M, 2) rows (x, y), or (M, 3) rows (x, y, z) of detections with a height,
    /// whose range bands read the slant range from the sensor's height (`pose.z`) and whose
    /// elevation sectors read the elevation above it. A model with an elevation sector
    /// needs the heights.
    pub fn evaluate_rows(
        &self,
        pose: &Pose,
        positions: &[f64],
        ncols: usize,
        metadata: &[f64],
        ranges: Option<&[f64]>,
        out: &mut [f64],
    ) -> Result<()> {
        let m = out.len();
        if ncols == 2 && self.uses_height {
            return Err(ModelError::shape(
                "positions",
                "the clutter model's elevation sector reads each detection's height: give (M, 3) positions (x, y, z)",
            ));
        }
        if !(ncols == 2 || ncols == 3) || positions.len() != ncols * m {
            return Err(ModelError::shape(
                "positions",
                format!(
                    "must be ({m}, 2) or ({m}, 3), got {} values in rows of {ncols}",
                    positions.len()
                ),
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
                ncols,
                metadata,
                ranges,
                first,
                out: chunk,
            })
        });
        if let Some(row) = bad {
            let place = &positions[ncols * row..][..ncols];
            let (argument, message) = self.problem(place, metadata, row, out[row]);
            return Err(ModelError::non_finite(argument, row, message));
        }
        Ok(())
    }

    /// λ of one detection at (x, y) (at height `z`, None: planar) with its metadata row
    /// and measured range (NaN: none), one factor after another: the readable reference the
    /// lane kernel must match bit for bit. NaN when the detection cannot be evaluated.
    pub fn at_one(&self, pose: &Pose, [x, y]: [f64; 2], z: Option<f64>, metadata: &[f64], measured: f64) -> f64 {
        let (dx, dy) = (x - pose.x, y - pose.y);
        let dz = z.map_or(0.0, |z| z - pose.z);
        let squared = dx * dx + dy * dy + dz * dz;
        let range = if measured.is_nan() { squared.sqrt() } else { measured };
        let finite = x.is_finite() && y.is_finite() && dz.is_finite();
        let mut density = if self.uses_position && !finite { f64::NAN } else { 1.0 };
        for f in &self.factors {
            density *= match f {
                ClutterFactor::Constant(v) => *v,
                ClutterFactor::Range(bands) => bands.at(range),
                // (a map is of the plane: a 3-D detection's measured range is a slant one)
                ClutterFactor::Map(map) => {
                    read_map(map).value_at(pose, x, y, if z.is_some() { f64::NAN } else { measured })
                }
                ClutterFactor::Coast(_) | ClutterFactor::Zone(_) => f.point_value(pose, x, y),
                ClutterFactor::Elevation(e) => e.at(dz, squared),
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
    fn problem(&self, place: &[f64], metadata: &[f64], row: usize, density: f64) -> (&'static str, String) {
        if self.uses_position && !place.iter().all(|v| v.is_finite()) {
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

#[cfg(test)]
mod tests;
