//! `mp interpolate`: in-between frames guided by the motion program.
//!
//! A first pass runs the pose model over the video (as `mp run` does) and
//! fits the concrete program to the keypoints (`mp_pipeline::concrete_program`,
//! the product's parameters). A second pass streams the frames two at a
//! time: for the in-between time `i + j/k` the program gives the pose
//! (plus the detected keypoints' offset from the program, interpolated
//! linearly between the two frames), and both neighbouring frames are
//! warped towards that pose and blended with weights `1 − j/k` and `j/k`.
//!
//! The warp is backward: each keypoint, and points along each bone, say
//! where the pixel at its new position comes from; a smooth displacement
//! field (Gaussian-weighted average of those displacements, fading to zero
//! a few widths away from the body, σ = [`InterpParams::sigma_frac`] of the
//! person's size) moves the rest, evaluated on a coarse grid and bilinearly
//! upsampled; pixels are sampled bilinearly. Frames without a person are
//! blended linearly.
//!
//! Baselines: [`InterpMethod::Linear`] (blending) and
//! [`InterpMethod::Minterpolate`] (FFmpeg's motion-compensated
//! `minterpolate` filter, `mi_mode=mci`).

use std::path::{Path, PathBuf};

use mp_concrete::{Program, Transition};
use mp_geom::{CancelToken, Track};
use mp_pipeline::{Input, Keep, Params, Silent};
use mp_pose::video::VideoReader;
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Result, VideoError};
use crate::motion::MIN_CONFIDENCE;
use crate::plan::{blend, AtomicVideo, RenderParams};

/// The supported factors.
pub const FACTORS: [usize; 3] = [2, 4, 8];

/// How the in-between frames are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub enum InterpMethod {
    /// Warp both neighbours towards the program's pose, then blend (ours).
    #[default]
    Program,
    /// Blend the neighbours.
    Linear,
    /// FFmpeg's `minterpolate` filter (motion-compensated).
    Minterpolate,
}

impl InterpMethod {
    /// Name.
    pub fn as_str(self) -> &'static str {
        match self {
            InterpMethod::Program => "program",
            InterpMethod::Linear => "linear",
            InterpMethod::Minterpolate => "minterpolate",
        }
    }
}

/// How the person's pixels are moved from a neighbouring frame to the
/// target pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub enum Warp {
    /// A smooth displacement field: the Gaussian-weighted average of the
    /// displacements of the keypoints and of points along the bones.
    #[default]
    Field,
    /// Each bone moves its pixels with its own transform (along the bone:
    /// stretched with it; across: the same distance on its rotated normal),
    /// blended between bones by inverse distance to the bones at the
    /// target pose (linear blend skinning).
    Bones,
}

/// Parameters of the program-guided warp.
#[derive(Debug, Clone, PartialEq)]
pub struct InterpParams {
    /// Width of a keypoint's influence, as a fraction of the person's size
    /// (the larger side of the keypoints' box). Default 0.08.
    pub sigma_frac: f64,
    /// The displacement fades to zero this many widths from the body. Default 2.5.
    pub decay_sigmas: f64,
    /// Grid step (pixels) of the displacement field. Default 4.
    pub grid: usize,
    /// Points per bone besides its joints. Default 3.
    pub bone_samples: usize,
    /// Half-thickness of the body mask (warped pixels inside, background
    /// outside), as a fraction of the person's size. Default 0.06.
    pub body_radius_frac: f64,
    /// Inside the body, the weight of the warped frames against plain
    /// blending. Default 1.
    pub warp_weight: f64,
    /// How the pixels of the person are moved to the target pose.
    pub warp: Warp,
    /// Inside the body, the two warped frames are weighted `(1 − w)^p` and
    /// `w^p` (normalised) at time `i + w`: 1 blends by time, larger values
    /// favour the nearer frame (fewer double limbs where the two warps
    /// disagree). Default 1.
    pub blend_power: f64,
    /// Where the two warped frames disagree by more than about this much
    /// (mean absolute difference over the channels, 0–255), the plain blend
    /// of the two frames is used instead (weight `exp(−(d/τ)²)` on the
    /// warped pixels); 0 turns the check off. Default 0.
    pub agree_tau: f64,
    /// Target pose between frames `i` and `i + 1`: the chord between the
    /// detected keypoints plus the program's bulge away from its own chord,
    /// cut to this fraction of the keypoints' chord (0: the keypoints
    /// interpolated linearly; a semicircle bulges 0.5). Default 0.5.
    pub max_bulge: f64,
    /// Pose model on the input: seconds after a lost person during which
    /// the region of the last pose is tried again
    /// (`mp_pose::BlazePoseParams::recover_s`). Default 0, MediaPipe's
    /// tracking: on the validation videos at 8×, 1 s found the person on more
    /// kept frames but gave frames whose arms were further from the truth
    /// (KD in the truth's crops 53.1 against 49.3 px) at 0.05 dB less PSNR.
    pub recover_s: f64,
    /// Check each joint's detected motion against the pixels
    /// ([`motion_supported`]): where the patch around the joint matches the
    /// other frame in place better than at the joint's new position, the
    /// pixels did not move as the keypoints say (a pose-model jump, not
    /// motion) and that joint's pixels are left where they are. Default off:
    /// on the validation videos at 8× it raised PSNR by 0.09 dB but the arms'
    /// KD by 3.2 px.
    pub pixel_check: bool,
    /// A joint moves pixels only where the pose model's confidence in it is
    /// above this in the kept frame (elsewhere it is not seen there).
    /// Default 0.3, the confidence above which the rest of the toolkit counts
    /// a joint as seen.
    pub min_confidence: f64,
    /// Encoding.
    pub render: RenderParams,
}

