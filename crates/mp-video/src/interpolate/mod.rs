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
//!
//! The steps, one submodule each: `guide` (the pose model's keypoints, the
//! program and the target pose at an in-between time), `warp` (displacement
//! fields, body masks and the in-between frame), `check` (whether the pixels
//! bear out a joint's motion or a pair's warp: [`motion_supported`],
//! [`warps_agree`]); this module holds the parameters and the streaming
//! driver.

use std::path::{Path, PathBuf};

use mp_concrete::InBetween;
use mp_pipeline::Params;
use mp_pose::VideoReader;
use serde::Serialize;

use crate::error::{Result, VideoError};
use crate::motion::VideoMotion;
use crate::plan::{AtomicVideo, RenderParams};

mod check;
mod guide;
mod warp;

pub use check::{motion_supported, warps_agree};
pub use guide::Guide;
use warp::between;

/// The supported factors.
pub const FACTORS: [usize; 3] = [2, 4, 8];

/// How the in-between frames are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[non_exhaustive]
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
#[non_exhaustive]
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
    /// Target pose between frames `i` and `i + 1` ([`mp_concrete::InBetweenPoses`]):
    /// default [`InBetween::default`], a cubic Hermite curve (the program's
    /// spline primitive over one frame interval) through the two detected
    /// keypoints with Catmull–Rom velocities from the neighbouring frames. `InBetween::Bulge { max_bulge: 0.5 }` is the earlier default
    /// (the chord plus the program's bulge away from its own chord, at most
    /// half the chord).
    pub inbetween: InBetween,
    /// Pose model on the input: seconds after a lost person during which
    /// the region of the last pose is tried again
    /// (`mp_pose::BlazePoseParams::recover_s`). Default 0, MediaPipe's
    /// tracking: on the validation videos at 8×, 1 s found the person on more
    /// kept frames but gave frames whose arms were further from the truth
    /// (KD in the truth's crops 53.1 against 49.3 px) at 0.05 dB less PSNR.
    pub recover_s: f64,
    /// Check each joint's detected motion against the pixels
    /// (`motion_supported`): where the patch around the joint matches the
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
    /// Check each pair of frames as a whole: at the middle time, the two
    /// frames warped to the target pose must agree with each other, on the
    /// person, at least as well as the two frames do unwarped
    /// (`warps_agree`). Where they do not, the warp moves pixels the way
    /// the pixels do not move (keypoints on something other than the
    /// person, or jumping between frames) and the pair is blended linearly.
    pub warp_check: bool,
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
            inbetween: InBetween::default(),
            recover_s: 0.0,
            pixel_check: false,
            min_confidence: VideoMotion::MIN_CONFIDENCE,
            warp_check: false,
            render: RenderParams::default(),
        }
    }
}

impl InterpParams {
    /// Errors unless the interpolation factor `factor` is 2, 4 or 8.
    pub fn check_factor(factor: usize) -> Result<()> {
        if FACTORS.contains(&factor) {
            Ok(())
        } else {
            Err(VideoError::Factor(factor))
        }
    }

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
        self.inbetween
            .validate()
            .map_err(|e| VideoError::param("inbetween", e.to_string()))?;
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

/// Two neighbouring frames (RGB, `size` = width × height).
pub struct Frames<'a> {
    /// Frame `i`.
    pub a: &'a [u8],
    /// Frame `i + 1`.
    pub b: &'a [u8],
    /// Width and height in pixels.
    pub size: (usize, usize),
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
    InterpParams::check_factor(factor)?;
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
            let pair_guide = match &guide {
                Some(g)
                    if params.warp_check
                        && !warps_agree(g, &frames, n_in - 1, params, support.as_deref())? =>
                {
                    None
                }
                g => g.as_ref(),
            };
            for j in 1..factor {
                let w = j as f64 / factor as f64;
                let f = between(pair_guide, &frames, n_in - 1, w, params, support.as_deref())?;
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
    InterpParams::check_factor(factor)?;
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
