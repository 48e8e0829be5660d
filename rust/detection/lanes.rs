//! The P_D kernels, four states at a time and fused: positions are read from the caller's
//! rows, every range and sector factor is applied in registers, and the product is stored
//! once. Land and line of sight then run point by point on the lanes still non-zero.
//! Written once over [`Lanes`]; [`crate::simd::dispatch`] picks the CPU's build. Each
//! kernel gives the bits of [`ScanDetection::at_point`] (tested for every backend).

use super::{Offsets, ScanDetection, Step, Tilted};
use crate::batch::{CvRows, Heights, Planar, PositionMapping, Positions, RowHeights, Rows, Velocities};
use crate::cubature::{
    cholesky2_lanes, cholesky3, is_positive_semidefinite, velocity_at_point, velocity_given_position, Rule, SpatialRule,
};
use crate::elevation::ElevationSector;
use crate::horizon::Horizon;
use crate::radar::OnePulseAtRange;
use crate::range_bands::{OneEdge, SquaredBands};
use crate::sector::FramedSector;
use crate::simd::{LaneKernel, Lanes};

impl Step {
    #[inline(always)]
    fn lanes_at<L: Lanes>(&self, g: &Offsets<L>) -> L {
        match self {
            Step::SquaredBands(bands) => bands.lanes_at_squared(g.r2),
            // (bands.lanes_at(r2.sqrt()), without the square root: the same bits)
            Step::Bands(bands) => bands.lanes_at_root(g.r2),
            Step::Sector(sector) => sector.lanes_at_squared(g.dx, g.dy, g.h2),
            Step::Radar(radar) => radar.lanes_at_squared(g.r2),
            Step::Elevation(e) => e.lanes_at(g.dz, g.r2),
            Step::Horizon(h) => h.lanes_at(g.h2, g.z),
            Step::RangeRate(n) => n.lanes_at(g.dot, g.r2),
            Step::TiltedSector(t) => t.lanes_at(g),
            Step::TiltedElevation(t) => t.lanes_at(g),
        }
    }
}

impl Tilted<FramedSector> {
    #[inline(always)]
    fn lanes_at<L: Lanes>(&self, g: &Offsets<L>) -> L {
        let [a, b, _] = self.rows;
        let sx = L::splat(a[0]) * g.dx + L::splat(a[1]) * g.dy + L::splat(a[2]) * g.dz;
        let sy = L::splat(b[0]) * g.dx + L::splat(b[1]) * g.dy + L::splat(b[2]) * g.dz;
        self.factor.lanes_at_squared(sx, sy, sx * sx + sy * sy)
    }
}

impl Tilted<ElevationSector> {
    #[inline(always)]
    fn lanes_at<L: Lanes>(&self, g: &Offsets<L>) -> L {
        let c = self.rows[2];
        let sz = L::splat(c[0]) * g.dx + L::splat(c[1]) * g.dy + L::splat(c[2]) * g.dz;
        self.factor.lanes_at(sz, g.r2)
    }
}

/// A scan's range and sector steps with their kinds fixed at compile time, so that a
/// kernel's loop holds no dispatch on the kind of each step (the common models: the
/// paper's radar and lidar). `apply` multiplies `pd` by each step's value in order: the
/// same bits as the general slice of steps.
trait FixedSteps: Copy {
    fn apply<L: Lanes>(self, pd: L, g: &Offsets<L>) -> L;
}

impl FixedSteps for () {
    #[inline(always)]
    fn apply<L: Lanes>(self, pd: L, _: &Offsets<L>) -> L {
        pd
    }
}

impl FixedSteps for &SquaredBands {
    #[inline(always)]
    fn apply<L: Lanes>(self, pd: L, g: &Offsets<L>) -> L {
        pd * self.lanes_at_squared(g.r2)
    }
}

impl FixedSteps for &FramedSector {
    #[inline(always)]
    fn apply<L: Lanes>(self, pd: L, g: &Offsets<L>) -> L {
        pd * self.lanes_at_squared(g.dx, g.dy, g.h2)
    }
}

impl FixedSteps for &ElevationSector {
    #[inline(always)]
    fn apply<L: Lanes>(self, pd: L, g: &Offsets<L>) -> L {
        pd * self.lanes_at(g.dz, g.r2)
    }
}

