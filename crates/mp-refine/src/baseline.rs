//! A non-learned refinement baseline.
//!
//! [`refine`] works in two steps:
//!
//! 1. **Detect** flawed frames:
//!    * *frozen* frames: the mean joint displacement from the previous frame
//!      is below [`RefineParams::frozen_speed_m`] (a repeated pose — recorded
//!      motion never repeats a frame exactly);
//!    * *outliers*: the mean joint acceleration `‖p(t+1) − 2p(t) + p(t−1)‖`
//!      has a robust z-score (median / 1.4826·MAD over the clip) above
//!      [`RefineParams::outlier_z`] and exceeds
//!      [`RefineParams::min_outlier_accel_m`];
//!    * *low-quality anchors* (when [`Concepts`] are given): anchors of the
//!      spline segmentation whose GMM log-likelihood is below the action's
//!      threshold, with [`RefineParams::anchor_half_width_frames`] frames on
//!      each side.
//!
//!    Detections are widened by [`RefineParams::dilate_frames`].
//! 2. **Repair** each run of flagged frames by fitting, per joint and axis, a
//!    cubic spline to the good frames around it (up to
//!    [`RefineParams::context_frames`] on each side; flagged frames have
//!    weight 0) and executing it on the flagged frames: the transition is
//!    re-fitted between the neighbouring good anchors. A run that touches the
//!    start or the end of the clip holds the nearest good pose.

#![allow(clippy::needless_range_loop, clippy::manual_memcpy)]

use mp_geom::median;
use mp_geom::Track;
use ndarray::s;
use serde::{Deserialize, Serialize};

use crate::concepts::{anchor_feature, root_of, Concepts};
use crate::error::{RefineError, Result};
use crate::segment::{check_track, fit_joint, segment_track, JointData, SegmentParams};

/// Parameters of the baseline refinement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefineParams {
    /// Segmentation used to find anchors (only with concepts).
    pub segment: SegmentParams,
    /// A frame whose mean joint displacement from the previous frame is below
    /// this is frozen (track units per frame). Default 1e-4 (0.1 mm).
    pub frozen_speed_m: f64,
    /// Only runs of at least this many frozen frames are flagged (recorded
    /// data repeats single frames: about a third of MSR Action3D's frames
    /// repeat the previous one). Default 3.
    pub min_frozen_run_frames: usize,
    /// Flagged runs longer than this are left as they are (not a local
    /// glitch: MSR Action3D has clips whose last hundreds of frames repeat
    /// one pose). Default 15 (1 s at 15 fps).
    pub max_run_frames: usize,
    /// Robust z-score of the mean joint acceleration above which a frame is
    /// an outlier. Default 3.5.
    pub outlier_z: f64,
    /// Outliers must also have a mean joint acceleration above this (track
    /// units per frame²). Default 0.01.
    pub min_outlier_accel_m: f64,
    /// Frames added on each side of every acceleration outlier. Default 0.
    pub dilate_frames: usize,
    /// Good frames used on each side of a flagged run. Default 4.
    pub context_frames: usize,
    /// Frames flagged on each side of a low-scoring anchor. Default 2.
    pub anchor_half_width_frames: usize,
}

impl Default for RefineParams {
    fn default() -> Self {
        RefineParams {
            segment: SegmentParams::default(),
            frozen_speed_m: 1e-4,
            min_frozen_run_frames: 3,
            max_run_frames: 15,
            outlier_z: 3.5,
            min_outlier_accel_m: 0.01,
            dilate_frames: 0,
            context_frames: 4,
            anchor_half_width_frames: 2,
        }
    }
}

impl RefineParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        self.segment.validate()?;
        for (name, v) in [
            ("frozen_speed_m", self.frozen_speed_m),
            ("outlier_z", self.outlier_z),
            ("min_outlier_accel_m", self.min_outlier_accel_m),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(RefineError::param(
                    name,
                    format!("must be finite and ≥ 0, got {v}"),
                ));
            }
        }
        if self.context_frames == 0 {
            return Err(RefineError::param("context_frames", "must be ≥ 1"));
        }
        Ok(())
    }
}

/// Result of [`refine`].
#[derive(Debug, Clone, PartialEq)]
pub struct Refinement {
    /// The refined track.
    pub track: Track,
    /// Frames detected as flawed (and re-fitted).
    pub flagged: Vec<bool>,
    /// Anchors judged flawed by the concepts' GMM (empty without concepts).
    pub flawed_anchors: Vec<usize>,
}

