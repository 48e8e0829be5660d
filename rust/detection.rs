//! Detection probability P_D(x; S): a product of factors, evaluated for one sensor pose S
//! over whole arrays of states.
//!
//! P_D(x; S) = Π_f f(x; S), each factor in [0, 1]: constants, range bands, body-frame
//! angular sectors, the radar equation (P_D from the SNR at range), elevation sectors, the
//! radar horizon at the target's height, a land mask (0 on land) and line of sight (0 when
//! shadowed by land).
//! The expected P_D of a Gaussian position, E[P_D(p)] with p ~ N(m, P), is evaluated with a
//! [`Rule`](crate::cubature::Rule).
//!
//! States are planar (x, y: every target at the sensor's height) or raised (x, y, z, by
//! the [`PositionMapping`]'s height column). With heights, ranges (bands, the radar
//! equation) are slant ranges from the sensor at its pose's height, elevations are the
//! target's angle above the sensor's horizontal plane, and bearings (sectors), land and
//! line of sight are read on the plane below the target.

use crate::batch::{
    check_columns, check_rows, for_each_chunk_from, ColumnHeights, ColumnVelocities, Columns, Cv3Rows, CvRows, Heights,
    Layout, MemoryOrder, Planar, PositionMapping, Positions, RowHeights, RowVelocities, Rows, Still, Velocities, CHUNK,
    PARALLEL_THRESHOLD,
};
use crate::cubature::Rule;
use crate::detection_estimate::{read_estimate, SharedEstimate};
use crate::elevation::ElevationSector;
use crate::error::{check_probability, ModelError, Result};
use crate::horizon::Horizon;
use crate::land::LandMask;
use crate::pose::{Pose, SensorFrame};
use crate::radar::RadarEquation;
use crate::range_bands::{RangeBands, SquaredBands};
use crate::range_rate::RangeRateNotch;
use crate::sector::{AngularSector, FramedSector};
use crate::sight::LineOfSight;
use crate::simd::dispatch;
use std::sync::Arc;

mod lanes;

#[derive(Debug, Clone)]
pub enum DetectionFactor {
    Constant(f64),
    Range(RangeBands),
    Sector(AngularSector),
    /// P_D of a Swerling target from the SNR at its range.
    Radar(RadarEquation),
    /// A band of elevations above the sensor's horizontal plane.
    Elevation(ElevationSector),
    /// 0 beyond the radar horizon of a target at its own height (raised states only).
    Horizon(Horizon),
    /// A notch around zero radial speed (and blind speeds): states with velocities only.
    RangeRate(RangeRateNotch),
    /// Land (boundary included) gets `on_land`, water 1.
    Land(Arc<LandMask>),
    /// A target shadowed from the sensor by land gets 0.
    Sight(Arc<LineOfSight>),
    /// Range bands learned online, as they stand when the model is put at a pose.
    Estimate(SharedEstimate),
}

#[derive(Debug, Clone)]
pub struct DetectionModel {
    factors: Vec<DetectionFactor>,
}

impl DetectionModel {
    pub fn new(factors: Vec<DetectionFactor>) -> Result<Self> {
        // The expected P_D integrates one notch over the velocity; two notches of the same
        // radial speed would not be independent.
        if factors
            .iter()
            .filter(|f| matches!(f, DetectionFactor::RangeRate(_)))
            .count()
            > 1
        {
            return Err(ModelError::invalid(
                "factors",
                "hold more than one RangeRateNotch; give the radar one notch (its blind speeds included)",
            ));
        }
        for (i, f) in factors.iter().enumerate() {
            let sector;
            let values: &[f64] = match f {
                DetectionFactor::Constant(v) => std::slice::from_ref(v),
                DetectionFactor::Range(b) => b.values(),
                DetectionFactor::Sector(s) => {
                    sector = s.values();
                    &sector
                }
                DetectionFactor::Elevation(e) => {
                    sector = e.values();
                    &sector
                }
                DetectionFactor::RangeRate(n) => {
                    sector = n.values();
                    &sector
                }
                DetectionFactor::Horizon(_)
                | DetectionFactor::Radar(_)
                | DetectionFactor::Land(_)
                | DetectionFactor::Sight(_)
                | DetectionFactor::Estimate(_) => &[], // (probabilities by construction)
            };
            for &v in values {
                check_probability("factors", v).map_err(|_| {
                    ModelError::invalid(
                        "factors",
                        format!("factor {i} holds {v}, but detection probabilities must lie in [0, 1]"),
                    )
                })?;
            }
        }
        Ok(DetectionModel { factors })
    }