impl Default for InterpParams {
    fn default() -> Self {
        InterpParams {
            sigma_frac: 0.08,
            decay_sigmas: 2.5,
            grid: 4,
            bone_samples: 3,
            body_radius_frac: 0.06,
            warp_weight: 1.0,
            warp: Warp::default(),
            blend_power: 1.0,
            agree_tau: 0.0,
            max_bulge: 0.5,
            recover_s: 0.0,
            pixel_check: false,
            min_confidence: MIN_CONFIDENCE,
            render: RenderParams::default(),
        }
    }
}

impl InterpParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        if !(self.sigma_frac.is_finite() && self.sigma_frac > 0.0 && self.sigma_frac <= 1.0) {
            return Err(VideoError::param("sigma_frac", "must be in (0, 1]"));
        }
        if !(self.decay_sigmas.is_finite() && self.decay_sigmas > 0.0) {
            return Err(VideoError::param("decay_sigmas", "must be > 0"));
        }
        if !(1..=64).contains(&self.grid) {
            return Err(VideoError::param("grid", "must be in 1..=64"));
        }
        if !(self.body_radius_frac.is_finite()
            && self.body_radius_frac > 0.0
            && self.body_radius_frac <= 1.0)
        {
            return Err(VideoError::param("body_radius_frac", "must be in (0, 1]"));
        }
        if !(0.0..=1.0).contains(&self.warp_weight) {
            return Err(VideoError::param("warp_weight", "must be in [0, 1]"));
        }
        if !(self.blend_power.is_finite() && (1.0..=64.0).contains(&self.blend_power)) {
            return Err(VideoError::param("blend_power", "must be in [1, 64]"));
        }
        if !(self.max_bulge.is_finite() && self.max_bulge >= 0.0) {
            return Err(VideoError::param("max_bulge", "must be ≥ 0"));
        }
        if !(self.agree_tau.is_finite() && self.agree_tau >= 0.0) {
            return Err(VideoError::param("agree_tau", "must be ≥ 0"));
        }
        if !(self.recover_s.is_finite() && self.recover_s >= 0.0) {
            return Err(VideoError::param(
                "recover_s",
                "must be a finite number of seconds ≥ 0",
            ));
        }
        if !(0.0..1.0).contains(&self.min_confidence) {
            return Err(VideoError::param("min_confidence", "must be in [0, 1)"));
        }
        if self.bone_samples > 32 {
            return Err(VideoError::param("bone_samples", "must be at most 32"));
        }
        Ok(())
    }
}

/// What an interpolation did.
#[derive(Debug, Clone, Serialize)]
pub struct InterpReport {
    /// Factor.
    pub factor: usize,
    /// Method.
    pub method: InterpMethod,
    /// Input frames.
    pub frames_in: usize,
    /// Output frames (`(frames_in − 1)·factor + 1`).
    pub frames_out: usize,
    /// Input frame rate.
    pub fps_in: f64,
    /// Output frame rate.
    pub fps_out: f64,
    /// Frames where a person was seen.
    pub person_frames: usize,
    /// The output file, once written.
    pub output: Option<PathBuf>,
}

/// Errors unless `factor` is one of [`FACTORS`].
pub fn check_factor(factor: usize) -> Result<()> {
    if FACTORS.contains(&factor) {
        Ok(())
    } else {
        Err(VideoError::Factor(factor))
    }
}

/// The keypoints of a video and the program fitted to them.
pub struct Guide {
    /// Keypoints (COCO-17, pixels).
    pub track: Track,
    /// The concrete program fitted to them.
    pub program: Program,
    /// The program's bulge away from the chord between two frames is cut to
    /// this fraction of the detected keypoints' chord
    /// ([`InterpParams::max_bulge`]).
    pub max_bulge: f64,
    /// Confidence above which a joint is seen ([`InterpParams::min_confidence`]).
    pub min_confidence: f64,
}

impl Guide {
    /// Runs the pose model over `input` and fits the program, as `mp run`
    /// does, with the pose model's recovery and the bulge cut of `params`.
    pub fn fit(input: &Path, analysis: &Params, params: &InterpParams) -> Result<Self> {
        let info = mp_pose::probe(input)?;
        let mut analysis = analysis.clone();
        analysis.pose.recover_s = params.recover_s;
        let analysis = &analysis;
        let (kp, _) = mp_pipeline::keypoints(
            Input::open(input, None)?,
            analysis,
            Keep::default(),
            &Silent,
            &CancelToken::new(),
        )?;
        let track = kp.track;
        if track.valid_count() == 0 || track.n_frames() < 2 {
            return Err(VideoError::NoPerson(input.to_path_buf()));
        }
        let frame_px = Some(info.width.max(info.height) as f64);
        let syn = mp_pipeline::concrete_program(&track, frame_px, analysis)?;
        Ok(Guide {
            track,
            program: syn.program,
            max_bulge: params.max_bulge,
            min_confidence: params.min_confidence,
        })
    }

