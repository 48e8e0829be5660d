//! Clutter spatial density λ(z; S): a product of factors evaluated per detection.
//!
//! Factors: constants, range bands over the detection's range from the sensor, and
//! threshold rules on one column of detection metadata (the paper's lidar: segment
//! `area < 10` → 1e-1, otherwise 1e-3). λ is a density in the detection's measurement
//! space, so it must be strictly positive: trackers divide by it.

use crate::batch::{for_each_chunk, CHUNK};
use crate::error::{ModelError, Result};
use crate::pose::Pose;
use crate::range_bands::RangeBands;

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

#[derive(Debug, Clone, PartialEq)]
pub enum ClutterFactor {
    Constant(f64),
    Range(RangeBands),
    Metadata(MetadataThreshold),
}

#[derive(Debug, Clone, PartialEq)]
pub struct ClutterModel {
    factors: Vec<ClutterFactor>,
    metadata_columns: usize,
    uses_position: bool,
}

fn check_density(i: usize, v: f64) -> Result<()> {
    if !(v.is_finite() && v > 0.0) {
        return Err(ModelError::invalid(
            "factors",
            format!("factor {i} holds {v}, but clutter densities must be finite and > 0 (trackers divide by them)"),
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
                ClutterFactor::Range(b) => {
                    uses_position = true;
                    for &v in b.values() {
                        check_density(i, v)?;
                    }
                }
                ClutterFactor::Metadata(rule) => {
                    if !rule.threshold.is_finite() {
                        return Err(ModelError::invalid("threshold", format!("must be finite, got {}", rule.threshold)));
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
        Ok(ClutterModel { factors, metadata_columns, uses_position })
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
        &self, pose: &Pose, positions: &[f64], metadata: &[f64], ranges: Option<&[f64]>, out: &mut [f64],
    ) -> Result<()> {
        let m = out.len();
        if positions.len() != 2 * m {
            return Err(ModelError::shape("positions", format!("must be ({m}, 2), got {} values", positions.len())));
        }
        if let Some(r) = ranges {
            if r.len() != m {
                return Err(ModelError::shape("ranges", format!("must have {m} entries, got {}", r.len())));
            }
            if let Some(row) = r.iter().position(|v| v.is_infinite()) {
                return Err(ModelError::non_finite("ranges", row, "range is infinite (NaN = use the position)"));
            }
        }
        let k = self.metadata_columns;
        if metadata.len() != k * m {
            return Err(ModelError::shape("metadata", format!("must be ({m}, {k}), got {} values", metadata.len())));
        }
        let origin = [pose.x, pose.y];
        // The first row that cannot be evaluated, with the argument and the problem.
        let problems = std::sync::Mutex::new(Vec::<(usize, &'static str, String)>::new());
        let bad = for_each_chunk(out, |first, chunk| {
            let mut range = [0.0f64; CHUNK];
            for i in 0..chunk.len() {
                let row = first + i;
                let (x, y) = (positions[2 * row], positions[2 * row + 1]);
                let measured = ranges.map_or(f64::NAN, |r| r[row]);
                range[i] = if measured.is_nan() {
                    ((x - origin[0]).powi(2) + (y - origin[1]).powi(2)).sqrt()
                } else {
                    measured
                };
                // NaN marks the row as not evaluable and survives every product below.
                let unusable = self.uses_position && !(x.is_finite() && y.is_finite());
                chunk[i] = if unusable { f64::NAN } else { 1.0 };
            }
            for f in &self.factors {
                match f {
                    ClutterFactor::Constant(v) => chunk.iter_mut().for_each(|o| *o *= v),
                    ClutterFactor::Range(bands) => {
                        for i in 0..chunk.len() {
                            chunk[i] *= bands.at(range[i]);
                        }
                    }
                    ClutterFactor::Metadata(rule) => {
                        for i in 0..chunk.len() {
                            let value = metadata[(first + i) * k + rule.column];
                            chunk[i] *= if value.is_nan() {
                                rule.missing.unwrap_or(f64::NAN)
                            } else if value.is_infinite() {
                                // ±inf (an overflowed value) would pass as "at or above".
                                f64::NAN
                            } else if value < rule.threshold {
                                rule.below
                            } else {
                                rule.at_or_above
                            };
                        }
                    }
                }
            }
            // Every factor value is finite and > 0, so a λ that is not marks a row that could
            // not be evaluated (or a product that under/overflowed); say why for the first one.
            let i = chunk.iter().position(|v| !(v.is_finite() && *v > 0.0))?;
            let row = first + i;
            let (x, y) = (positions[2 * row], positions[2 * row + 1]);
            let problem = if self.uses_position && !(x.is_finite() && y.is_finite()) {
                ("positions", "position is NaN or infinite".to_string())
            } else {
                let metadata_problem = self.factors.iter().find_map(|f| match f {
                    ClutterFactor::Metadata(rule) => {
                        let value = metadata[row * k + rule.column];
                        if value.is_infinite() {
                            Some(format!("metadata column {} is {value}; values must be finite (NaN = missing)", rule.column))
                        } else if rule.missing.is_none() && value.is_nan() {
                            Some(format!("metadata column {} is missing and the rule has no `missing` value", rule.column))
                        } else {
                            None
                        }
                    }
                    _ => None,
                });
                match metadata_problem {
                    Some(message) => ("metadata", message),
                    None => ("factors", format!("the product of the clutter factors is {}, not a finite density > 0 (factors too small or too large)", chunk[i])),
                }
            };
            problems.lock().unwrap().push((row, problem.0, problem.1));
            Some(i)
        });
        if let Some(row) = bad {
            let problems = problems.into_inner().unwrap();
            let (_, argument, message) = problems.into_iter().find(|p| p.0 == row).unwrap();
            return Err(ModelError::non_finite(argument, row, message));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_metadata_column_beyond_usize_is_an_error_not_an_overflow() {
        let rule = MetadataThreshold { column: usize::MAX, threshold: 10.0, below: 1e-1, at_or_above: 1e-3, missing: None };
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
        model.evaluate_with_ranges(&pose, &positions, &[], Some(&[1000.0, f64::NAN, 999.0]), &mut out).unwrap();
        assert_eq!(out, [1e-2, 1e-3, 1e-3]);
        let err = model.evaluate_with_ranges(&pose, &positions, &[], Some(&[f64::INFINITY, 0.0, 0.0]), &mut out).unwrap_err();
        assert_eq!(err, ModelError::non_finite("ranges", 0, "range is infinite (NaN = use the position)"));
        assert!(model.evaluate_with_ranges(&pose, &positions, &[], Some(&[1.0]), &mut out).is_err());
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
        model.evaluate(&pose, &[0.0; 6], &[9.99, 10.0, 250.0], &mut out).unwrap();
        assert_eq!(out, [1e-1, 1e-3, 1e-3]);
        let err = model.evaluate(&pose, &[0.0; 6], &[9.99, f64::NAN, 250.0], &mut out).unwrap_err();
        assert_eq!(err, ModelError::non_finite("metadata", 1, "metadata column 0 is missing and the rule has no `missing` value"));
    }

    #[test]
    fn infinite_metadata_is_an_error_naming_metadata() {
        let rule = MetadataThreshold { column: 0, threshold: 10.0, below: 1e-1, at_or_above: 1e-3, missing: Some(1.0) };
        let model = ClutterModel::new(vec![ClutterFactor::Metadata(rule)]).unwrap();
        let pose = Pose::new(0.0, 0.0, 0.0).unwrap();
        let mut out = [0.0; 3];
        for bad in [f64::INFINITY, f64::NEG_INFINITY] {
            let err = model.evaluate(&pose, &[0.0; 6], &[1.0, f64::NAN, bad], &mut out).unwrap_err();
            assert_eq!(err, ModelError::non_finite("metadata", 2, format!("metadata column 0 is {bad}; values must be finite (NaN = missing)")));
        }
    }

    #[test]
    fn paper_radar_range_rule() {
        let model = ClutterModel::new(vec![ClutterFactor::Range(RangeBands::new(vec![1000.0], vec![1e-3, 1e-2], vec![true]).unwrap())]).unwrap();
        let pose = Pose::new(10.0, 10.0, 0.0).unwrap();
        let mut out = [0.0; 3];
        model.evaluate(&pose, &[10.0, 1009.0, 10.0, 1010.0, 1010.0, 10.0], &[], &mut out).unwrap();
        assert_eq!(out, [1e-3, 1e-2, 1e-2]);
    }

    #[test]
    fn zero_or_negative_density_is_rejected() {
        assert!(ClutterModel::new(vec![ClutterFactor::Constant(0.0)]).is_err());
        assert!(ClutterModel::new(vec![ClutterFactor::Constant(-1e-3)]).is_err());
    }
}
