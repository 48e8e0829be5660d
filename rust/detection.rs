//! Detection probability P_D(x; S): a product of factors, evaluated for one sensor pose S
//! over whole arrays of states.
//!
//! P_D(x; S) = Π_f f(x; S), each factor in [0, 1]: constants, range bands, body-frame
//! angular sectors, a land mask (0 on land) and line of sight (0 when shadowed by land).
//! The expected P_D of a Gaussian position, E[P_D(p)] with p ~ N(m, P), is evaluated with a
//! [`Rule`](crate::cubature::Rule).

use crate::batch::{check_columns, check_rows, for_each_chunk, Layout, MemoryOrder, PositionMapping, CHUNK};
use crate::cubature::{cholesky2, Rule};
use crate::error::{check_probability, ModelError, Result};
use crate::land::LandMask;
use crate::pose::{Pose, SensorFrame};
use crate::range_bands::{RangeBands, SquaredBands};
use crate::sector::{AngularSector, FramedSector};
use crate::sight::LineOfSight;
use std::sync::Arc;

#[derive(Debug, Clone)]
pub enum DetectionFactor {
    Constant(f64),
    Range(RangeBands),
    Sector(AngularSector),
    /// Land (boundary included) gets `on_land`, water 1.
    Land(Arc<LandMask>),
    /// A target shadowed from the sensor by land gets 0.
    Sight(Arc<LineOfSight>),
}

#[derive(Debug, Clone)]
pub struct DetectionModel {
    factors: Vec<DetectionFactor>,
}