impl FixedSteps for &Horizon {
    #[inline(always)]
    fn apply<L: Lanes>(self, pd: L, g: &Offsets<L>) -> L {
        pd * self.lanes_at(g.h2, g.z)
    }
}

impl FixedSteps for OneEdge {
    #[inline(always)]
    fn apply<L: Lanes>(self, pd: L, g: &Offsets<L>) -> L {
        pd * self.lanes_at_squared(g.r2)
    }
}

/// A one-pulse radar equation whose form (exponential or not) is fixed at compile time.
#[derive(Clone, Copy)]
struct OnePulseForm<const EXPONENTIAL: bool>(OnePulseAtRange);

impl<const EXPONENTIAL: bool> FixedSteps for OnePulseForm<EXPONENTIAL> {
    #[inline(always)]
    fn apply<L: Lanes>(self, pd: L, g: &Offsets<L>) -> L {
        pd * self.0.lanes_form::<L, EXPONENTIAL>(g.r2)
    }
}

/// A sector at most a half-plane wide ([`FramedSector::is_narrow`]), known to be so.
#[derive(Clone, Copy)]
struct Narrow<'a>(&'a FramedSector);

impl FixedSteps for Narrow<'_> {
    #[inline(always)]
    fn apply<L: Lanes>(self, pd: L, g: &Offsets<L>) -> L {
        pd * self.0.lanes_narrow(g.dx, g.dy, g.h2)
    }
}

impl<A: FixedSteps, B: FixedSteps> FixedSteps for (A, B) {
    #[inline(always)]
    fn apply<L: Lanes>(self, pd: L, g: &Offsets<L>) -> L {
        self.1.apply(self.0.apply(pd, g), g)
    }
}

/// The steps without the range-rate notch: the expected P_D with velocities takes the
/// notch's expectation apart ([`ScanDetection::at_state_uncertain`]).
#[derive(Clone, Copy)]
struct SkipNotch<'a>(&'a [Step]);

impl FixedSteps for SkipNotch<'_> {
    #[inline(always)]
    fn apply<L: Lanes>(self, mut pd: L, g: &Offsets<L>) -> L {
        for step in self.0 {
            if !matches!(step, Step::RangeRate(_)) {
                pd = pd * step.lanes_at(g);
            }
        }
        pd
    }
}

/// Any other sequence, dispatched step by step.
impl FixedSteps for &[Step] {
    #[inline(always)]
    fn apply<L: Lanes>(self, mut pd: L, g: &Offsets<L>) -> L {
        for step in self {
            pd = pd * step.lanes_at(g);
        }
        pd
    }
}

/// `$body` with `$steps` bound to the scan's steps as a [`FixedSteps`] and the constant
/// `$indexed` to whether it has land or sight steps: a specialised copy of the body for
/// each common sequence, the general one for the rest.
macro_rules! with_fixed_steps {
    ($scan:expr, $steps:ident, $indexed:ident => $body:expr) => {
        if $scan.indexed.is_empty() {
            const $indexed: bool = false;
            with_fixed_steps!(@steps $scan, $steps => $body)
        } else {
            const $indexed: bool = true;
            with_fixed_steps!(@steps $scan, $steps => $body)
        }
    };
    (@steps $scan:expr, $steps:ident => $body:expr) => {
        match $scan.steps.as_slice() {
            [] => {
                let $steps = ();
                $body
            }
            [Step::SquaredBands(a)] => {
                let $steps = a;
                $body
            }
            [Step::Sector(a)] => {
                let $steps = a;
                $body
            }
            [Step::Elevation(a)] => {
                let $steps = a;
                $body
            }
            [Step::SquaredBands(a), Step::Sector(b)] if b.is_narrow() => {
                let $steps = (a, Narrow(b));
                $body
            }
            [Step::SquaredBands(a), Step::Sector(b)] => {
                let $steps = (a, b);
                $body
            }
            [Step::Sector(a), Step::SquaredBands(b)] => {
                let $steps = (a, b);
                $body
            }
            // a 3-D surveillance beam: slant range, elevation, the horizon at each height
            [Step::SquaredBands(a), Step::Elevation(b), Step::Horizon(c)] => {
                let $steps = ((a, b), c);
                $body
            }
            other => {
                let $steps = other;
                $body
            }
        }
    };
}

