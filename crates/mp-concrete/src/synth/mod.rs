//! Synthesis of a concrete program from a track (paper §3.1): the shared
//! segmentation minimising Σ segments (Σ joints best-fit error + λ) is found
//! by [`Segmentation::search`] — an exact branch and bound over the DP of
//! [`crate::dp`] with segment moments updated in O(1) per candidate and lower
//! bounds of the fit errors ([`crate::search`], module docs there) — and the
//! chosen segments are fitted once more with [`mp_geom::fit_best`] (in
//! parallel) to get their primitives. The costs are those of `fit_best` on
//! every candidate segment `k..n` of at most `W` frames;
//! [`Segmentation::exhaustive`] still computes them all into a [`CostTable`]
//! and is the reference the tests compare with (same optimum; `O(T·W)`
//! memory and `O(T·W²·J)` time).
//!
//! The parameters (scale, λ, [`SynthParams`]) and their units are described in
//! [`params`].

use mp_geom::{fit_best_checked, FitParams};
use mp_geom::{Checked, Validate};
use mp_geom::{Primitive, Track};
use ndarray::{s, Array2};
use rayon::prelude::*;

use crate::dp::{segment_table, CostTable, Segmentation};
use crate::error::{ConcreteError, Result};
use crate::program::{Program, Segment};
use crate::search::{segment_search, JointTrack, SearchStats};
use crate::smooth::{refit_joint, Continuity, JointSeries, RefitNorm};

pub mod params;

pub use params::{
    lambda_per_frame, Lambda, Scale, SynthParams, UnobservedJoints, BUDGET_LAMBDA_RANGE,
    BUDGET_LAMBDA_STEP,
};

/// The result of [`Program::synthesize_detailed`].
#[derive(Debug, Clone, PartialEq)]
pub struct Synthesis {
    /// The program.
    pub program: Program,
    /// The segmentation and its total DP cost (fit errors + λ, track units).
    pub segmentation: Segmentation,
    /// Track units per reference pixel used for thresholds and λ.
    pub unit_scale: f64,
    /// λ per frame in track units (segment `k..n` pays `lambda[n − 1]`).
    pub lambda: Vec<f64>,
}

/// Track data prepared for fitting: gap-filled trajectories and 0/1 weights per joint.
struct Prepared {
    /// Per joint `T × D` (missing frames filled by interpolation).
    points: Vec<Array2<f64>>,
    /// Per joint, weight per frame (1 observed, 0 missing).
    weights: Vec<Vec<f64>>,
    /// Per joint, prefix count of observed frames (length T + 1).
    prefix_valid: Vec<Vec<usize>>,
}

fn prepare(track: &Track, min_conf: f64, unobserved: UnobservedJoints) -> Result<Prepared> {
    let (t, j) = (track.n_frames(), track.n_joints());
    if t == 0 {
        return Err(ConcreteError::Track("the track has no frames".into()));
    }
    if t < 2 {
        return Err(ConcreteError::Track(format!(
            "the track has {t} frame; synthesis needs at least 2"
        )));
    }
    if j == 0 {
        return Err(ConcreteError::Track("the track has no joints".into()));
    }
    let conf = track.confidence();
    if conf.iter().all(|&c| c <= min_conf) {
        return Err(ConcreteError::Track(format!(
            "every joint of every frame has confidence ≤ {min_conf} (nothing observed)"
        )));
    }
    let names = &track.skeleton().joints;
    let mut filled = track.clone();
    // Mark low-confidence entries missing before filling.
    {
        let mut c = filled.confidence_mut();
        c.mapv_inplace(|v| if v > min_conf { v } else { 0.0 });
    }
    filled.fill_missing();
    let mut points = Vec::with_capacity(j);
    let mut weights = Vec::with_capacity(j);
    let mut prefix_valid = Vec::with_capacity(j);
    for ji in 0..j {
        let w: Vec<f64> = (0..t)
            .map(|ti| if conf[[ti, ji]] > min_conf { 1.0 } else { 0.0 })
            .collect();
        if w.iter().all(|&x| x == 0.0) && unobserved == UnobservedJoints::Error {
            let name = names.get(ji).map(String::as_str).unwrap_or("?");
            return Err(ConcreteError::Track(format!(
                "joint {ji} (`{name}`) is missing in every frame (confidence ≤ {min_conf} or non-finite positions); set `unobserved_joints` to ignore it"
            )));
        }
        let mut pre = vec![0usize; t + 1];
        for ti in 0..t {
            pre[ti + 1] = pre[ti] + usize::from(w[ti] > 0.0);
        }
        points.push(filled.joint(ji).to_owned());
        weights.push(w);
        prefix_valid.push(pre);
    }
    Ok(Prepared {
        points,
        weights,
        prefix_valid,
    })
}