    pub fn factors(&self) -> &[DetectionFactor] {
        &self.factors
    }

    /// The model at one sensor pose: per-scan constants computed once.
    pub fn at_pose(&self, pose: &Pose) -> ScanDetection {
        let frame = pose.frame();
        let mut constant = 1.0;
        let (mut steps, mut indexed) = (Vec::new(), Vec::new());
        // Land and sight run after the others (which keep their order, and so their bits),
        // only where P_D is still non-zero.
        for f in &self.factors {
            match f {
                DetectionFactor::Constant(v) => constant *= v,
                DetectionFactor::Range(bands) => steps.push(match bands.squared() {
                    Some(sq) => Step::SquaredBands(sq),
                    None => Step::Bands(bands.clone()),
                }),
                // frozen for the scan: a learner's update after it does not reach this one
                DetectionFactor::Estimate(estimate) => {
                    let bands = read_estimate(estimate).bands();
                    steps.push(match bands.squared() {
                        Some(sq) => Step::SquaredBands(sq),
                        None => Step::Bands(bands),
                    })
                }
                DetectionFactor::Sector(s) => steps.push(match frame.tilt {
                    None => Step::Sector(s.in_frame(&frame)),
                    Some(rows) => Step::TiltedSector(Tilted {
                        rows,
                        factor: s.in_sensor_frame(),
                    }),
                }),
                DetectionFactor::Radar(radar) => steps.push(Step::Radar(radar.clone())),
                DetectionFactor::Elevation(e) => steps.push(match frame.tilt {
                    None => Step::Elevation(e.clone()),
                    Some(rows) => Step::TiltedElevation(Tilted {
                        rows,
                        factor: e.clone(),
                    }),
                }),
                DetectionFactor::Horizon(h) => steps.push(Step::Horizon(h.clone())),
                DetectionFactor::RangeRate(n) => steps.push(Step::RangeRate(n.clone())),
                DetectionFactor::Land(land) => indexed.push(Indexed::Land(Arc::clone(land))),
                DetectionFactor::Sight(sight) => indexed.push(Indexed::Sight(Arc::clone(sight))),
            }
        }
        let heavy = steps.iter().any(|s| matches!(s, Step::Radar(_)));
        ScanDetection {
            frame,
            steps,
            indexed,
            constant,
            parallel_from: if heavy { 2 * CHUNK } else { PARALLEL_THRESHOLD },
        }
    }
}

/// A range, sector or radar-equation factor prepared for a pose, evaluated four states at a time
/// (owned, so a scan's model can outlive the call that built it: the bindings keep one per
/// detector context).
enum Step {
    SquaredBands(SquaredBands),
    Bands(RangeBands),
    Sector(FramedSector),
    Radar(RadarEquation),
    Elevation(ElevationSector),
    Horizon(Horizon),
    RangeRate(RangeRateNotch),
    /// A sector of a pitched or rolled sensor: read on the first two rows of M d.
    TiltedSector(Tilted<FramedSector>),
    /// An elevation sector of a pitched or rolled sensor: read on M d's third row.
    TiltedElevation(Tilted<ElevationSector>),
}

/// A bearing or elevation factor of a pitched or rolled sensor, with the rows of the
/// world → sensor rotation M ([`crate::pose::Pose::rotation`]) it reads the offset through.
#[derive(Debug, Clone)]
struct Tilted<T> {
    rows: [[f64; 3]; 3],
    factor: T,
}

/// (Its lanes in [`lanes`], the same bits.)
impl Tilted<FramedSector> {
    fn at(&self, g: &Offsets<f64>) -> f64 {
        let [a, b, _] = self.rows;
        let sx = a[0] * g.dx + a[1] * g.dy + a[2] * g.dz;
        let sy = b[0] * g.dx + b[1] * g.dy + b[2] * g.dz;
        self.factor.at_squared(sx, sy, sx * sx + sy * sy)
    }
}