    fn seen(&self, t: usize, j: usize) -> bool {
        t < self.track.n_frames() && self.track.is_valid(t, j, self.min_confidence)
    }

    /// The pose the in-between frame at time `i + w` (`0 ≤ w ≤ 1`) is warped
    /// to, per joint (`None` where neither neighbour shows the joint): the
    /// program executed at that time plus the detected keypoints' offset
    /// from the program at frames `i` and `i + 1`, interpolated linearly.
    ///
    /// This is the pose before the pixels are consulted: the warp of
    /// [`interpolate_frames`] also leaves in place the joints whose detected
    /// motion the pixels do not show ([`InterpParams::pixel_check`]).
    pub fn target_pose(&self, i: usize, w: f64) -> Result<Vec<Option<[f64; 2]>>> {
        Ok(self
            .targets(i, w, None)?
            .map(|t| t.iter().map(|x| x.map(|t| t.at)).collect())
            .unwrap_or_default())
    }

    /// Per joint, whether the pixels of frames `i` (`a`) and `i + 1` (`b`)
    /// show the joint's detected motion ([`motion_supported`], patches of
    /// half-size `σ` of the warp); `true` where the joint is not seen in both
    /// frames or moves by less than a pixel.
    fn pixel_support(&self, i: usize, frames: &Frames<'_>, params: &InterpParams) -> Vec<bool> {
        let nj = self.track.n_joints();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for t in [i, i + 1] {
            for j in (0..nj).filter(|&j| self.seen(t, j)) {
                let p = self.track.point(t, j);
                for d in 0..2 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
            }
        }
        if !(lo[0].is_finite() && hi[0].is_finite()) {
            return vec![true; nj];
        }
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let r = (params.sigma_frac * size).clamp(2.0, 64.0).round() as usize;
        (0..nj)
            .map(|j| {
                if !(self.seen(i, j) && self.seen(i + 1, j)) {
                    return true;
                }
                let (pa, pb) = (self.track.point(i, j), self.track.point(i + 1, j));
                let (ka, kb) = ([pa[0], pa[1]], [pb[0], pb[1]]);
                motion_supported(frames.a, frames.b, frames.size, ka, kb, r)
            })
            .collect()
    }

    /// Per joint: the target at `i + w` and the joint in frames `i` and
    /// `i + 1` where seen; `None` past the end. A joint whose motion
    /// `support` says the pixels do not show is moved by nothing.
    fn targets(
        &self,
        i: usize,
        w: f64,
        support: Option<&[bool]>,
    ) -> Result<Option<Vec<Option<Target>>>> {
        let nt = self.track.n_frames();
        if i + 1 >= nt || i + 1 >= self.program.n_frames() {
            return Ok(None);
        }
        let p = self
            .program
            .sample_frames(&[i as f64, i as f64 + w, (i + 1) as f64], Transition::Blend)
            .map_err(|e| VideoError::Program(e.to_string()))?;
        let nj = self.track.n_joints().min(p.dim().1);
        let mut targets = vec![None; nj];
        for j in 0..nj {
            let (va, vb) = (self.seen(i, j), self.seen(i + 1, j));
            let ka = [self.track.point(i, j)[0], self.track.point(i, j)[1]];
            let kb = [self.track.point(i + 1, j)[0], self.track.point(i + 1, j)[1]];
            let mut t = [0.0; 2];
            if va && vb {
                // The chord between the detected keypoints plus the program's
                // bulge away from its own chord, at most `max_bulge` of the
                // keypoints' chord long.
                let mut dev = [0.0; 2];
                for (d, x) in dev.iter_mut().enumerate() {
                    *x = p[[1, j, d]] - (1.0 - w) * p[[0, j, d]] - w * p[[2, j, d]];
                }
                let chord = ((kb[0] - ka[0]).powi(2) + (kb[1] - ka[1]).powi(2)).sqrt();
                let len = (dev[0] * dev[0] + dev[1] * dev[1]).sqrt();
                let cap = self.max_bulge * chord;
                let scale = if len > cap && len > 0.0 {
                    cap / len
                } else {
                    1.0
                };
                for d in 0..2 {
                    t[d] = (1.0 - w) * ka[d] + w * kb[d] + scale * dev[d];
                }
            } else {
                // Seen in one frame only: held there (the program's value
                // where the joint was not seen is no measurement).
                t = match (va, vb) {
                    (true, false) => ka,
                    (false, true) => kb,
                    _ => [f64::NAN; 2],
                };
            }
            if !(t[0].is_finite() && t[1].is_finite()) {
                continue;
            }
            let moved = support.is_none_or(|s| s.get(j).copied().unwrap_or(true));
            targets[j] = Some(if moved {
                Target {
                    at: t,
                    a: va.then_some((ka, t)),
                    b: vb.then_some((kb, t)),
                }
            } else {
                // Each frame's pixels stay where they are; the body is drawn
                // on the keypoints' chord.
                Target {
                    at: lerp(ka, kb, w),
                    a: Some((ka, ka)),
                    b: Some((kb, kb)),
                }
            });
        }
        Ok(Some(targets))
    }