/// Mean joint distance between frames `a` and `b`.
fn frame_dist(p: &ndarray::ArrayView3<'_, f64>, a: usize, b: usize) -> f64 {
    let (_, nj, d) = p.dim();
    let mut s = 0.0;
    for j in 0..nj {
        let mut e = 0.0;
        for k in 0..d {
            let x = p[[a, j, k]] - p[[b, j, k]];
            e += x * x;
        }
        s += e.sqrt();
    }
    s / nj.max(1) as f64
}

/// Frames `f ≥ 1` of `pos` (`T × J × D`) whose mean joint displacement from
/// frame `f − 1` is below `tol`: repeats of a held pose. Frames with a
/// non-finite coordinate never count.
pub fn held_frames(pos: ndarray::ArrayView3<'_, f64>, tol: f64) -> Vec<usize> {
    (1..pos.dim().0)
        .filter(|&f| frame_dist(&pos, f, f - 1) < tol)
        .collect()
}

/// (frozen frames, acceleration outliers), undilated.
fn detect_parts(track: &Track, params: &RefineParams) -> Result<(Vec<bool>, Vec<bool>)> {
    params.validate()?;
    check_track(track, params.segment.n_joints, "detect_motion_flaws")?;
    let p = track.positions();
    let t = track.n_frames();
    let mut flag = vec![false; t];
    let mut out = vec![false; t];
    let mut frozen = vec![false; t];
    for f in held_frames(p, params.frozen_speed_m) {
        frozen[f] = true;
    }
    for run in true_runs(&frozen) {
        if run.len() >= params.min_frozen_run_frames {
            flag[run].iter_mut().for_each(|x| *x = true);
        }
    }
    if t >= 3 {
        let (_, nj, d) = p.dim();
        let acc: Vec<f64> = (1..t - 1)
            .map(|f| {
                let mut s = 0.0;
                for j in 0..nj {
                    let mut e = 0.0;
                    for k in 0..d {
                        let x = p[[f + 1, j, k]] - 2.0 * p[[f, j, k]] + p[[f - 1, j, k]];
                        e += x * x;
                    }
                    s += e.sqrt();
                }
                s / nj.max(1) as f64
            })
            .collect();
        let med = median(&mut acc.clone()).unwrap_or(0.0);
        let mut dev: Vec<f64> = acc.iter().map(|a| (a - med).abs()).collect();
        let mad = 1.4826 * median(&mut dev).unwrap_or(0.0);
        for (i, a) in acc.iter().enumerate() {
            let z = if mad > 0.0 {
                (a - med) / mad
            } else {
                f64::INFINITY
            };
            if z > params.outlier_z && *a > params.min_outlier_accel_m {
                out[i + 1] = true;
            }
        }
    }
    Ok((flag, out))
}

/// Detects flawed frames and re-fits them (see the module docs).
///
/// `concepts` = the learned concepts and the clip's action, to also flag
/// low-scoring anchors. Errors: invalid parameters; fewer than 2 frames; a
/// joint count that differs from the concepts' (or
/// [`SegmentParams::n_joints`]); an action the concepts do not know.
pub fn refine(
    track: &Track,
    concepts: Option<(&Concepts, u32)>,
    params: &RefineParams,
) -> Result<Refinement> {
    params.validate()?;
    check_track(track, params.segment.n_joints, "refine")?;
    let t = track.n_frames();
    let (frozen, outliers) = detect_parts(track, params)?;
    let mut flagged = frozen;
    let h = params.dilate_frames;
    for (f, &r) in outliers.iter().enumerate() {
        if r {
            for g in f.saturating_sub(h)..=(f + h).min(t - 1) {
                flagged[g] = true;
            }
        }
    }
    let mut flawed_anchors = Vec::new();
    if let Some((c, action)) = concepts {
        let dim = track.n_joints() * track.dims();
        if c.dim != dim {
            return Err(RefineError::JointCount {
                what: "refine with concepts".into(),
                expected: c.dim / track.dims().max(1),
                got: track.n_joints(),
            });
        }
        let ac = c.action(action)?;
        let seg = segment_track(track, &params.segment)?;
        let root = root_of(track, &c.params);
        let w = params.anchor_half_width_frames;
        for &a in seg.anchors.iter().filter(|&&a| a > 0 && a + 1 < t) {
            let pose = track.positions().index_axis_move(ndarray::Axis(0), a);
            let feat = anchor_feature(pose, root, c.params.scale_normalise)?;
            if ac.gmm.log_likelihood(&feat)? < ac.score_threshold {
                flawed_anchors.push(a);
                for g in a.saturating_sub(w)..=(a + w).min(t - 1) {
                    flagged[g] = true;
                }
            }
        }
    }
    // Drop runs too long to be a local flaw.
    for run in true_runs(&flagged) {
        if run.len() > params.max_run_frames {
            flagged[run].iter_mut().for_each(|x| *x = false);
        }
    }
    let repaired = repair(track, &flagged, params.context_frames)?;
    Ok(Refinement {
        track: repaired,
        flagged,
        flawed_anchors,
    })
}