impl Tilted<ElevationSector> {
    fn at(&self, g: &Offsets<f64>) -> f64 {
        let c = self.rows[2];
        self.factor.at(c[0] * g.dx + c[1] * g.dy + c[2] * g.dz, g.r2)
    }
}

/// Where a target is from the sensor: what every step reads. Planar states have dz = 0,
/// r2 = h2 and z the sensor's height; states without velocities have dot = 0.
#[derive(Clone, Copy)]
pub(crate) struct Offsets<T> {
    /// World-frame plane offsets.
    pub dx: T,
    pub dy: T,
    /// Squared plane distance dx² + dy².
    pub h2: T,
    /// Height above the sensor.
    pub dz: T,
    /// Squared slant range h2 + dz².
    pub r2: T,
    /// The target's height.
    pub z: T,
    /// Δp·Δv: the offset from the sensor dotted with the velocity relative to it (the
    /// radial speed times the slant range).
    pub dot: T,
}

impl Step {
    /// The step's value at one target.
    fn at(&self, g: &Offsets<f64>) -> f64 {
        match self {
            Step::SquaredBands(bands) => bands.at_squared(g.r2),
            Step::Bands(bands) => bands.at(g.r2.sqrt()),
            Step::Sector(sector) => sector.at_squared(g.dx, g.dy, g.h2),
            Step::Radar(radar) => radar.at_squared(g.r2),
            Step::Elevation(e) => e.at(g.dz, g.r2),
            Step::Horizon(h) => h.at(g.h2, g.z),
            Step::RangeRate(n) => n.at(g.dot, g.r2),
            Step::TiltedSector(t) => t.at(g),
            Step::TiltedElevation(t) => t.at(g),
        }
    }
}

/// A factor evaluated point by point (a spatial index lookup each).
enum Indexed {
    /// Land (boundary included) gets 0.
    Land(Arc<LandMask>),
    /// A target shadowed from the sensor by land gets 0.
    Sight(Arc<LineOfSight>),
}

/// A [`DetectionModel`] at one pose.
pub struct ScanDetection {
    frame: SensorFrame,
    steps: Vec<Step>,
    indexed: Vec<Indexed>,
    constant: f64,
    /// Rows from which an evaluation is split over threads: fewer with the radar equation,
    /// whose P_D costs an e^x per state at least (a series with several pulses or a
    /// steady target).
    parallel_from: usize,
}

impl ScanDetection {
    /// P_D at one world point at the sensor's height, one factor after another: the
    /// readable reference the planar lane kernels ([`lanes`]) must match bit for bit.
    pub fn at_point(&self, x: f64, y: f64) -> f64 {
        self.at_state(x, y, None, None)
    }

    /// P_D at one world point at height `z`: the reference of the raised kernels.
    pub fn at_raised(&self, x: f64, y: f64, z: f64) -> f64 {
        self.at_state(x, y, Some(z), None)
    }

    /// P_D of a target at (x, y), at height `z` (None: the sensor's) and moving at
    /// `velocity` (None: not read; vz ignored without a height): the reference of every
    /// kernel.
    pub fn at_state(&self, x: f64, y: f64, z: Option<f64>, velocity: Option<[f64; 3]>) -> f64 {
        self.at_offsets(x, y, &self.offsets(x, y, z, velocity))
    }

    /// P_D of a target at (x, y) (at height `z`, None: the sensor's) whose velocity is
    /// normal, N(`velocity`, `spread`) (vz and its row and column read only with a height):
    /// every factor at the point, the range-rate notch by its expectation over the
    /// velocity ([`RangeRateNotch::expected_at`]). The reference of the expected kernels
    /// with velocities.
    pub fn at_state_uncertain(
        &self,
        x: f64,
        y: f64,
        z: Option<f64>,
        velocity: [f64; 3],
        spread: &[[f64; 3]; 3],
    ) -> f64 {
        let g = self.offsets(x, y, z, Some(velocity));
        let mut pd = self.constant;
        for step in self.steps.iter().filter(|s| !matches!(s, Step::RangeRate(_))) {
            pd *= step.at(&g);
        }
        self.indexed_at(x, y, pd) * self.notch_given(&g, spread)
    }