impl ScanDetection {
    /// [`Self::at_point`] (or, with heights `H`, [`Self::at_raised`]) at four world
    /// points, and the squared ranges: infinite or NaN where a position is (or, rarely,
    /// where a finite one is very far away).
    /// `INDEXED`: whether the scan has land or sight steps (`!self.indexed.is_empty()`),
    /// fixed at compile time so that the common loop carries none of their code.
    #[inline(always)]
    fn lanes_at<L: Lanes, S: FixedSteps, H: Heights, V: Velocities, const INDEXED: bool>(
        &self,
        steps: S,
        x: L,
        y: L,
        z: L,
        v: [L; 3],
    ) -> (L, L) {
        let [ox, oy] = self.frame.origin;
        let (dx, dy) = (x - L::splat(ox), y - L::splat(oy));
        let h2 = dx * dx + dy * dy;
        let oz = L::splat(self.frame.height);
        let (dz, r2, z) = if H::RAISED {
            let dz = z - oz;
            (dz, h2 + dz * dz, z)
        } else {
            (L::splat(0.0), h2, oz)
        };
        let dot = if V::MOVING {
            let [px, py, pz] = self.frame.velocity;
            let (px, py, pz) = (L::splat(px), L::splat(py), L::splat(pz));
            let plane = dx * (v[0] - px) + dy * (v[1] - py);
            if H::RAISED {
                plane + dz * (v[2] - pz)
            } else {
                plane
            }
        } else {
            L::splat(0.0)
        };
        let g = Offsets {
            dx,
            dy,
            h2,
            dz,
            r2,
            z,
            dot,
        };
        // Not finite where a position is (or a velocity read), or, rarely, where a finite one
        // is very far away (r² + 0·dot: r² itself unless the velocity product is not finite).
        let r2 = if V::MOVING { r2 + dot * L::splat(0.0) } else { r2 };
        let pd = steps.apply(L::splat(self.constant), &g);
        if !INDEXED {
            return (pd, r2);
        }
        let (xs, ys, mut pds) = (x.to_array(), y.to_array(), pd.to_array());
        for l in 0..4 {
            pds[l] = self.indexed_at(xs[l], ys[l], pds[l]);
        }
        (L::from_array(pds), r2)
    }
}

/// P_D of states `first..first + out.len()`; the index (in `out`) of the first state whose
/// position is not finite.
pub(super) struct AtStates<'a, P, H, V> {
    pub scan: &'a ScanDetection,
    pub positions: P,
    pub heights: H,
    pub velocities: V,
    pub first: usize,
    pub out: &'a mut [f64],
}

impl<P: Positions, H: Heights, V: Velocities> LaneKernel for AtStates<'_, P, H, V> {
    type Output = Option<usize>;

    #[inline(always)]
    fn run<L: Lanes>(self) -> Option<usize> {
        // A lone factor with a cheaper fixed form, without land or sight: here only, not in
        // the expected kernels, as each specialisation adds to one function's stack frame
        // in unoptimised builds.
        if self.scan.indexed.is_empty() {
            match self.scan.steps.as_slice() {
                [Step::SquaredBands(a)] => {
                    if let Some(edge) = a.one_edge() {
                        return self.run_with::<L, _, false>(edge);
                    }
                }
                [Step::Radar(a)] => match a.one_pulse() {
                    Some(p) if p.is_exponential() => return self.run_with::<L, _, false>(OnePulseForm::<true>(p)),
                    Some(p) => return self.run_with::<L, _, false>(OnePulseForm::<false>(p)),
                    None => {}
                },
                _ => {}
            }
        }
        with_fixed_steps!(self.scan, steps, INDEXED => self.run_with::<L, _, INDEXED>(steps))
    }
}

