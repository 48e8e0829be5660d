//! ctxmodels core: context-aware sensor models for multi-target tracking.
//!
//! Pure Rust, no Python: coverage geometry (range bands, body-frame sectors, land masks,
//! line of sight, elevation sectors and the radar horizon in 3-D), detection probability P_D(x; S) and clutter density λ(z; S), evaluated
//! over whole arrays for one sensor pose S. The Python binding lives in [`python`] and is
//! compiled only with the `python` feature.

pub mod batch;
pub mod clutter;
pub mod clutter_map;
pub mod coast;
pub mod cubature;
pub mod detection;
pub mod detection_estimate;
pub mod distinct;
pub mod elevation;
pub mod error;
#[cfg(test)]
mod fuzz;
pub mod gmphd;
pub mod horizon;
pub mod jpda;
pub mod kalman;
pub mod land;
mod memory;
pub mod pose;
pub mod radar;
pub mod range_bands;
pub mod range_rate;
pub mod sector;
pub mod sight;
pub(crate) mod simd;
pub mod zone;

#[cfg(feature = "python")]
mod python;

pub use batch::{MemoryOrder, PositionMapping};
pub use clutter::{ClutterFactor, ClutterModel, MetadataThreshold};
pub use cubature::Rule;
pub use detection::{DetectionFactor, DetectionModel, ScanDetection};
pub use distinct::{ln_in_place, Distinct};
pub use elevation::ElevationSector;
pub use error::{ModelError, Result};
pub use horizon::Horizon;
pub use land::{LandMask, Polygon};
pub use pose::{Mounting, Pose, SensorFrame};
pub use range_bands::RangeBands;
pub use range_rate::RangeRateNotch;
pub use sector::AngularSector;
pub use sight::LineOfSight;