    /// The expectation of the scan's range-rate notch (a model has one at most) at offsets
    /// `g`, the velocity having covariance `spread`: ṙ has variance uᵀ `spread` u along the
    /// unit line of sight u = Δp/|Δp|; 1 without a notch.
    fn notch_given(&self, g: &Offsets<f64>, spread: &[[f64; 3]; 3]) -> f64 {
        let Some(notch) = self.notch() else {
            return 1.0;
        };
        let r = g.r2.sqrt();
        let u = [g.dx / r, g.dy / r, g.dz / r];
        let mut var = 0.0;
        for (ui, row) in u.iter().zip(spread) {
            var += ui * (row[0] * u[0] + row[1] * u[1] + row[2] * u[2]);
        }
        notch.expected_at(g.dot, g.r2, var)
    }

    /// [`Self::notch_given`] at a point: the factor the expected kernels take apart.
    #[inline]
    fn notch_at(&self, x: f64, y: f64, z: Option<f64>, velocity: [f64; 3], spread: &[[f64; 3]; 3]) -> f64 {
        self.notch_given(&self.offsets(x, y, z, Some(velocity)), spread)
    }

    fn notch(&self) -> Option<&RangeRateNotch> {
        self.steps.iter().find_map(|s| match s {
            Step::RangeRate(n) => Some(n),
            _ => None,
        })
    }

    /// Where a target is from the sensor (as the lane kernels compute it, the same bits).
    fn offsets(&self, x: f64, y: f64, z: Option<f64>, velocity: Option<[f64; 3]>) -> Offsets<f64> {
        let [ox, oy] = self.frame.origin;
        let (dx, dy) = (x - ox, y - oy);
        let h2 = dx * dx + dy * dy;
        let (dz, r2, height) = match z {
            Some(z) => {
                let dz = z - self.frame.height;
                (dz, h2 + dz * dz, z)
            }
            None => (0.0, h2, self.frame.height),
        };
        let [px, py, pz] = self.frame.velocity;
        let dot = match (velocity, z) {
            (None, _) => 0.0,
            (Some(v), None) => dx * (v[0] - px) + dy * (v[1] - py),
            (Some(v), Some(_)) => dx * (v[0] - px) + dy * (v[1] - py) + dz * (v[2] - pz),
        };
        Offsets {
            dx,
            dy,
            h2,
            dz,
            r2,
            z: height,
            dot,
        }
    }

    fn at_offsets(&self, x: f64, y: f64, g: &Offsets<f64>) -> f64 {
        let mut pd = self.constant;
        for step in &self.steps {
            pd *= step.at(g);
        }
        self.indexed_at(x, y, pd)
    }

    /// The mapping as the scan reads it: refused, naming `position_mapping`, without the
    /// heights a horizon at the target's height needs, or, naming `velocity_mapping`,
    /// without the velocities a range-rate notch needs; its velocity dropped when no
    /// factor reads it (so the kernels read no more than they need).
    fn reads(&self, mapping: PositionMapping) -> Result<PositionMapping> {
        if mapping.z.is_none() && self.steps.iter().any(|s| matches!(s, Step::Horizon(_))) {
            return Err(ModelError::invalid(
                "position_mapping",
                format!("{mapping} gives no height, but the model's radar horizon is at each target's height; give the (x, y, z) indices of the state"),
            ));
        }
        let moving = self.steps.iter().any(|s| matches!(s, Step::RangeRate(_)));
        if moving && mapping.velocity.is_none() {
            return Err(ModelError::invalid(
                "velocity_mapping",
                "is not given, but the model's range-rate notch reads each target's velocity; give the state's velocity indices",
            ));
        }
        Ok(PositionMapping {
            velocity: mapping.velocity.filter(|_| moving),
            ..mapping
        })
    }

    /// `pd` after the land and sight factors at (x, y): skipped once it is 0.
    #[inline]
    fn indexed_at(&self, x: f64, y: f64, mut pd: f64) -> f64 {
        for step in &self.indexed {
            if pd == 0.0 {
                break;
            }
            let hidden = match step {
                Indexed::Land(land) => land.contains([x, y]),
                Indexed::Sight(sight) => !sight.visible(self.frame.origin, [x, y]),
            };
            if hidden {
                pd = 0.0;
            }
        }
        pd
    }