fn joint_name(track: &Track, j: usize) -> String {
    track
        .skeleton()
        .joints
        .get(j)
        .cloned()
        .unwrap_or_else(|| format!("{j}"))
}

fn segment_cost(
    prep: &Prepared,
    fit: &Checked<FitParams>,
    track: &Track,
    k: usize,
    n: usize,
) -> Result<f64> {
    let mut total = 0.0;
    for (ji, pts) in prep.points.iter().enumerate() {
        if prep.prefix_valid[ji][n] == prep.prefix_valid[ji][k] {
            continue; // joint unobserved in this segment: no evidence, no cost
        }
        let f = fit_best_checked(pts.slice(s![k..n, ..]), Some(&prep.weights[ji][k..n]), fit)
            .map_err(|e| {
                ConcreteError::Track(format!(
                    "fitting joint `{}` on frames {k}..{n}: {e}",
                    joint_name(track, ji)
                ))
            })?;
        total += f.error;
    }
    Ok(total)
}

/// Fills the cost table (fit errors summed over joints + λ of the segment's last frame) in parallel.
fn cost_table(
    prep: &Prepared,
    fit: &Checked<FitParams>,
    track: &Track,
    lambda: &[f64],
    window: usize,
) -> Result<CostTable> {
    CostTable::try_from_fn_parallel(track.n_frames(), window, |k, n| {
        Ok(segment_cost(prep, fit, track, k, n)? + lambda[n - 1])
    })
}

/// Fits the primitives of one segment for every joint. A joint unobserved in
/// the whole segment gets the best fit to its gap-filled trajectory.
fn fit_segment(
    prep: &Prepared,
    fit: &Checked<FitParams>,
    track: &Track,
    k: usize,
    n: usize,
) -> Result<Vec<Primitive>> {
    prep.points
        .iter()
        .enumerate()
        .map(|(ji, pts)| {
            let observed = prep.prefix_valid[ji][n] > prep.prefix_valid[ji][k];
            let w = observed.then(|| &prep.weights[ji][k..n]);
            fit_best_checked(pts.slice(s![k..n, ..]), w, fit)
                .map(|f| f.primitive)
                .map_err(|e| {
                    ConcreteError::Track(format!(
                        "fitting joint `{}` on frames {k}..{n}: {e}",
                        joint_name(track, ji)
                    ))
                })
        })
        .collect()
}

/// The fit parameters at the track's `unit_scale`, checked once here: the
/// DP then fits every candidate segment with [`fit_best_checked`].
fn scaled_fit(params: &SynthParams, unit_scale: f64) -> Result<Checked<FitParams>> {
    let mut fit = params.fit.clone();
    fit.unit_scale = unit_scale;
    Ok(fit.check()?)
}

/// The DP's cost table for a track: `cost(k, n)` = Σ over joints of the best
/// fit error on frames `k..n` + λ of frame `n − 1` (track units), for every
/// segment of at most `max_segment_frames` frames. [`Program::synthesize`]
/// segments with exactly these costs.
pub(crate) fn segment_costs(track: &Track, params: &SynthParams) -> Result<CostTable> {
    params.validate()?;
    let params = &resolve_budget(track, params)?;
    let su = setup(track, params)?;
    cost_table(
        &su.prep,
        &su.fit,
        track,
        &su.lambda,
        params.max_segment_frames,
    )
}