impl<P: Positions, H: Heights, V: Velocities> AtStates<'_, P, H, V> {
    #[inline(always)]
    fn run_with<L: Lanes, S: FixedSteps, const INDEXED: bool>(self, steps: S) -> Option<usize> {
        let AtStates {
            scan,
            positions,
            heights,
            velocities,
            first,
            out,
        } = self;
        let n = out.len();
        let full = n - n % 4;
        // A non-finite position makes r² non-finite: noted in one branch-free mask, and
        // the chunk searched afterwards (a finite position so far away that r² overflows
        // costs that search and is not reported).
        let mut bad = L::none();
        // Exact chunks: the stores need no bounds checks.
        for (j, o) in out[..full].chunks_exact_mut(4).enumerate() {
            let (x, y) = positions.lanes::<L>(first + 4 * j);
            let z = heights.lanes::<L>(first + 4 * j);
            let v = velocities.lanes::<L>(first + 4 * j);
            let (pd, r2) = scan.lanes_at::<L, S, H, V, INDEXED>(steps, x, y, z, v);
            bad = L::or(bad, r2.non_finite());
            pd.store(o);
        }
        if full < n {
            let (x, y) = positions.partial::<L>(first + full, n - full);
            let z = heights.partial::<L>(first + full, n - full);
            let v = velocities.partial::<L>(first + full, n - full);
            let (pd, r2) = scan.lanes_at::<L, S, H, V, INDEXED>(steps, x, y, z, v);
            bad = L::or(bad, r2.non_finite());
            out[full..].copy_from_slice(&pd.to_array()[..n - full]);
        }
        if !L::any(bad) {
            return None;
        }
        (0..n).find(|&i| {
            let finite = |v: &f64| v.is_finite();
            !(positions.one(first + i).iter().all(finite)
                && heights.one(first + i).is_finite()
                && velocities.one(first + i).iter().all(finite))
        })
    }
}

/// `$body` with `$steps` the scan's steps without its notch, as [`SkipNotch`], and `$indexed`
/// as in [`with_fixed_steps`].
macro_rules! without_notch {
    ($scan:expr, $steps:ident, $indexed:ident => $body:expr) => {{
        let $steps = SkipNotch(&$scan.steps);
        if $scan.indexed.is_empty() {
            const $indexed: bool = false;
            $body
        } else {
            const $indexed: bool = true;
            $body
        }
    }};
}

/// What is wrong with a Gaussian that cannot be evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum BadGaussian {
    Mean,
    Covar,
    /// The covariance of the position and the velocity a notch reads, together.
    Velocity,
}

/// Means (N, ncols) and their (N, ncols, ncols) covariances.
#[derive(Clone, Copy)]
pub(super) struct Gaussians<'a> {
    pub means: Rows<'a>,
    pub covars: &'a [f64],
}