impl DetectionModel {
    pub fn new(factors: Vec<DetectionFactor>) -> Result<Self> {
        for (i, f) in factors.iter().enumerate() {
            let values: Vec<f64> = match f {
                DetectionFactor::Constant(v) => vec![*v],
                DetectionFactor::Range(b) => b.values().to_vec(),
                DetectionFactor::Sector(s) => s.values().to_vec(),
                DetectionFactor::Land(_) | DetectionFactor::Sight(_) => vec![],
            };
            for v in values {
                check_probability("factors", v).map_err(|_| {
                    ModelError::invalid("factors", format!("factor {i} holds {v}, but detection probabilities must lie in [0, 1]"))
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
        let mut steps = Vec::with_capacity(self.factors.len());
        for f in &self.factors {
            match f {
                DetectionFactor::Constant(v) => constant *= v,
                DetectionFactor::Range(bands) => steps.push(match bands.squared() {
                    Some(sq) => Step::SquaredBands(sq),
                    None => Step::Bands(bands.clone()),
                }),
                DetectionFactor::Sector(s) => steps.push(Step::Sector(s.in_frame(&frame))),
                DetectionFactor::Land(land) => steps.push(Step::Land(Arc::clone(land))),
                DetectionFactor::Sight(sight) => steps.push(Step::Sight(Arc::clone(sight))),
            }
        }
        // Cheap factors first, so land and sight only run where P_D is still non-zero.
        steps.sort_by_key(|s| matches!(s, Step::Land(_) | Step::Sight(_)));
        ScanDetection { frame, steps, constant }
    }
}

#[inline(always)]
fn is_non_finite(v: f64) -> bool {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    v.to_bits() & EXPONENT == EXPONENT
}

/// Per-thread scratch for one chunk: allocated once per thread, so evaluating a chunk
/// neither allocates nor clears 40 KB of stack arrays.
pub(crate) struct Scratch {
    xs: Vec<f64>,
    ys: Vec<f64>,
    dx: Vec<f64>,
    dy: Vec<f64>,
    r2: Vec<f64>,
    band: Vec<f64>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch {
        xs: vec![0.0; CHUNK], ys: vec![0.0; CHUNK], dx: vec![0.0; CHUNK],
        dy: vec![0.0; CHUNK], r2: vec![0.0; CHUNK], band: vec![0.0; CHUNK],
    });
}

/// One factor, prepared for a pose (owned, so a scan's model can outlive the call that
/// built it: the bindings keep one per detector context).
enum Step {
    SquaredBands(SquaredBands),
    Bands(RangeBands),
    Sector(FramedSector),
    Land(Arc<LandMask>),
    Sight(Arc<LineOfSight>),
}

/// A [`DetectionModel`] at one pose.
pub struct ScanDetection {
    frame: SensorFrame,
    steps: Vec<Step>,
    constant: f64,
}

impl ScanDetection {
    /// P_D at the world points (xs[i], ys[i]) of `scratch` into out[i] (one chunk).
    /// Factor by factor over the chunk, so each loop body is small and branch-free enough
    /// for the compiler to vectorise.
    fn at_points(&self, scratch: &mut Scratch, out: &mut [f64]) {
        let n = out.len();
        let Scratch { xs, ys, dx, dy, r2, band } = scratch;
        let (xs, ys) = (&xs[..n], &ys[..n]);
        let (dx, dy, r2) = (&mut dx[..n], &mut dy[..n], &mut r2[..n]);
        let [ox, oy] = self.frame.origin;
        for i in 0..n {
            dx[i] = xs[i] - ox;
            dy[i] = ys[i] - oy;
            r2[i] = dx[i] * dx[i] + dy[i] * dy[i];
            out[i] = self.constant;
        }
        for step in &self.steps {
            match step {
                Step::SquaredBands(bands) => bands.multiply_into(r2, out, band),
                Step::Bands(bands) => {
                    for i in 0..n {
                        out[i] *= bands.at(r2[i].sqrt());
                    }
                }
                Step::Sector(sector) => {
                    for i in 0..n {
                        out[i] *= sector.at_squared(dx[i], dy[i], r2[i]);
                    }
                }
                Step::Land(land) => {
                    for i in 0..n {
                        if out[i] != 0.0 && land.contains([xs[i], ys[i]]) {
                            out[i] = 0.0;
                        }
                    }
                }
                Step::Sight(sight) => {
                    for i in 0..n {
                        if out[i] != 0.0 && !sight.visible(self.frame.origin, [xs[i], ys[i]]) {
                            out[i] = 0.0;
                        }
                    }
                }
            }
        }
    }

    /// P_D at the position of each state row. `states` is (N, ncols) row-major.
    pub fn at_states(&self, states: &[f64], ncols: usize, mapping: PositionMapping, out: &mut [f64]) -> Result<()> {
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
    pub fn at_particles(&self, particles: &[f64], ndim: usize, order: MemoryOrder, mapping: PositionMapping, out: &mut [f64]) -> Result<()> {
        check_columns(particles, ndim, out.len(), mapping, "particles")?;
        match self.at_layout(particles, order.layout(ndim, out.len()), mapping, out) {
            Some(i) => Err(ModelError::invalid("particles", format!("particle {i} (column {i}) has a NaN or infinite position"))),
            None => Ok(()),
        }
    }

    /// P_D of every state of a checked array; the first state whose position is not finite.
    fn at_layout(&self, states: &[f64], layout: Layout, mapping: PositionMapping, out: &mut [f64]) -> Option<usize> {
        for_each_chunk(out, |first, chunk| {
            let n = chunk.len();
            SCRATCH.with(|cell| {
                let scratch = &mut *cell.borrow_mut();
                let (xs, ys) = (&mut scratch.xs[..n], &mut scratch.ys[..n]);
                layout.gather(states, first, mapping, xs, ys);
                // Branch-free scan for NaN/inf (all exponent bits set); the rare bad chunk is
                // then searched for its first bad state.
                let mut non_finite = 0u64;
                for i in 0..n {
                    non_finite |= (is_non_finite(xs[i]) | is_non_finite(ys[i])) as u64;
                }
                let bad = if non_finite == 0 {
                    None
                } else {
                    (0..n).find(|&i| !(xs[i].is_finite() && ys[i].is_finite()))
                };
                self.at_points(scratch, chunk);
                bad
            })
        })
    }

    /// Expected P_D over each Gaussian N(mean_i, P_i), P_i the position block of the
    /// (ncols × ncols) covariance `covars[i]`.
    pub fn expected_at_gaussians(
        &self,
        means: &[f64],
        covars: &[f64],
        ncols: usize,
        mapping: PositionMapping,
        rule: &Rule,
        out: &mut [f64],
    ) -> Result<()> {
        mapping.check(ncols, "means")?;
        let n = check_rows(means, ncols, out.len(), "means")?;
        if covars.len() != n * ncols * ncols {
            return Err(ModelError::shape("covars", format!("must be ({n}, {ncols}, {ncols}) to match means, got {} values", covars.len())));
        }
        #[derive(Clone, Copy, PartialEq)]
        enum Bad {
            Mean,
            Covar,
        }
        let bad_kind = std::sync::Mutex::new(Vec::<(usize, Bad)>::new());
        let bad = for_each_chunk(out, |first, chunk| {
            let n = chunk.len();
            let mut mx = [0.0f64; CHUNK];
            let mut my = [0.0f64; CHUNK];
            let mut chol = [[0.0f64; 3]; CHUNK];
            let mut bad = None;
            for i in 0..n {
                let row = first + i;
                mx[i] = means[row * ncols + mapping.x];
                my[i] = means[row * ncols + mapping.y];
                let c = &covars[row * ncols * ncols..(row + 1) * ncols * ncols];
                let (ix, iy) = (mapping.x, mapping.y);
                let l = cholesky2(c[ix * ncols + ix], c[ix * ncols + iy], c[iy * ncols + ix], c[iy * ncols + iy]);
                let kind = if !(mx[i].is_finite() && my[i].is_finite()) {
                    Some(Bad::Mean)
                } else if l.is_none() {
                    Some(Bad::Covar)
                } else {
                    None
                };
                if let Some(kind) = kind {
                    if bad.is_none() {
                        bad = Some(i);
                        bad_kind.lock().unwrap().push((row, kind));
                    }
                    mx[i] = 0.0;
                    my[i] = 0.0;
                }
                chol[i] = l.unwrap_or([0.0; 3]);
            }
            chunk.fill(0.0);
            let mut value = [0.0f64; CHUNK];
            SCRATCH.with(|cell| {
                let scratch = &mut *cell.borrow_mut();
                for (u, &w) in rule.points().iter().zip(rule.weights()) {
                    for i in 0..n {
                        let [l11, l21, l22] = chol[i];
                        scratch.xs[i] = mx[i] + l11 * u[0];
                        scratch.ys[i] = my[i] + l21 * u[0] + l22 * u[1];
                    }
                    self.at_points(scratch, &mut value[..n]);
                    for i in 0..n {
                        chunk[i] += w * value[i];
                    }
                }
            });
            // Rounding can push a weighted sum of values in [0, 1] a hair outside.
            for v in chunk.iter_mut() {
                *v = v.clamp(0.0, 1.0);
            }
            bad
        });
        if let Some(row) = bad {
            let kinds = bad_kind.into_inner().unwrap();
            let kind = kinds.iter().find(|(r, _)| *r == row).map(|(_, k)| *k).unwrap_or(Bad::Mean);
            return Err(match kind {
                Bad::Mean => ModelError::non_finite("means", row, "position is NaN or infinite"),
                Bad::Covar => ModelError::invalid(
                    "covars",
                    format!("row {row}: the position block is not a finite symmetric positive semi-definite matrix"),
                ),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod column_tests;

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn radar() -> DetectionModel {
        DetectionModel::new(vec![
            DetectionFactor::Range(RangeBands::new(vec![50.0, 1612.0], vec![0.0, 0.4, 0.0], vec![false, true]).unwrap()),
            DetectionFactor::Sector(AngularSector::new(PI, 65f64.to_radians(), 0.0, 1.0).unwrap()),
        ])
        .unwrap()
    }

    #[test]
    fn radar_at_states_with_heading() {
        let model = radar();
        let pose = Pose::new(100.0, 0.0, PI / 2.0).unwrap(); // facing +y
        let scan = model.at_pose(&pose);
        // rows [x, vx, y, vy]: ahead 500 m, astern 500 m, abeam 1000 m, 40 m, 1700 m.
        let states = [
            100.0, 0.0, 500.0, 0.0, 100.0, 0.0, -500.0, 0.0, 1100.0, 0.0, 0.0, 0.0, 140.0, 0.0, 0.0, 0.0, 100.0, 0.0, 1700.0,
            0.0,
        ];
        let mut out = [9.0; 5];
        scan.at_states(&states, 4, PositionMapping::default(), &mut out).unwrap();
        assert_eq!(out, [0.4, 0.0, 0.4, 0.0, 0.0]);
    }

    #[test]
    fn many_rows_in_parallel_match_serial() {
        let model = radar();
        let scan = model.at_pose(&Pose::new(3.0, -7.0, 0.7).unwrap());
        let n = 100_003;
        let states: Vec<f64> = (0..n * 4).map(|k| ((k as f64) * 0.618).sin() * 2000.0).collect();
        let mut out = vec![0.0; n];
        scan.at_states(&states, 4, PositionMapping::default(), &mut out).unwrap();
        for i in (0..n).step_by(997) {
            let mut one = [0.0];
            scan.at_states(&states[i * 4..i * 4 + 4], 4, PositionMapping::default(), &mut one).unwrap();
            assert_eq!(one[0], out[i]);
        }
    }

    #[test]
    fn first_bad_row_is_named() {
        let model = radar();
        let scan = model.at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
        let n = 70_000;
        let mut states = vec![1.0; n * 4];
        states[50_001 * 4 + 2] = f64::NAN;
        states[60_000 * 4] = f64::INFINITY;
        let mut out = vec![0.0; n];
        let err = scan.at_states(&states, 4, PositionMapping::default(), &mut out).unwrap_err();
        assert_eq!(err, ModelError::non_finite("states", 50_001, "position is NaN or infinite"));
        let err = scan.at_states(&states, 2, PositionMapping::default(), &mut vec![0.0; n * 2]).unwrap_err();
        assert_eq!(err.argument(), "states");
    }

    #[test]
    fn probabilities_outside_unit_interval_are_rejected() {
        let err = DetectionModel::new(vec![DetectionFactor::Constant(1.5)]).unwrap_err();
        assert_eq!(err.argument(), "factors");
    }

    #[test]
    fn expected_pd_of_point_mass_is_pd_at_mean() {
        let model = radar();
        let scan = model.at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
        let means = [300.0, 1.0, 20.0, 1.0];
        let covars = [0.0; 16];
        let mut out = [0.0];
        scan.expected_at_gaussians(&means, &covars, 4, PositionMapping::default(), &Rule::gauss_hermite(5).unwrap(), &mut out).unwrap();
        assert!((out[0] - 0.4).abs() < 1e-12);
    }

    #[test]
    fn expected_pd_straddling_an_edge() {
        // Lidar-like bands, Gaussian centred on the 50 m edge with σ = 10 m along range:
        // about half the mass on each side.
        let model = DetectionModel::new(vec![DetectionFactor::Range(
            RangeBands::new(vec![50.0], vec![1.0, 0.0], vec![true]).unwrap(),
        )])
        .unwrap();
        let scan = model.at_pose(&Pose::new(0.0, 0.0, 0.0).unwrap());
        let means = [50.0, 0.0, 0.0, 0.0];
        let mut covars = [0.0; 16];
        covars[0] = 100.0;
        covars[10] = 1e-6;
        let mut out = [0.0];
        scan.expected_at_gaussians(&means, &covars, 4, PositionMapping::default(), &Rule::gauss_hermite(20).unwrap(), &mut out).unwrap();
        assert!((out[0] - 0.5).abs() < 0.05, "{}", out[0]);
        covars[2] = 1e3; // not symmetric
        let err = scan.expected_at_gaussians(&means, &covars, 4, PositionMapping::default(), &Rule::cubature(), &mut out).unwrap_err();
        assert_eq!(err.argument(), "covars");
    }
}