/// Re-fits every run of flagged frames from the good frames around it.
pub fn repair(track: &Track, flagged: &[bool], context_frames: usize) -> Result<Track> {
    let t = track.n_frames();
    if flagged.len() != t {
        return Err(RefineError::Shape(format!(
            "repair: {} flags for {t} frames",
            flagged.len()
        )));
    }
    let mut pos = track.positions().to_owned();
    let data = JointData::new(track, 0.0);
    let fit = mp_geom::FitParams {
        kinds: vec![mp_geom::PrimitiveKind::Spline],
        ..mp_geom::FitParams::default()
    };
    let mut f = 0;
    while f < t {
        if !flagged[f] {
            f += 1;
            continue;
        }
        let a = f;
        while f < t && flagged[f] {
            f += 1;
        }
        let b = f - 1; // run a..=b
        let has_left = a > 0;
        let has_right = b + 1 < t;
        if !has_left && !has_right {
            break; // nothing good to repair from
        }
        if !(has_left && has_right) {
            let src = if has_left { a - 1 } else { b + 1 };
            let held = track.positions().slice(s![src, .., ..]).to_owned();
            for g in a..=b {
                pos.slice_mut(s![g, .., ..]).assign(&held);
            }
            continue;
        }
        // Context: up to `context_frames` good frames on each side.
        let mut lo = a;
        let mut n_left = 0;
        while lo > 0 && n_left < context_frames {
            lo -= 1;
            if !flagged[lo] {
                n_left += 1;
            }
        }
        let mut hi = b;
        let mut n_right = 0;
        while hi + 1 < t && n_right < context_frames {
            hi += 1;
            if !flagged[hi] {
                n_right += 1;
            }
        }
        if n_left < 2 || n_right < 2 {
            // Too little context for a cubic: interpolate linearly between
            // the nearest good frames.
            let (l, r) = (a - 1, b + 1);
            for g in a..=b {
                let u = (g - l) as f64 / (r - l) as f64;
                let mut row = pos.slice_mut(s![g, .., ..]);
                let pl = track.positions().slice(s![l, .., ..]).to_owned();
                let pr = track.positions().slice(s![r, .., ..]).to_owned();
                row.assign(&(&pl * (1.0 - u) + &pr * u));
            }
            continue;
        }
        for (j, (pts, w)) in data.points.iter().zip(&data.weights).enumerate() {
            let ww: Vec<f64> = (lo..=hi)
                .map(|g| if flagged[g] { 0.0 } else { w[g] })
                .collect();
            if ww.iter().all(|&x| x == 0.0) {
                continue; // joint unobserved around the run: leave it
            }
            let sp = fit_joint(pts.slice(s![lo..=hi, ..]), &ww, &fit).map_err(|e| {
                RefineError::NonFinite(format!("repair of joint {j} on frames {a}..={b}: {e}"))
            })?;
            for g in a..=b {
                let v = sp.primitive.eval((g - lo) as f64);
                for (k, x) in v.into_iter().enumerate() {
                    pos[[g, j, k]] = x;
                }
            }
        }
    }
    Ok(Track::new(
        pos,
        Some(track.confidence().to_owned()),
        track.fps(),
        track.units(),
        track.skeleton().clone(),
    )?)
}

/// The track with confidence 1 everywhere.
///
/// MSR Action3D's `conf` is the Kinect tracking state: 0 marks an *inferred*
/// joint whose position is still an estimate (the hip centre is inferred in
/// almost every frame), so refinement and its evaluations use every joint.
/// Frames without any tracked joint (lost tracking) stay at confidence 0.
pub fn full_confidence(track: &Track) -> Result<Track> {
    let c = track.confidence();
    let mut conf = ndarray::Array2::<f64>::ones(c.dim());
    for (f, row) in c.outer_iter().enumerate() {
        if row.iter().all(|&x| x <= 0.0) {
            conf.row_mut(f).fill(0.0);
        }
    }
    Ok(Track::new(
        track.positions().to_owned(),
        Some(conf),
        track.fps(),
        track.units(),
        track.skeleton().clone(),
    )?)
}

/// The maximal runs of `true` in `mask`, in order.
fn true_runs(mask: &[bool]) -> Vec<std::ops::Range<usize>> {
    let mut runs = Vec::new();
    let mut f = 0;
    while f < mask.len() {
        if !mask[f] {
            f += 1;
            continue;
        }
        let a = f;
        while f < mask.len() && mask[f] {
            f += 1;
        }
        runs.push(a..f);
    }
    runs
}