    /// P_D at the position of each state row. `states` is (N, ncols) row-major.
    pub fn at_states(&self, states: &[f64], ncols: usize, mapping: PositionMapping, out: &mut [f64]) -> Result<()> {
        let mapping = self.reads(mapping)?;
        mapping.check(ncols, "states")?;
        check_rows(states, ncols, out.len(), "states")?;
        match self.at_layout(states, Layout::Rows { ncols }, mapping, out) {
            Some(row) => Err(ModelError::non_finite("states", row, "position is NaN or infinite")),
            None => Ok(()),
        }
    }

    /// P_D at the position of each particle of `particles`, a (ndim, N) array (one column
    /// per particle, Stone Soup's `StateVectors`; N = `out.len()`) in memory order `order`,
    /// read in place: no transpose. Same kernel as [`Self::at_states`], so the same bits.
    pub fn at_particles(
        &self,
        particles: &[f64],
        ndim: usize,
        order: MemoryOrder,
        mapping: PositionMapping,
        out: &mut [f64],
    ) -> Result<()> {
        let mapping = self.reads(mapping)?;
        check_columns(particles, ndim, out.len(), mapping, "particles")?;
        match self.at_layout(particles, order.layout(ndim, out.len()), mapping, out) {
            Some(i) => Err(ModelError::invalid(
                "particles",
                format!("particle {i} (column {i}) has a NaN or infinite position"),
            )),
            None => Ok(()),
        }
    }

    /// P_D of every state of a checked array; the first state whose position (or velocity,
    /// where read) is not finite.
    fn at_layout(&self, states: &[f64], layout: Layout, mapping: PositionMapping, out: &mut [f64]) -> Option<usize> {
        for_each_chunk_from(out, self.parallel_from, |first, chunk| match layout {
            Layout::Rows { ncols } => {
                let rows = Rows {
                    data: states,
                    ncols,
                    mapping,
                };
                let heights = mapping.z.map(|z| RowHeights { data: states, ncols, z });
                let velocities = mapping.velocity.map(|v| RowVelocities {
                    data: states,
                    ncols,
                    mapping: v,
                });
                match (heights, velocities) {
                    (None, None) if ncols == 4 && mapping == PositionMapping::default() => {
                        self.run(CvRows(states), Planar, Still, first, chunk)
                    }
                    (Some(_), None) if ncols == 6 && (mapping.x, mapping.y, mapping.z) == (0, 2, Some(4)) => {
                        self.run(Cv3Rows(states), Cv3Rows(states), Still, first, chunk)
                    }
                    // [x, vx, y, vy] read by a notch: the velocities with vector loads too
                    (None, Some(v))
                        if ncols == 4 && (mapping.x, mapping.y) == (0, 2) && (v.mapping.vx, v.mapping.vy) == (1, 3) =>
                    {
                        self.run(CvRows(states), Planar, CvRows(states), first, chunk)
                    }
                    (None, None) => self.run(rows, Planar, Still, first, chunk),
                    (Some(h), None) => self.run(rows, h, Still, first, chunk),
                    (None, Some(v)) => self.run(rows, Planar, v, first, chunk),
                    (Some(h), Some(v)) => self.run(rows, h, v, first, chunk),
                }
            }
            Layout::Columns { nstates } => {
                let row = |i: usize| &states[i * nstates..][..nstates];
                let columns = Columns {
                    xs: row(mapping.x),
                    ys: row(mapping.y),
                };
                let velocities = mapping.velocity.map(|v| ColumnVelocities {
                    vx: row(v.vx),
                    vy: row(v.vy),
                    vz: v.vz.map(row),
                });
                match (mapping.z, velocities) {
                    (None, None) => self.run(columns, Planar, Still, first, chunk),
                    (Some(z), None) => self.run(columns, ColumnHeights(row(z)), Still, first, chunk),
                    (None, Some(v)) => self.run(columns, Planar, v, first, chunk),
                    (Some(z), Some(v)) => self.run(columns, ColumnHeights(row(z)), v, first, chunk),
                }
            }
        })
    }