impl Gaussians<'_> {
    /// The (x, y, z) block of row `row`'s covariance, z the height column, row-major.
    #[inline(always)]
    fn block3(self, row: usize, z: usize) -> [f64; 9] {
        let k = self.means.ncols;
        let c = &self.covars[row * k * k..][..k * k];
        let axes = [self.means.mapping.x, self.means.mapping.y, z];
        let mut block = [0.0; 9];
        for (a, &i) in axes.iter().enumerate() {
            for (b, &j) in axes.iter().enumerate() {
                block[3 * a + b] = c[i * k + j];
            }
        }
        block
    }

    /// Entry `e` (row-major) of the covariances of the `count` ≤ 4 Gaussians from `first`,
    /// zero-padded. A method, not a closure: closures are compiled apart from the kernel,
    /// without its AVX2, and cost a call per use.
    #[inline(always)]
    fn entry<L: Lanes>(self, first: usize, count: usize, e: usize) -> L {
        let size = self.means.ncols * self.means.ncols;
        if count == 4 {
            // One bounds check for the four matrices, none per entry.
            let c = &self.covars[first * size..(first + 4) * size];
            return L::from_array([c[e], c[size + e], c[2 * size + e], c[3 * size + e]]);
        }
        let at = |i: usize| {
            if i < count {
                self.covars[(first + i) * size + e]
            } else {
                0.0
            }
        };
        L::from_array([at(0), at(1), at(2), at(3)])
    }

    /// The velocity of row `row` given its position ([`velocity_given_position`]), the
    /// position block being `l` (lower triangular) on `positions`, the velocity in columns
    /// `velocities`: (B, the covariance left), or None where the covariance of the position
    /// and the velocity together is not finite, symmetric and positive semi-definite.
    #[allow(clippy::type_complexity)]
    fn velocity_spread<const D: usize>(
        self,
        row: usize,
        l: [[f64; D]; D],
        positions: [usize; D],
        velocities: [usize; D],
    ) -> Option<([[f64; 3]; 3], [[f64; 3]; 3])> {
        let k = self.means.ncols;
        let c = &self.covars[row * k * k..][..k * k];
        let (mut cross, mut block) = ([[0.0; D]; D], [[0.0; D]; D]);
        for (i, &vi) in velocities.iter().enumerate() {
            for j in 0..D {
                cross[i][j] = c[vi * k + positions[j]];
                block[i][j] = c[vi * k + velocities[j]];
            }
        }
        // the joint block of the positions and the velocity, as the state orders neither
        let mut joint = [0.0; 36];
        let axes = positions.iter().chain(&velocities);
        for (a, &i) in axes.clone().enumerate() {
            for (b, &j) in axes.clone().enumerate() {
                joint[a * 2 * D + b] = c[i * k + j];
            }
        }
        if !is_positive_semidefinite(&joint[..4 * D * D], 2 * D) {
            return None;
        }
        let (b, left) = velocity_given_position(l, cross, block);
        b.iter()
            .chain(&left)
            .flatten()
            .all(|v| v.is_finite())
            .then_some((b, left))
    }

    /// The (x, y) columns and the (vx, vy) columns (the latter zero without velocities).
    fn planar_axes(self) -> ([usize; 2], [usize; 2]) {
        let m = self.means.mapping;
        let v = m.velocity.map_or([0, 0], |v| [v.vx, v.vy]);
        ([m.x, m.y], v)
    }

    /// Means, the Cholesky factors [l11, l21, l22] of the position blocks and a mask of the
    /// Gaussians that cannot be evaluated, for the `count` ≤ 4 Gaussians from `first`
    /// (padding lanes are point masses at the origin).
    #[inline(always)]
    fn lanes<L: Lanes>(self, first: usize, count: usize) -> (L, L, [L; 3], L::Mask, L::Mask) {
        let k = self.means.ncols;
        let (ix, iy) = (self.means.mapping.x, self.means.mapping.y);
        let (mx, my) = match count {
            4 if k == 4 && self.means.mapping == PositionMapping::default() => {
                Positions::lanes::<L>(CvRows(self.means.data), first)
            }
            4 => self.means.lanes::<L>(first),
            _ => self.means.partial::<L>(first, count),
        };
        let (a, b) = (
            self.entry::<L>(first, count, ix * k + ix),
            self.entry::<L>(first, count, ix * k + iy),
        );
        let (b_t, c) = (
            self.entry::<L>(first, count, iy * k + ix),
            self.entry::<L>(first, count, iy * k + iy),
        );
        let (bad_covar, l) = cholesky2_lanes(a, b, b_t, c);
        (mx, my, l, L::or(mx.non_finite(), my.non_finite()), bad_covar)
    }
}

/// Expected P_D of Gaussians `first..first + out.len()` under `rule`: the points m + L u
/// are made and evaluated in the same pass, four Gaussians at a time. The first Gaussian
/// that cannot be evaluated, with the reason (its own entry is then meaningless).
pub(super) struct Expected<'a, V> {
    pub scan: &'a ScanDetection,
    pub gaussians: Gaussians<'a>,
    /// The velocity at each mean (the rule's points are in position; a notch is
    /// integrated over the velocity given each point).
    pub velocities: V,
    pub rule: &'a Rule,
    pub first: usize,
    pub out: &'a mut [f64],
}

impl<V: Velocities> LaneKernel for Expected<'_, V> {
    type Output = Option<(usize, BadGaussian)>;

    #[inline(always)]
    fn run<L: Lanes>(self) -> Self::Output {
        if V::MOVING {
            without_notch!(self.scan, steps, INDEXED => self.run_with::<L, _, INDEXED>(steps))
        } else {
            with_fixed_steps!(self.scan, steps, INDEXED => self.run_with::<L, _, INDEXED>(steps))
        }
    }
}