    /// Control points `(target, source offset)` for warping frames `i`
    /// (`.0`) and `i + 1` (`.1`) to time `i + w`, and the person's size.
    /// `support`: [`Guide::pixel_support`] of the two frames, when checked.
    fn controls(
        &self,
        i: usize,
        w: f64,
        params: &InterpParams,
        support: Option<&[bool]>,
    ) -> Result<Option<Controls>> {
        let Some(targets) = self.targets(i, w, support)? else {
            return Ok(None);
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for tj in targets.iter().flatten() {
            for (k, _) in [tj.a, tj.b].into_iter().flatten() {
                for d in 0..2 {
                    lo[d] = lo[d].min(k[d]);
                    hi[d] = hi[d].max(k[d]);
                }
            }
        }
        let nj = targets.len();
        if !(lo[0].is_finite() && hi[0].is_finite()) {
            return Ok(None);
        }
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let mut ca = Vec::new();
        let mut cb = Vec::new();
        for tj in targets.iter().flatten() {
            if let Some((k, t)) = tj.a {
                ca.push((t, [k[0] - t[0], k[1] - t[1]]));
            }
            if let Some((k, t)) = tj.b {
                cb.push((t, [k[0] - t[0], k[1] - t[1]]));
            }
        }
        // Points along the bones.
        let ns = params.bone_samples;
        for &(p0, p1) in &self.track.skeleton().bones {
            let (Some(Some(a)), Some(Some(b))) = (targets.get(p0), targets.get(p1)) else {
                continue;
            };
            for s in 1..=ns {
                let l = s as f64 / (ns + 1) as f64;
                if let (Some((ka, ta)), Some((kb, tb))) = (a.a, b.a) {
                    let (k, t) = (lerp(ka, kb, l), lerp(ta, tb, l));
                    ca.push((t, [k[0] - t[0], k[1] - t[1]]));
                }
                if let (Some((ka, ta)), Some((kb, tb))) = (a.b, b.b) {
                    let (k, t) = (lerp(ka, kb, l), lerp(ta, tb, l));
                    cb.push((t, [k[0] - t[0], k[1] - t[1]]));
                }
            }
        }
        // The body as segments (bones, torso diagonals, and each joint as a
        // point) at the target pose and in each frame.
        let mut pairs: Vec<(usize, usize)> = self.track.skeleton().bones.clone();
        pairs.extend(TORSO_DIAGONALS);
        pairs.extend((0..nj).map(|j| (j, j)));
        let (mut st, mut sa, mut sb) = (Vec::new(), Vec::new(), Vec::new());
        let (mut bone_a, mut bone_b) = (Vec::new(), Vec::new());
        for (p0, p1) in pairs {
            let (Some(Some(a)), Some(Some(b))) = (targets.get(p0), targets.get(p1)) else {
                continue;
            };
            st.push((a.at, b.at));
            if let (Some((x, tx)), Some((y, ty))) = (a.a, b.a) {
                sa.push((x, y));
                bone_a.push(((tx, ty), (x, y)));
            }
            if let (Some((x, tx)), Some((y, ty))) = (a.b, b.b) {
                sb.push((x, y));
                bone_b.push(((tx, ty), (x, y)));
            }
        }
        let sigma = (params.sigma_frac * size).max(2.0);
        let radius = (params.body_radius_frac * size).max(2.0);
        Ok(Some(Controls {
            a: ca,
            b: cb,
            sigma,
            radius,
            seg_t: st,
            seg_a: sa,
            seg_b: sb,
            bone_a,
            bone_b,
        }))
    }
}

/// The point a fraction `l` of the way from `p` to `q`.
fn lerp(p: [f64; 2], q: [f64; 2], l: f64) -> [f64; 2] {
    [p[0] + l * (q[0] - p[0]), p[1] + l * (q[1] - p[1])]
}

/// A joint at an in-between time.
#[derive(Debug, Clone, Copy)]
struct Target {
    /// Where the body is drawn (the target pose).
    at: [f64; 2],
    /// Where frame `i` shows the joint and where its pixels there go; `None`
    /// where frame `i` does not show it.
    a: Option<([f64; 2], [f64; 2])>,
    /// The same for frame `i + 1`.
    b: Option<([f64; 2], [f64; 2])>,
}

/// The two neighbouring frames (RGB) and their size.
struct Frames<'a> {
    a: &'a [u8],
    b: &'a [u8],
    size: (usize, usize),
}

/// Whether the pixels of frames `a` and `b` (RGB, `width × height`) show a
/// patch of half-size `r` moving from `pa` (in `a`) to `pb` (in `b`): the
/// patch of `a` at `pa` matches `b` at `pb` (sum of absolute differences) at
/// least as well as the patch at `pa` or the one at `pb` matches the other
/// frame in place. Uniform patches match everywhere and count as support; a
/// joint the pose model moved while the pixels stayed does not. Patches are
/// clamped to the frame and sampled on a grid of at most 17 × 17 points.
pub fn motion_supported(
    a: &[u8],
    b: &[u8],
    (width, height): (usize, usize),
    pa: [f64; 2],
    pb: [f64; 2],
    r: usize,
) -> bool {
    if width == 0 || height == 0 || a.len() < width * height * 3 || b.len() < a.len() {
        return true;
    }
    if (pa[0] - pb[0]).hypot(pa[1] - pb[1]) < 1.0 {
        return true;
    }
    let at = |p: [f64; 2], dx: isize, dy: isize| {
        let x = (p[0].round() as isize + dx).clamp(0, width as isize - 1) as usize;
        let y = (p[1].round() as isize + dy).clamp(0, height as isize - 1) as usize;
        (y * width + x) * 3
    };
    let sad = |f: &[u8], p: [f64; 2], g: &[u8], q: [f64; 2]| {
        let r = r as isize;
        let step = (r / 8).max(1) as usize;
        let mut s = 0u64;
        for dy in (-r..=r).step_by(step) {
            for dx in (-r..=r).step_by(step) {
                let (i, k) = (at(p, dx, dy), at(q, dx, dy));
                for c in 0..3 {
                    s += f[i + c].abs_diff(g[k + c]) as u64;
                }
            }
        }
        s
    };
    let moved = sad(a, pa, b, pb);
    let stayed = sad(a, pa, b, pa).max(sad(a, pb, b, pb));
    moved <= stayed
}