    /// The P_D kernel for this CPU over one chunk.
    fn run<P: Positions, H: Heights, V: Velocities>(
        &self,
        positions: P,
        heights: H,
        velocities: V,
        first: usize,
        out: &mut [f64],
    ) -> Option<usize> {
        dispatch(lanes::AtStates {
            scan: self,
            positions,
            heights,
            velocities,
            first,
            out,
        })
    }

    /// Expected P_D over each Gaussian N(mean_i, P_i), P_i the position block of the
    /// (ncols × ncols) covariance `covars[i]` (x, y, and z when the mapping has a height:
    /// then under the rule's 3-D form).
    pub fn expected_at_gaussians(
        &self,
        means: &[f64],
        covars: &[f64],
        ncols: usize,
        mapping: PositionMapping,
        rule: &Rule,
        out: &mut [f64],
    ) -> Result<()> {
        let mapping = self.reads(mapping)?;
        mapping.check(ncols, "means")?;
        let n = check_rows(means, ncols, out.len(), "means")?;
        if covars.len() != n * ncols * ncols {
            return Err(ModelError::shape(
                "covars",
                format!(
                    "must be ({n}, {ncols}, {ncols}) to match means, got {} values",
                    covars.len()
                ),
            ));
        }
        let gaussians = lanes::Gaussians {
            means: Rows {
                data: means,
                ncols,
                mapping,
            },
            covars,
        };
        let spatial = mapping.z.map(|z| (z, rule.spatial()));
        // The first bad row of each chunk, with what is wrong with it.
        let problems = std::sync::Mutex::new(Vec::<(usize, lanes::BadGaussian)>::new());
        // (velocities at each mean; a notch is integrated over the velocity given each point)
        let velocities = mapping.velocity.map(|v| RowVelocities {
            data: means,
            ncols,
            mapping: v,
        });
        let bad = for_each_chunk_from(out, self.parallel_from, |first, chunk| {
            macro_rules! expected {
                ($velocities:expr) => {
                    dispatch(lanes::Expected {
                        scan: self,
                        gaussians,
                        velocities: $velocities,
                        rule,
                        first,
                        out: chunk,
                    })
                };
            }
            macro_rules! raised {
                ($z:expr, $rule:expr, $velocities:expr) => {
                    dispatch(lanes::ExpectedRaised {
                        scan: self,
                        gaussians,
                        heights: RowHeights {
                            data: means,
                            ncols,
                            z: $z,
                        },
                        velocities: $velocities,
                        rule: $rule,
                        first,
                        out: chunk,
                    })
                };
            }
            let (i, kind) = match (&spatial, velocities) {
                (None, None) => expected!(Still),
                (None, Some(v)) => expected!(v),
                (Some((z, rule)), None) => raised!(*z, rule, Still),
                (Some((z, rule)), Some(v)) => raised!(*z, rule, v),
            }?;
            // (one entry per chunk at most, so not user-sized beyond the output; a poisoned
            // lock still holds whole entries: the push is its only use)
            problems
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .push((first + i, kind));
            Some(i)
        });
        let Some(row) = bad else { return Ok(()) };
        let problems = problems.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
        Err(match problems.iter().find(|(r, _)| *r == row).map(|(_, k)| *k) {
            Some(lanes::BadGaussian::Covar) => ModelError::invalid(
                "covars",
                format!("row {row}: the position block is not a finite symmetric positive semi-definite matrix"),
            ),
            Some(lanes::BadGaussian::Velocity) => ModelError::invalid(
                "covars",
                format!("row {row}: the block of the position and the velocity (which the range-rate notch reads) is not a finite symmetric positive semi-definite matrix"),
            ),
            _ if mapping.velocity.is_some() => {
                ModelError::non_finite("means", row, "position or velocity is NaN or infinite")
            }
            _ => ModelError::non_finite("means", row, "position is NaN or infinite"),
        })
    }
}

#[cfg(test)]
mod column_tests;
#[cfg(test)]
mod lane_tests;
#[cfg(test)]
mod moving_tests;
#[cfg(test)]
mod raised_tests;

#[cfg(test)]
mod tests;