impl<V: Velocities> Expected<'_, V> {
    #[inline(always)]
    fn run_with<L: Lanes, S: FixedSteps, const INDEXED: bool>(self, steps: S) -> <Self as LaneKernel>::Output {
        let Expected {
            scan,
            gaussians,
            velocities,
            rule,
            first,
            out,
        } = self;
        let mut bad = None;
        let (zero, one) = (L::splat(0.0), L::splat(1.0));
        // Factors for GROUP blocks first, then their points: each Cholesky factor is a chain
        // of two square roots and a division, and a short loop of independent ones lets the
        // CPU overlap them.
        const GROUP: usize = 16;
        let mut factors = [[zero; 8]; GROUP];
        // With velocities (V::MOVING, the steps without the notch): each Gaussian's velocity
        // given its position, (B, the covariance left), for the notch's expectation.
        let mut spreads = [[([[0.0; 3]; 3], [[0.0; 3]; 3]); 4]; GROUP];
        let (axes, speeds) = gaussians.planar_axes();
        for (g, group) in out.chunks_mut(4 * GROUP).enumerate() {
            let start = 4 * GROUP * g;
            for (j, block) in group.chunks(4).enumerate() {
                let (mut mx, mut my, mut l, mut bad_mean, bad_covar) =
                    gaussians.lanes::<L>(first + start + 4 * j, block.len());
                let mut bad_velocity = L::none();
                if V::MOVING {
                    let [l11, l21, l22] = [l[0].to_array(), l[1].to_array(), l[2].to_array()];
                    let mut refused = [0.0; 4];
                    for (i, flag) in refused.iter_mut().enumerate().take(block.len()) {
                        let factor = [[l11[i], 0.0], [l21[i], l22[i]]];
                        match gaussians.velocity_spread(first + start + 4 * j + i, factor, axes, speeds) {
                            Some(spread) => spreads[j][i] = spread,
                            None => *flag = 1.0,
                        }
                    }
                    bad_velocity = L::select(bad_covar, zero, L::from_array(refused)).gt(zero);
                }
                let mut v = match block.len() {
                    4 => velocities.lanes::<L>(first + start + 4 * j),
                    count => velocities.partial::<L>(first + start + 4 * j, count),
                };
                if V::MOVING {
                    bad_mean = L::or(
                        bad_mean,
                        L::or(v[0].non_finite(), L::or(v[1].non_finite(), v[2].non_finite())),
                    );
                }
                let unusable = L::or(bad_mean, L::or(bad_covar, bad_velocity));
                if L::any(unusable) {
                    // Said for the first such Gaussian; evaluated as a point mass at the
                    // origin in its place.
                    let (mean, position, either) = (
                        L::select(bad_mean, one, zero).to_array(),
                        L::select(bad_covar, one, zero).to_array(),
                        L::select(unusable, one, zero).to_array(),
                    );
                    for (i, spread) in spreads[j].iter_mut().enumerate() {
                        if either[i] != 0.0 {
                            *spread = Default::default();
                        }
                    }
                    if let Some(i) = (0..block.len()).find(|&i| either[i] != 0.0) {
                        bad = bad.or(Some((
                            start + 4 * j + i,
                            if mean[i] != 0.0 {
                                BadGaussian::Mean
                            } else if position[i] != 0.0 {
                                BadGaussian::Covar
                            } else {
                                BadGaussian::Velocity
                            },
                        )));
                    }
                    (mx, my) = (L::select(unusable, zero, mx), L::select(unusable, zero, my));
                    l = [
                        L::select(unusable, zero, l[0]),
                        L::select(unusable, zero, l[1]),
                        L::select(unusable, zero, l[2]),
                    ];
                    v = [
                        L::select(unusable, zero, v[0]),
                        L::select(unusable, zero, v[1]),
                        L::select(unusable, zero, v[2]),
                    ];
                }
                factors[j] = [mx, my, l[0], l[1], l[2], v[0], v[1], v[2]];
            }
            for (j, block) in group.chunks_mut(4).enumerate() {
                let [mx, my, l11, l21, l22, vx, vy, vz] = factors[j];
                let mut expected = zero;
                for (u, &w) in rule.points().iter().zip(rule.weights()) {
                    let (u0, u1) = (L::splat(u[0]), L::splat(u[1]));
                    let (x, y) = (mx + l11 * u0, my + l21 * u0 + l22 * u1);
                    let mut point = scan
                        .lanes_at::<L, S, Planar, V, INDEXED>(steps, x, y, zero, [vx, vy, vz])
                        .0;
                    if V::MOVING {
                        let (xs, ys, vxs, vys) = (x.to_array(), y.to_array(), vx.to_array(), vy.to_array());
                        let mut notch = [1.0; 4];
                        for (i, value) in notch.iter_mut().enumerate() {
                            let (b, left) = &spreads[j][i];
                            let v = velocity_at_point([vxs[i], vys[i], 0.0], b, [u[0], u[1], 0.0]);
                            *value = scan.notch_at(xs[i], ys[i], None, v, left);
                        }
                        point = point * L::from_array(notch);
                    }
                    expected = expected + L::splat(w) * point;
                }
                // Rounding can push a weighted sum of values in [0, 1] a hair outside.
                expected = L::select(expected.lt(zero), zero, L::select(expected.gt(one), one, expected));
                if block.len() == 4 {
                    expected.store(block);
                } else {
                    block.copy_from_slice(&expected.to_array()[..block.len()]);
                }
            }
        }
        bad
    }
}