/// COCO-17 shoulder–hip diagonals, so the body mask covers the torso.
const TORSO_DIAGONALS: [(usize, usize); 2] = [(5, 12), (6, 11)];

type Segment = ([f64; 2], [f64; 2]);

struct Controls {
    a: Vec<([f64; 2], [f64; 2])>,
    b: Vec<([f64; 2], [f64; 2])>,
    sigma: f64,
    radius: f64,
    seg_t: Vec<Segment>,
    seg_a: Vec<Segment>,
    seg_b: Vec<Segment>,
    /// (segment at the target pose, the same segment in frame `i`).
    bone_a: Vec<(Segment, Segment)>,
    /// (segment at the target pose, the same segment in frame `i + 1`).
    bone_b: Vec<(Segment, Segment)>,
}

/// The backward displacement field of a bone warp on a grid of step `g`:
/// each bone maps a target pixel to the source frame (the position along
/// the bone scaled with it, the distance across kept on the source bone's
/// normal; a bone of no length translates), and the bones' maps are
/// blended with weights `1 / (d² + ε²)²` of the distance `d` to each bone at
/// the target pose.
fn bone_field(
    bones: &[(Segment, Segment)],
    eps: f64,
    g: usize,
    w: usize,
    h: usize,
) -> Vec<[f32; 2]> {
    let gw = (w - 1) / g + 2;
    let gh = (h - 1) / g + 2;
    let e2 = eps * eps;
    (0..gw * gh)
        .into_par_iter()
        .map(|idx| {
            let (x, y) = (((idx % gw) * g) as f64, ((idx / gw) * g) as f64);
            let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
            for ((t0, t1), (s0, s1)) in bones {
                let (dx, dy) = (t1[0] - t0[0], t1[1] - t0[1]);
                let l2 = dx * dx + dy * dy;
                let (ex, ey) = (s1[0] - s0[0], s1[1] - s0[1]);
                let m2 = ex * ex + ey * ey;
                let (src, dist2) = if l2 < 1.0 || m2 < 1.0 {
                    // A point (or a bone seen end-on): translate with its middle.
                    let (cx, cy) = ((t0[0] + t1[0]) / 2.0, (t0[1] + t1[1]) / 2.0);
                    let (ox, oy) = ((s0[0] + s1[0]) / 2.0 - cx, (s0[1] + s1[1]) / 2.0 - cy);
                    let tc = if l2 > 0.0 {
                        (((x - t0[0]) * dx + (y - t0[1]) * dy) / l2).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let (px, py) = (t0[0] + tc * dx - x, t0[1] + tc * dy - y);
                    ([x + ox, y + oy], px * px + py * py)
                } else {
                    let l = l2.sqrt();
                    let m = m2.sqrt();
                    let u = ((x - t0[0]) * dx + (y - t0[1]) * dy) / l2;
                    // Signed distance across the bone, in pixels.
                    let v = ((x - t0[0]) * -dy + (y - t0[1]) * dx) / l;
                    let src = [s0[0] + u * ex + v * -ey / m, s0[1] + u * ey + v * ex / m];
                    let uc = u.clamp(0.0, 1.0);
                    let (px, py) = (t0[0] + uc * dx - x, t0[1] + uc * dy - y);
                    (src, px * px + py * py)
                };
                let wt = 1.0 / (dist2 + e2).powi(2);
                sx += wt * (src[0] - x);
                sy += wt * (src[1] - y);
                sw += wt;
            }
            if sw > 0.0 {
                [(sx / sw) as f32, (sy / sw) as f32]
            } else {
                [0.0, 0.0]
            }
        })
        .collect()
}

/// A soft body mask on the grid: 1 within `r` of a segment, fading to 0 at `2r`.
fn body_mask(segs: &[Segment], r: f64, g: usize, w: usize, h: usize) -> Vec<f32> {
    let gw = (w - 1) / g + 2;
    let gh = (h - 1) / g + 2;
    (0..gw * gh)
        .into_par_iter()
        .map(|idx| {
            let (x, y) = (((idx % gw) * g) as f64, ((idx / gw) * g) as f64);
            let mut best = f64::INFINITY;
            for (p, q) in segs {
                let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
                let l2 = dx * dx + dy * dy;
                let t = if l2 > 0.0 {
                    (((x - p[0]) * dx + (y - p[1]) * dy) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let (cx, cy) = (p[0] + t * dx - x, p[1] + t * dy - y);
                best = best.min(cx * cx + cy * cy);
            }
            ((2.0 * r - best.sqrt()) / r).clamp(0.0, 1.0) as f32
        })
        .collect()
}

/// The displacement field of `controls` on a grid of step `g` covering the frame.
fn field(
    controls: &[([f64; 2], [f64; 2])],
    sigma: f64,
    decay: f64,
    g: usize,
    w: usize,
    h: usize,
) -> (Vec<[f32; 2]>, usize, usize) {
    let gw = (w - 1) / g + 2;
    let gh = (h - 1) / g + 2;
    let inv = 1.0 / (2.0 * sigma * sigma);
    let w0 = (-decay * decay / 2.0).exp();
    let cut = (decay + 2.0) * sigma;
    let cut2 = cut * cut;
    let f: Vec<[f32; 2]> = (0..gw * gh)
        .into_par_iter()
        .map(|idx| {
            let (x, y) = (((idx % gw) * g) as f64, ((idx / gw) * g) as f64);
            let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
            for (t, u) in controls {
                let d2 = (x - t[0]).powi(2) + (y - t[1]).powi(2);
                if d2 > cut2 {
                    continue;
                }
                let wt = (-d2 * inv).exp();
                sx += wt * u[0];
                sy += wt * u[1];
                sw += wt;
            }
            let den = sw + w0;
            [(sx / den) as f32, (sy / den) as f32]
        })
        .collect();
    (f, gw, gh)
}

/// Bilinear sample of a grid of step `g` (`gw` columns) at pixel `(x, y)`.
#[inline]
fn grid_at<T: Copy>(
    f: &[T],
    gw: usize,
    g: f32,
    x: usize,
    y: usize,
    lerp: impl Fn(T, T, T, T, f32, f32) -> T,
) -> T {
    let (gx, gy) = (x as f32 / g, y as f32 / g);
    let (x0, y0) = (gx.floor() as usize, gy.floor() as usize);
    let (tx, ty) = (gx - x0 as f32, gy - y0 as f32);
    lerp(
        f[y0 * gw + x0],
        f[y0 * gw + x0 + 1],
        f[(y0 + 1) * gw + x0],
        f[(y0 + 1) * gw + x0 + 1],
        tx,
        ty,
    )
}

fn lerp1(a: f32, b: f32, c: f32, d: f32, tx: f32, ty: f32) -> f32 {
    (1.0 - ty) * ((1.0 - tx) * a + tx * b) + ty * ((1.0 - tx) * c + tx * d)
}

fn lerp2(a: [f32; 2], b: [f32; 2], c: [f32; 2], d: [f32; 2], tx: f32, ty: f32) -> [f32; 2] {
    [
        lerp1(a[0], b[0], c[0], d[0], tx, ty),
        lerp1(a[1], b[1], c[1], d[1], tx, ty),
    ]
}

/// Bilinear sample of RGB `src` at `(sx, sy)` (clamped to the frame).
#[inline]
fn sample(src: &[u8], w: usize, h: usize, sx: f32, sy: f32, out: &mut [f32; 3]) {
    let sx = sx.clamp(0.0, (w - 1) as f32);
    let sy = sy.clamp(0.0, (h - 1) as f32);
    let (ix, iy) = (sx.floor() as usize, sy.floor() as usize);
    let (fx, fy) = (sx - ix as f32, sy - iy as f32);
    let (ix1, iy1) = ((ix + 1).min(w - 1), (iy + 1).min(h - 1));
    for (ch, o) in out.iter_mut().enumerate() {
        let p = |xx: usize, yy: usize| src[(yy * w + xx) * 3 + ch] as f32;
        *o = (1.0 - fy) * ((1.0 - fx) * p(ix, iy) + fx * p(ix1, iy))
            + fy * ((1.0 - fx) * p(ix, iy1) + fx * p(ix1, iy1));
    }
}

/// The frame between `a` (frame `i`) and `b` (frame `i + 1`) at `i + w`.
///
/// Inside the body at the target pose, both frames warped towards it and
/// blended; elsewhere the background: each frame's own pixels, weighted by
/// time and left out where that frame shows the person.
fn between(
    guide: Option<&Guide>,
    frames: &Frames<'_>,
    i: usize,
    w: f64,
    params: &InterpParams,
    support: Option<&[bool]>,
) -> Result<Vec<u8>> {
    let (a, b) = (frames.a, frames.b);
    let (width, height) = frames.size;
    let ctl = match guide {
        Some(g) => g.controls(i, w, params, support)?,
        None => None,
    };
    let Some(c) = ctl else {
        return Ok(blend(a, b, w as f32));
    };
    let g = params.grid;
    let gf = g as f32;
    let d = params.decay_sigmas;
    let cells = ((width - 1) / g + 2) * ((height - 1) / g + 2);
    let warp_field = |pts: &[([f64; 2], [f64; 2])], bones: &[(Segment, Segment)]| match params.warp
    {
        Warp::Field if !pts.is_empty() => field(pts, c.sigma, d, g, width, height).0,
        Warp::Bones if !bones.is_empty() => bone_field(bones, 0.5 * c.radius, g, width, height),
        _ => vec![[0.0f32; 2]; cells],
    };
    let fa = warp_field(&c.a, &c.bone_a);
    let fb = warp_field(&c.b, &c.bone_b);
    // Weights of the two warped frames inside the body.
    let (pwa, pwb) = {
        let p = params.blend_power;
        let (x, y) = ((1.0 - w).powf(p), w.powf(p));
        ((x / (x + y)) as f32, (y / (x + y)) as f32)
    };
    let mt = body_mask(&c.seg_t, c.radius, g, width, height);
    let ma = body_mask(&c.seg_a, c.radius, g, width, height);
    let mb = body_mask(&c.seg_b, c.radius, g, width, height);
    let gw = (width - 1) / g + 2;
    let wf = w as f32;
    let ww = params.warp_weight as f32;
    let tau = params.agree_tau as f32;
    let mut out = vec![0u8; a.len()];
    out.par_chunks_mut(width * 3)
        .enumerate()
        .for_each(|(y, row)| {
            let (mut pa, mut pb) = ([0.0f32; 3], [0.0f32; 3]);
            for x in 0..width {
                let m_t = grid_at(&mt, gw, gf, x, y, lerp1);
                let m_a = grid_at(&ma, gw, gf, x, y, lerp1);
                let m_b = grid_at(&mb, gw, gf, x, y, lerp1);
                // Background: each frame where it does not show the person.
                let mut ba = (1.0 - wf) * (1.0 - m_a);
                let mut bb = wf * (1.0 - m_b);
                if ba + bb < 1e-3 {
                    ba = 1.0 - wf;
                    bb = wf;
                }
                let (ba, bb) = (ba / (ba + bb), bb / (ba + bb));
                let p = (y * width + x) * 3;
                let mut bg = [0.0f32; 3];
                for ch in 0..3 {
                    bg[ch] = ba * a[p + ch] as f32 + bb * b[p + ch] as f32;
                }
                if m_t > 0.0 {
                    let ua = grid_at(&fa, gw, gf, x, y, lerp2);
                    let ub = grid_at(&fb, gw, gf, x, y, lerp2);
                    sample(
                        a,
                        width,
                        height,
                        x as f32 + ua[0],
                        y as f32 + ua[1],
                        &mut pa,
                    );
                    sample(
                        b,
                        width,
                        height,
                        x as f32 + ub[0],
                        y as f32 + ub[1],
                        &mut pb,
                    );
                    let ww = if tau > 0.0 {
                        let dd =
                            ((pa[0] - pb[0]).abs() + (pa[1] - pb[1]).abs() + (pa[2] - pb[2]).abs())
                                / 3.0
                                / tau;
                        ww * (-dd * dd).exp()
                    } else {
                        ww
                    };
                    for ch in 0..3 {
                        let lin = (1.0 - wf) * a[p + ch] as f32 + wf * b[p + ch] as f32;
                        let person = ww * (pwa * pa[ch] + pwb * pb[ch]) + (1.0 - ww) * lin;
                        bg[ch] = m_t * person + (1.0 - m_t) * bg[ch];
                    }
                }
                for ch in 0..3 {
                    row[x * 3 + ch] = bg[ch].round().clamp(0.0, 255.0) as u8;
                }
            }
        });
    Ok(out)
}

/// Interpolates `input` by `factor` with `method`, handing each output frame
/// (RGB) to `sink` in order: the input's frames with `factor − 1` new frames
/// between each pair. `analysis` are the pipeline's parameters (pose model,
/// program fitting).
pub fn interpolate_frames(
    input: &Path,
    factor: usize,
    method: InterpMethod,
    params: &InterpParams,
    analysis: &Params,
    mut sink: impl FnMut(&[u8]) -> Result<()>,
) -> Result<InterpReport> {
    check_factor(factor)?;
    params.validate()?;
    let info = mp_pose::probe(input)?;
    let (width, height) = (info.width, info.height);
    let fps_out = info.fps * factor as f64;
    if method == InterpMethod::Minterpolate {
        let mut out_info = info.clone();
        out_info.fps = fps_out;
        let n_in = VideoReader::open(input)?.count();
        let want = n_in.saturating_sub(1) * factor + 1;
        let filter = format!("minterpolate=fps={fps_out}:mi_mode=mci");
        let mut n = 0;
        for f in VideoReader::with_filter(out_info, &filter)?.take(want) {
            sink(&f?.rgb)?;
            n += 1;
        }
        return Ok(InterpReport {
            factor,
            method,
            frames_in: n_in,
            frames_out: n,
            fps_in: info.fps,
            fps_out,
            person_frames: 0,
            output: None,
        });
    }
    let guide = match method {
        InterpMethod::Program => Some(Guide::fit(input, analysis, params)?),
        _ => None,
    };
    let person_frames = guide.as_ref().map_or(0, |g| {
        (0..g.track.n_frames())
            .filter(|&t| (0..g.track.n_joints()).any(|j| g.seen(t, j)))
            .count()
    });
    let mut prev: Option<Vec<u8>> = None;
    let (mut n_in, mut n_out) = (0usize, 0usize);
    for frame in VideoReader::open(input)? {
        let frame = frame?;
        if let Some(a) = prev.take() {
            sink(&a)?;
            n_out += 1;
            let frames = Frames {
                a: &a,
                b: &frame.rgb,
                size: (width, height),
            };
            // The pixel check depends on the two frames only: once per pair.
            let support = match &guide {
                Some(g) if params.pixel_check => Some(g.pixel_support(n_in - 1, &frames, params)),
                _ => None,
            };
            for j in 1..factor {
                let w = j as f64 / factor as f64;
                let f = between(
                    guide.as_ref(),
                    &frames,
                    n_in - 1,
                    w,
                    params,
                    support.as_deref(),
                )?;
                sink(&f)?;
                n_out += 1;
            }
        }
        prev = Some(frame.rgb);
        n_in += 1;
    }
    if let Some(a) = prev {
        sink(&a)?;
        n_out += 1;
    }
    Ok(InterpReport {
        factor,
        method,
        frames_in: n_in,
        frames_out: n_out,
        fps_in: info.fps,
        fps_out,
        person_frames,
        output: None,
    })
}

/// [`interpolate_frames`] into the video file `output` at `factor` times the
/// frame rate (written atomically).
pub fn interpolate_video(
    input: &Path,
    factor: usize,
    method: InterpMethod,
    params: &InterpParams,
    analysis: &Params,
    output: &Path,
) -> Result<InterpReport> {
    check_factor(factor)?;
    let info = mp_pose::probe(input)?;
    let mut out = AtomicVideo::create(
        output,
        info.width,
        info.height,
        info.fps * factor as f64,
        params.render.preset,
    )?;
    let mut report = interpolate_frames(input, factor, method, params, analysis, |rgb| {
        out.write(rgb)
    })?;
    out.finish()?;
    report.output = Some(output.to_path_buf());
    Ok(report)
}

/// Writes every `step`-th frame of `input` (the first `max_frames` when
/// given) losslessly (FFV1 in Matroska) to `output`, at `1/step` of the
/// frame rate: the input of an interpolation experiment.
pub fn keep_every(
    input: &Path,
    step: usize,
    max_frames: Option<usize>,
    output: &Path,
) -> Result<usize> {
    if step == 0 {
        return Err(VideoError::param("step", "must be at least 1"));
    }
    let info = mp_pose::probe(input)?;
    let fps = info.fps / step as f64;
    let mut cmd = std::process::Command::new("ffmpeg");
    cmd.args(["-v", "error", "-nostdin", "-y", "-i"])
        .arg(input)
        .args(["-map", "0:v:0", "-vf"])
        .arg(format!("select=not(mod(n\\,{step})),setpts=N/({fps})/TB"))
        .args(["-fps_mode", "passthrough", "-r"])
        .arg(format!("{fps}"));
    if let Some(m) = max_frames {
        cmd.arg("-frames:v").arg(m.div_ceil(step).to_string());
    }
    let out = cmd
        .args(["-c:v", "ffv1"])
        .arg(output)
        .stdin(std::process::Stdio::null())
        .output()
        .map_err(|e| VideoError::io(output, e))?;
    if !out.status.success() {
        return Err(VideoError::Edit(format!(
            "ffmpeg could not write {}: {}",
            output.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    Ok(VideoReader::open(output)?.count())
}

#[cfg(test)]
mod tests {
    use super::motion_supported;

    /// A `w × h` RGB frame: a checkerboard of 4-px cells in a 24-px square
    /// at `(x0, y0)` on a flat grey background.
    fn frame(w: usize, h: usize, x0: usize, y0: usize) -> Vec<u8> {
        let mut f = vec![90u8; w * h * 3];
        for y in y0..(y0 + 24).min(h) {
            for x in x0..(x0 + 24).min(w) {
                let v = if ((x - x0) / 4 + (y - y0) / 4).is_multiple_of(2) {
                    20
                } else {
                    230
                };
                f[(y * w + x) * 3..(y * w + x) * 3 + 3].fill(v);
            }
        }
        f
    }

    #[test]
    fn motion_the_pixels_show_is_supported() {
        let (w, h) = (120, 80);
        let (a, b) = (frame(w, h, 20, 20), frame(w, h, 50, 30));
        // The square's centre moves with the keypoint.
        assert!(motion_supported(
            &a,
            &b,
            (w, h),
            [32.0, 32.0],
            [62.0, 42.0],
            8
        ));
    }

    #[test]
    fn a_keypoint_jump_on_still_pixels_is_not_supported() {
        let (w, h) = (120, 80);
        let a = frame(w, h, 20, 20);
        assert!(!motion_supported(
            &a,
            &a,
            (w, h),
            [32.0, 32.0],
            [70.0, 50.0],
            8
        ));
        // Less than a pixel, a uniform background, and frames of the wrong
        // size count as support (nothing to contradict the keypoints).
        assert!(motion_supported(
            &a,
            &a,
            (w, h),
            [32.0, 32.0],
            [32.5, 32.0],
            8
        ));
        let grey = vec![90u8; w * h * 3];
        assert!(motion_supported(
            &grey,
            &grey,
            (w, h),
            [5.0, 5.0],
            [90.0, 60.0],
            8
        ));
        assert!(motion_supported(
            &a,
            &a[..10],
            (w, h),
            [32.0, 32.0],
            [70.0, 50.0],
            8
        ));
        // Patches at the border are clamped to the frame.
        assert!(!motion_supported(
            &a,
            &a,
            (w, h),
            [0.0, 0.0],
            [30.0, 30.0],
            8
        ));
    }
}
