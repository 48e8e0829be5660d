//! Range bands: a value that is piecewise constant in range from the sensor.
//!
//! `edges` e_0 < e_1 < … < e_{k-1} split [0, ∞) into k + 1 bands holding `values`
//! v_0 … v_k. Who owns an edge is explicit, because the paper's equations differ:
//! the lidar's 0.2 band is 50 ≤ r < 80 (edge owned by the band above) while the radar's
//! 0.4 band is 50 < r < 1612 (the 50 m edge owned by the band below). `upper_owns[i]`
//! says that r == e_i falls into the band above e_i.

use crate::error::{ModelError, Result};

#[derive(Debug, Clone, PartialEq)]
pub struct RangeBands {
    edges: Vec<f64>,
    values: Vec<f64>,
    upper_owns: Vec<bool>,
}

impl RangeBands {
    pub fn new(edges: Vec<f64>, values: Vec<f64>, upper_owns: Vec<bool>) -> Result<Self> {
        if values.len() != edges.len() + 1 {
            return Err(ModelError::shape(
                "values",
                format!("needs one more entry than edges ({} edges → {} values), got {}", edges.len(), edges.len() + 1, values.len()),
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
                return Err(ModelError::invalid("edges", format!("edge {i} must be finite and >= 0, got {e}")));
            }
            if i > 0 && e <= edges[i - 1] {
                return Err(ModelError::invalid("edges", format!("must be strictly increasing, but edge {i} ({e}) <= edge {} ({})", i - 1, edges[i - 1])));
            }
        }
        for (i, &v) in values.iter().enumerate() {
            if !v.is_finite() {
                return Err(ModelError::invalid("values", format!("value {i} must be finite, got {v}")));
            }
        }
        Ok(RangeBands { edges, values, upper_owns })
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
            let passed = r > edge || (r == edge && self.upper_owns[i]);
            if passed {
                value = self.values[i + 1];
            }
        }
        value
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
        assert_eq!(RangeBands::new(vec![80.0, 50.0], vec![1.0, 0.5, 0.0], vec![true, true]).unwrap_err().argument(), "edges");
        assert_eq!(RangeBands::new(vec![-1.0], vec![1.0, 0.5], vec![true]).unwrap_err().argument(), "edges");
        assert_eq!(RangeBands::new(vec![1.0], vec![1.0], vec![true]).unwrap_err().argument(), "values");
        assert_eq!(RangeBands::new(vec![1.0], vec![1.0, f64::NAN], vec![true]).unwrap_err().argument(), "values");
        assert_eq!(RangeBands::new(vec![1.0], vec![1.0, 0.0], vec![]).unwrap_err().argument(), "upper_owns");
    }

    #[test]
    fn no_edges_is_a_constant() {
        let b = RangeBands::new(vec![], vec![0.7], vec![]).unwrap();
        assert_eq!(b.at(0.0), 0.7);
        assert_eq!(b.at(1e6), 0.7);
    }
}