/// Expected P_D of Gaussians with heights `first..first + out.len()` under the 3-D form of
/// a rule: each Gaussian's 3×3 position block factored once ([`cholesky3`]), its points
/// m + L u evaluated four Gaussians at a time. The first Gaussian that cannot be evaluated,
/// with the reason (its own entry is then meaningless).
pub(super) struct ExpectedRaised<'a, V> {
    pub scan: &'a ScanDetection,
    pub gaussians: Gaussians<'a>,
    pub heights: RowHeights<'a>,
    /// The velocity at each mean (the rule's points are in position; a notch is
    /// integrated over the velocity given each point).
    pub velocities: V,
    pub rule: &'a SpatialRule,
    pub first: usize,
    pub out: &'a mut [f64],
}

impl<V: Velocities> LaneKernel for ExpectedRaised<'_, V> {
    type Output = Option<(usize, BadGaussian)>;

    #[inline(always)]
    fn run<L: Lanes>(self) -> Self::Output {
        if V::MOVING {
            without_notch!(self.scan, steps, INDEXED => self.run_with::<L, _, INDEXED>(steps))
        } else {
            with_fixed_steps!(self.scan, steps, INDEXED => self.run_with::<L, _, INDEXED>(steps))
        }
    }
}

impl<V: Velocities> ExpectedRaised<'_, V> {
    #[inline(always)]
    fn run_with<L: Lanes, S: FixedSteps, const INDEXED: bool>(self, steps: S) -> <Self as LaneKernel>::Output {
        let ExpectedRaised {
            scan,
            gaussians,
            heights,
            velocities,
            rule,
            first,
            out,
        } = self;
        let mut bad = None;
        let (zero, one) = (L::splat(0.0), L::splat(1.0));
        for (j, block) in out.chunks_mut(4).enumerate() {
            // Lane by lane: the mean and the factor, or a point mass at the origin in the
            // place of a Gaussian that cannot be evaluated (said for the first).
            let (mut m, mut l, mut vs) = ([[0.0; 4]; 3], [[0.0; 4]; 6], [[0.0; 4]; 3]);
            let mut spreads = [([[0.0; 3]; 3], [[0.0; 3]; 3]); 4];
            for (i, _) in block.iter().enumerate() {
                let row = first + 4 * j + i;
                let [x, y] = gaussians.means.one(row);
                let z = heights.one(row);
                let velocity = velocities.one(row);
                let factor = cholesky3(gaussians.block3(row, heights.z));
                // the velocity given the position, when a notch reads it
                let spread = match (V::MOVING, factor, gaussians.means.mapping.velocity) {
                    (true, Some([l11, l21, l22, l31, l32, l33]), Some(v)) => gaussians.velocity_spread(
                        row,
                        [[l11, 0.0, 0.0], [l21, l22, 0.0], [l31, l32, l33]],
                        [gaussians.means.mapping.x, gaussians.means.mapping.y, heights.z],
                        [v.vx, v.vy, v.vz.unwrap_or(v.vx)], // (vz is there: a raised mapping's velocity has three)
                    ),
                    _ => Some(Default::default()),
                };
                let problem =
                    if !(x.is_finite() && y.is_finite() && z.is_finite() && velocity.iter().all(|v| v.is_finite())) {
                        Some(BadGaussian::Mean)
                    } else if factor.is_none() {
                        Some(BadGaussian::Covar)
                    } else if spread.is_none() {
                        Some(BadGaussian::Velocity)
                    } else {
                        None
                    };
                if let Some(kind) = problem {
                    bad = bad.or(Some((4 * j + i, kind)));
                    continue;
                }
                for (k, v) in [x, y, z].into_iter().enumerate() {
                    m[k][i] = v;
                }
                for (k, v) in factor.unwrap_or_default().into_iter().enumerate() {
                    l[k][i] = v;
                }
                for (k, v) in velocity.into_iter().enumerate() {
                    vs[k][i] = v;
                }
                spreads[i] = spread.unwrap_or_default();
            }
            let [mx, my, mz] = [L::from_array(m[0]), L::from_array(m[1]), L::from_array(m[2])];
            let velocity = [L::from_array(vs[0]), L::from_array(vs[1]), L::from_array(vs[2])];
            let [l11, l21, l22, l31, l32, l33] = [
                L::from_array(l[0]),
                L::from_array(l[1]),
                L::from_array(l[2]),
                L::from_array(l[3]),
                L::from_array(l[4]),
                L::from_array(l[5]),
            ];
            let mut expected = zero;
            for (u, &w) in rule.points().iter().zip(rule.weights()) {
                let (u0, u1, u2) = (L::splat(u[0]), L::splat(u[1]), L::splat(u[2]));
                let x = mx + l11 * u0;
                let y = my + l21 * u0 + l22 * u1;
                let z = mz + l31 * u0 + l32 * u1 + l33 * u2;
                let mut point = scan
                    .lanes_at::<L, S, RowHeights, V, INDEXED>(steps, x, y, z, velocity)
                    .0;
                if V::MOVING {
                    let (xs, ys, zs) = (x.to_array(), y.to_array(), z.to_array());
                    let mut notch = [1.0; 4];
                    for (i, value) in notch.iter_mut().enumerate() {
                        let (b, left) = &spreads[i];
                        let v = velocity_at_point([vs[0][i], vs[1][i], vs[2][i]], b, *u);
                        *value = scan.notch_at(xs[i], ys[i], Some(zs[i]), v, left);
                    }
                    point = point * L::from_array(notch);
                }
                expected = expected + L::splat(w) * point;
            }
            expected = L::select(expected.lt(zero), zero, L::select(expected.gt(one), one, expected));
            block.copy_from_slice(&expected.to_array()[..block.len()]);
        }
        bad
    }
}