/// What every segmentation of a track starts from.
struct Setup {
    /// The joints' points and weights.
    prep: Prepared,
    /// The fit parameters at the track's scale.
    fit: Checked<FitParams>,
    unit_scale: f64,
    /// λ per frame (track units).
    lambda: Vec<f64>,
}

/// The [`Setup`] of `track` (`params` validated, a budget resolved).
fn setup(track: &Track, params: &SynthParams) -> Result<Setup> {
    let prep = prepare(track, params.min_confidence, params.unobserved_joints)?;
    let unit_scale = params.unit_scale(track);
    let fit = scaled_fit(params, unit_scale)?;
    let lambda = lambda_per_frame(track, params, unit_scale);
    Ok(Setup {
        prep,
        fit,
        unit_scale,
        lambda,
    })
}

/// The optimal segmentation by branch and bound over the DP ([`crate::search`]).
fn search_prepared(
    su: &Setup,
    track: &Track,
    window: usize,
) -> Result<(Segmentation, SearchStats)> {
    let (prep, fit, lambda) = (&su.prep, &su.fit, &su.lambda);
    let joints: Vec<JointTrack<'_>> = prep
        .points
        .iter()
        .zip(&prep.weights)
        .map(|(points, weights)| JointTrack {
            points,
            weights: weights.as_slice(),
        })
        .collect();
    segment_search(&joints, &track.skeleton().joints, fit, lambda, window)
}

impl Segmentation {
    /// The segmentation that [`Program::synthesize`] uses (branch and bound,
    /// no cost table).
    pub fn search(track: &Track, params: &SynthParams) -> Result<Segmentation> {
        if let Lambda::Budget { ratio } = params.lambda {
            params.validate()?;
            // The bisection has segmented at the λ it chose already.
            return synthesize_budget(track, params, ratio).map(|(s, _)| s.segmentation);
        }
        // (Validates the parameters.)
        Segmentation::search_with_stats(track, params).map(|(s, _)| s)
    }

    /// [`Segmentation::search`] and the work its search did ([`SearchStats`]).
    /// With a [`Lambda::Budget`], the search at the fixed λ the budget chose
    /// (the bisection's other searches are not counted).
    pub fn search_with_stats(
        track: &Track,
        params: &SynthParams,
    ) -> Result<(Segmentation, SearchStats)> {
        params.validate()?;
        let params = &resolve_budget(track, params)?;
        search_prepared(&setup(track, params)?, track, params.max_segment_frames)
    }

    /// The reference segmentation: every candidate segment refitted with
    /// [`mp_geom::fit_best`] into the full `T × W` cost table (`O(T·W)`
    /// memory, `O(T·W²·J)` time), then the exhaustive DP over it.
    /// [`Segmentation::search`] finds the same optimum much faster (same
    /// costs up to rounding); this is kept for tests and benchmarks.
    pub fn exhaustive(track: &Track, params: &SynthParams) -> Result<Segmentation> {
        segment_table(&segment_costs(track, params)?)
    }
}

/// Refits every joint's primitives of the chosen segmentation so that
/// consecutive segments share their boundary pose ([`crate::smooth`]).
fn smooth_segments(
    prep: &Prepared,
    fit: &FitParams,
    norm: RefitNorm,
    track: &Track,
    bounds: &[usize],
    mut segments: Vec<Segment>,
) -> Result<Vec<Segment>> {
    let per_joint = (0..prep.points.len())
        .into_par_iter()
        .map(|ji| {
            let series = JointSeries {
                points: prep.points[ji].view(),
                weights: &prep.weights[ji],
            };
            let prims: Vec<Primitive> = segments.iter().map(|s| s.primitives[ji].clone()).collect();
            refit_joint(&series, bounds, &prims, fit, norm).ok_or_else(|| {
                ConcreteError::Track(format!(
                    "joint `{}`: the continuous (C0) refit has no solution (non-finite positions?)",
                    joint_name(track, ji)
                ))
            })
        })
        .collect::<Result<Vec<_>>>()?;
    for (ji, prims) in per_joint.into_iter().enumerate() {
        for (seg, p) in segments.iter_mut().zip(prims) {
            seg.primitives[ji] = p;
        }
    }
    Ok(segments)
}