/// The scalar formula for one Gaussian with a height, for tests: Σ_k w_k P_D(m + L u_k),
/// clamped, L = [l11, l21, l22, l31, l32, l33].
#[cfg(test)]
pub(super) fn expected_raised_reference(scan: &ScanDetection, mean: [f64; 3], l: [f64; 6], rule: &SpatialRule) -> f64 {
    let mut expected = 0.0;
    for (u, &w) in rule.points().iter().zip(rule.weights()) {
        let x = mean[0] + l[0] * u[0];
        let y = mean[1] + l[1] * u[0] + l[2] * u[1];
        let z = mean[2] + l[3] * u[0] + l[4] * u[1] + l[5] * u[2];
        expected += w * scan.at_raised(x, y, z);
    }
    expected.clamp(0.0, 1.0)
}

/// The scalar formula for one Gaussian, for tests: Σ_k w_k P_D(m + L u_k), clamped.
#[cfg(test)]
pub(super) fn expected_reference(scan: &ScanDetection, mean: [f64; 2], l: [f64; 3], rule: &Rule) -> f64 {
    let mut expected = 0.0;
    for (u, &w) in rule.points().iter().zip(rule.weights()) {
        let (x, y) = (mean[0] + l[0] * u[0], mean[1] + l[1] * u[0] + l[2] * u[1]);
        expected += w * scan.at_point(x, y);
    }
    expected.clamp(0.0, 1.0)
}