/// `params` with a [`Lambda::Budget`] replaced by the fixed λ it resolves to.
fn resolve_budget(track: &Track, params: &SynthParams) -> Result<SynthParams> {
    Ok(match params.lambda {
        Lambda::Budget { ratio } => SynthParams {
            lambda: Lambda::fixed(synthesize_budget(track, params, ratio)?.1),
            ..params.clone()
        },
        _ => params.clone(),
    })
}

/// [`Lambda::Budget`]: bisection on a fixed λ (see the module docs); the
/// synthesis and the λ (reference scale) it used.
fn synthesize_budget(track: &Track, params: &SynthParams, ratio: f64) -> Result<(Synthesis, f64)> {
    let raw = (track.n_frames() * track.n_joints() * track.dims()).max(1) as f64;
    let at = |lambda_ref: f64| {
        let p = SynthParams {
            lambda: Lambda::fixed(lambda_ref),
            ..params.clone()
        };
        Program::synthesize_detailed(track, &p).map(|s| {
            let r = s.program.n_params() as f64 / raw;
            (s, r)
        })
    };
    let (mut lo, mut hi) = BUDGET_LAMBDA_RANGE;
    let (first, r_lo) = at(lo)?;
    if r_lo <= ratio {
        return Ok((first, lo));
    }
    let (mut best, r_hi) = at(hi)?;
    if r_hi > ratio {
        return Err(ConcreteError::param(
            "lambda.ratio",
            format!(
                "a parameter budget of {ratio} is below the most compact program of this track \
                 ({r_hi:.4} of its {raw} numbers at λ = {hi})"
            ),
        ));
    }
    while hi / lo > BUDGET_LAMBDA_STEP {
        let mid = (lo * hi).sqrt();
        let (s, r) = at(mid)?;
        if r <= ratio {
            hi = mid;
            best = s;
        } else {
            lo = mid;
        }
    }
    Ok((best, hi))
}

impl Program {
    /// Synthesises a concrete program from a track.
    ///
    /// Errors: invalid parameters; a track with fewer than 2 frames or no
    /// joints; nothing observed at all; a joint missing in every frame (named in
    /// the message) unless [`SynthParams::unobserved_joints`] says to ignore it.
    pub fn synthesize(track: &Track, params: &SynthParams) -> Result<Program> {
        Program::synthesize_detailed(track, params).map(|s| s.program)
    }

    /// Synthesises a concrete program with all details ([`Synthesis`]:
    /// segmentation cost, scale, λ).
    pub fn synthesize_detailed(track: &Track, params: &SynthParams) -> Result<Synthesis> {
        params.validate()?;
        if let Lambda::Budget { ratio } = params.lambda {
            return synthesize_budget(track, params, ratio).map(|(s, _)| s);
        }
        let su = setup(track, params)?;
        let (segmentation, _) = search_prepared(&su, track, params.max_segment_frames)?;
        let Setup {
            prep,
            fit,
            unit_scale,
            lambda,
        } = su;
        let segments = segmentation
            .boundaries
            .windows(2)
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|w| {
                Ok(Segment {
                    duration_frames: w[1] - w[0],
                    primitives: fit_segment(&prep, &fit, track, w[0], w[1])?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let segments = match params.continuity {
            Continuity::None => segments,
            Continuity::C0 => smooth_segments(
                &prep,
                &fit,
                params.refit_norm,
                track,
                &segmentation.boundaries,
                segments,
            )?,
        };
        let program = Program {
            continuity: params.continuity,
            fps: track.fps(),
            units: track.units(),
            dims: track.dims(),
            skeleton: track.skeleton().name.clone(),
            joints: track.skeleton().joints.clone(),
            segments,
        };
        Ok(Synthesis {
            program,
            segmentation,
            unit_scale,
            lambda,
        })
    }
}
