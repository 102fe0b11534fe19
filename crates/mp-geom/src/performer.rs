//! A procedurally generated performer: the project's own motion data.
//!
//! A kinematic 3D body (pelvis, spine, head, arms and legs with fixed bone
//! lengths, proportioned for a person of [`PerformerParams::body_height_m`])
//! performs a routine of moves. Each move is a smooth joint-angle pattern
//! over one repetition (phase 0 → 1) that starts and ends in the same pose,
//! so repetitions join without a jump; moves are joined by short eased
//! transitions. The output is a COCO-17 track in metres (x = performer's
//! left, y up, z towards the camera), a COCO-17 track in pixels seen by a
//! camera in front of the performer, and the ground-truth frame ranges of
//! every move and repetition (for testing loop and segment detection).
//!
//! Randomness (seeded, [`rand_chacha::ChaCha8Rng`]): each repetition's
//! amplitude and duration vary by [`PerformerParams::variation`], and the
//! pixel track gets Gaussian noise of [`PerformerParams::noise_px`]. Bone
//! lengths in the 3D track are exact for every rigid bone (upper arms,
//! forearms, thighs, shins, shoulder and hip widths, face).

use std::f64::consts::PI;
use std::ops::Range;

use nalgebra::{Matrix3, Vector3};
use ndarray::{Array2, Array3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::error::{GeomError, Result};
use crate::skeleton::Skeleton;
use crate::track::{Track, Units};

/// A move of the routine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Move {
    /// Jumping jacks: arms from the sides to overhead while the feet hop apart.
    JumpingJack,
    /// Squats: hips and knees bend, trunk leans, arms reach forward; feet stay put.
    Squat,
    /// Arm circles: both straight arms sweep full circles in the frontal plane.
    ArmCircle,
    /// A golf-like swing: address, backswing with trunk turn, downswing,
    /// follow-through, and back to address.
    GolfSwing,
}

impl Move {
    /// Duration of one repetition relative to [`PerformerParams::rep_seconds`]:
    /// jumping jack and arm circle 1, squat 1.5, golf swing 2.5.
    pub fn tempo_factor(&self) -> f64 {
        match self {
            Move::JumpingJack | Move::ArmCircle => 1.0,
            Move::Squat => 1.5,
            Move::GolfSwing => 2.5,
        }
    }
    /// Short name.
    pub fn name(&self) -> &'static str {
        match self {
            Move::JumpingJack => "jumping_jack",
            Move::Squat => "squat",
            Move::ArmCircle => "arm_circle",
            Move::GolfSwing => "golf_swing",
        }
    }
}

/// How the 3D body is seen in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Projection {
    /// Parallel projection onto the x–y plane.
    Orthographic,
    /// Pinhole camera on the z axis at this distance from the performer,
    /// 1 m above the ground, with the same scale as orthographic at z = 0.
    Perspective {
        /// Distance from the camera to the performer's plane (m).
        camera_distance_m: f64,
    },
}

/// Parameters of [`perform`]. Defaults: 4 jumping jacks, 3 squats, 3 arm
/// circles and 1 golf swing at 30 fps, 1.2 s per repetition (times the
/// move's [`Move::tempo_factor`]), 0.5 s transitions, 5 % variation,
/// 1 px noise, seed 0, 512×512 frames, orthographic, 1.75 m tall.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PerformerParams {
    /// The routine: each move with its number of repetitions (≥ 1).
    pub moves: Vec<(Move, usize)>,
    /// Frame rate.
    pub fps: f64,
    /// Seconds per repetition before [`Move::tempo_factor`].
    pub rep_seconds: f64,
    /// Seconds of eased transition between consecutive moves (0 = none).
    pub transition_seconds: f64,
    /// Relative standard deviation of each repetition's amplitude and
    /// duration (0 = identical repetitions), in [0, 0.3].
    pub variation: f64,
    /// Standard deviation of Gaussian pixel noise on the 2D track.
    pub noise_px: f64,
    /// Random seed.
    pub seed: u64,
    /// Frame size in pixels (width, height).
    pub frame_size_px: (usize, usize),
    /// Camera model.
    pub projection: Projection,
    /// Body height in metres (scales every bone).
    pub body_height_m: f64,
}

impl Default for PerformerParams {
    fn default() -> Self {
        PerformerParams {
            moves: vec![
                (Move::JumpingJack, 4),
                (Move::Squat, 3),
                (Move::ArmCircle, 3),
                (Move::GolfSwing, 1),
            ],
            fps: 30.0,
            rep_seconds: 1.2,
            transition_seconds: 0.5,
            variation: 0.05,
            noise_px: 1.0,
            seed: 0,
            frame_size_px: (512, 512),
            projection: Projection::Orthographic,
            body_height_m: 1.75,
        }
    }
}

impl PerformerParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<()> {
        let pos = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(GeomError::param(
                    name,
                    format!("must be finite and > 0, got {v}"),
                ))
            }
        };
        if self.moves.is_empty() {
            return Err(GeomError::param("moves", "the routine has no moves"));
        }
        if let Some((m, _)) = self.moves.iter().find(|(_, r)| *r == 0) {
            return Err(GeomError::param(
                "moves",
                format!("`{}` has 0 repetitions", m.name()),
            ));
        }
        pos("fps", self.fps)?;
        pos("rep_seconds", self.rep_seconds)?;
        pos("body_height_m", self.body_height_m)?;
        if self.rep_seconds * self.fps < 4.0 {
            return Err(GeomError::param(
                "rep_seconds",
                format!(
                    "{} s at {} fps is under 4 frames per repetition",
                    self.rep_seconds, self.fps
                ),
            ));
        }
        if !(self.transition_seconds.is_finite() && self.transition_seconds >= 0.0) {
            return Err(GeomError::param(
                "transition_seconds",
                "must be finite and ≥ 0",
            ));
        }
        if !(0.0..=0.3).contains(&self.variation) {
            return Err(GeomError::param(
                "variation",
                format!("must be in [0, 0.3], got {}", self.variation),
            ));
        }
        if !(self.noise_px.is_finite() && self.noise_px >= 0.0) {
            return Err(GeomError::param("noise_px", "must be finite and ≥ 0"));
        }
        if self.frame_size_px.0 < 16 || self.frame_size_px.1 < 16 {
            return Err(GeomError::param(
                "frame_size_px",
                format!("{:?} is smaller than 16×16", self.frame_size_px),
            ));
        }
        if let Projection::Perspective { camera_distance_m } = self.projection {
            if !(camera_distance_m.is_finite() && camera_distance_m > 1.5) {
                return Err(GeomError::param(
                    "projection",
                    format!("camera distance {camera_distance_m} m must be > 1.5 m"),
                ));
            }
        }
        Ok(())
    }
}

/// Ground truth of one move in the routine.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct MoveSegment {
    /// The move.
    pub kind: Move,
    /// Frames of the whole move (all repetitions, no transitions).
    pub frames: Range<usize>,
    /// Frames of each repetition, contiguous, covering `frames`.
    pub reps: Vec<Range<usize>>,
}

/// Output of [`perform`].
#[derive(Debug, Clone)]
pub struct Performance {
    /// COCO-17 positions in metres (x = performer's left, y up, z to camera).
    pub track_3d: Track,
    /// COCO-17 positions in pixels (y down), with noise.
    pub track_2d: Track,
    /// Ground-truth moves and repetitions, in order.
    pub segments: Vec<MoveSegment>,
    /// Pixels per metre at the performer's plane.
    pub px_per_m: f64,
}

/// COCO-17 bones whose length never changes in the 3D track: upper arms,
/// forearms, thighs, shins, shoulder and hip widths, face.
#[cfg(test)]
pub const RIGID_BONES: [(usize, usize); 12] = [
    (5, 7),
    (7, 9),
    (6, 8),
    (8, 10),
    (11, 13),
    (13, 15),
    (12, 14),
    (14, 16),
    (5, 6),
    (11, 12),
    (0, 1),
    (0, 2),
];

// Pose parameters (degrees unless noted), indices into `Pose`.
const ROOT_X: usize = 0; // m
const ROOT_Y: usize = 1; // m
const ROOT_Z: usize = 2; // m
const TRUNK_FLEX: usize = 3; // forward lean
const TRUNK_TWIST: usize = 4; // + turns towards the performer's left
const HEAD_FLEX: usize = 5;
const L_SH_ABD: usize = 6; // arm away from the body in the frontal plane
const L_SH_FLEX: usize = 7; // arm forward
const L_SH_HORIZ: usize = 8; // arm towards the front/midline about the vertical
const L_ELBOW: usize = 9;
const R_SH_ABD: usize = 10;
const R_SH_FLEX: usize = 11;
const R_SH_HORIZ: usize = 12;
const R_ELBOW: usize = 13;
const L_HIP_ABD: usize = 14;
const L_HIP_FLEX: usize = 15;
const L_KNEE: usize = 16;
const R_HIP_ABD: usize = 17;
const R_HIP_FLEX: usize = 18;
const R_KNEE: usize = 19;
const NP: usize = 20;

type Pose = [f64; NP];

fn lerp(a: &Pose, b: &Pose, w: f64) -> Pose {
    let mut p = [0.0; NP];
    for k in 0..NP {
        p[k] = a[k] * (1.0 - w) + b[k] * w;
    }
    p
}

/// Smooth 0 → 1 easing with zero slope at both ends.
fn ease(w: f64) -> f64 {
    let w = w.clamp(0.0, 1.0);
    0.5 - 0.5 * (PI * w).cos()
}

/// Bone lengths (m) for a given body height.
#[derive(Debug, Clone, Copy)]
struct Body {
    thigh: f64,
    shin: f64,
    ankle_h: f64,
    hip_half: f64,
    spine: f64,
    shoulder_half: f64,
    upper_arm: f64,
    forearm: f64,
    neck: f64,
}

impl Body {
    fn new(height_m: f64) -> Self {
        let k = height_m / 1.75;
        Body {
            thigh: 0.43 * k,
            shin: 0.42 * k,
            ankle_h: 0.08 * k,
            hip_half: 0.09 * k,
            spine: 0.50 * k,
            shoulder_half: 0.18 * k,
            upper_arm: 0.30 * k,
            forearm: 0.26 * k,
            neck: 0.14 * k,
        }
    }
    fn hip_height(&self) -> f64 {
        self.ankle_h + self.thigh + self.shin
    }
}

fn rx(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}
fn ry(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}
fn rz(deg: f64) -> Matrix3<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Forward kinematics: the 17 COCO joints of a pose.
fn pose_to_coco(p: &Pose, b: &Body) -> [Vector3<f64>; 17] {
    let down = Vector3::new(0.0, -1.0, 0.0);
    let pelvis = Vector3::new(p[ROOT_X], b.hip_height() + p[ROOT_Y], p[ROOT_Z]);
    let r_pelvis = ry(0.4 * p[TRUNK_TWIST]);
    let r_trunk = r_pelvis * ry(0.6 * p[TRUNK_TWIST]) * rx(p[TRUNK_FLEX]);
    let mut out = [Vector3::zeros(); 17];
    // Legs: side = +1 left, −1 right.
    for (side, hip_i, abd, flex, knee) in [
        (1.0, 11, L_HIP_ABD, L_HIP_FLEX, L_KNEE),
        (-1.0, 12, R_HIP_ABD, R_HIP_FLEX, R_KNEE),
    ] {
        let hip = pelvis + r_pelvis * Vector3::new(side * b.hip_half, 0.0, 0.0);
        let r_thigh = r_pelvis * rz(side * p[abd]) * rx(-p[flex]);
        let knee_p = hip + r_thigh * down * b.thigh;
        let r_shin = r_thigh * rx(p[knee]);
        let ankle = knee_p + r_shin * down * b.shin;
        out[hip_i] = hip;
        out[hip_i + 2] = knee_p;
        out[hip_i + 4] = ankle;
    }
    // Trunk and arms.
    let neck = pelvis + r_trunk * Vector3::new(0.0, b.spine, 0.0);
    for (side, sh_i, abd, flex, horiz, elbow) in [
        (1.0, 5, L_SH_ABD, L_SH_FLEX, L_SH_HORIZ, L_ELBOW),
        (-1.0, 6, R_SH_ABD, R_SH_FLEX, R_SH_HORIZ, R_ELBOW),
    ] {
        let sh = neck + r_trunk * Vector3::new(side * b.shoulder_half, 0.0, 0.0);
        let r_ua = r_trunk * ry(-side * p[horiz]) * rz(side * p[abd]) * rx(-p[flex]);
        let el = sh + r_ua * down * b.upper_arm;
        let r_fa = r_ua * rx(-p[elbow]);
        let wr = el + r_fa * down * b.forearm;
        out[sh_i] = sh;
        out[sh_i + 2] = el;
        out[sh_i + 4] = wr;
    }
    // Head.
    let r_head = r_trunk * rx(p[HEAD_FLEX]);
    let k = b.neck / 0.14;
    let hc = neck + r_head * Vector3::new(0.0, b.neck, 0.0);
    out[0] = hc + r_head * Vector3::new(0.0, 0.0, 0.10 * k);
    out[1] = hc + r_head * Vector3::new(0.032 * k, 0.035 * k, 0.085 * k);
    out[2] = hc + r_head * Vector3::new(-0.032 * k, 0.035 * k, 0.085 * k);
    out[3] = hc + r_head * Vector3::new(0.075 * k, 0.01 * k, 0.0);
    out[4] = hc + r_head * Vector3::new(-0.075 * k, 0.01 * k, 0.0);
    out
}

/// Pose of `mv` at phase `ph` ∈ [0, 1] with amplitude factor `a`; phase 0
/// and 1 give the same pose.
fn move_pose(mv: Move, ph: f64, a: f64, b: &Body) -> Pose {
    let mut p = [0.0; NP];
    let s = 0.5 - 0.5 * (2.0 * PI * ph).cos();
    match mv {
        Move::JumpingJack => {
            let arm = 10.0 + 155.0 * s * a;
            p[L_SH_ABD] = arm;
            p[R_SH_ABD] = arm;
            p[L_ELBOW] = 10.0;
            p[R_ELBOW] = 10.0;
            p[L_HIP_ABD] = 3.0 + 12.0 * s * a;
            p[R_HIP_ABD] = 3.0 + 12.0 * s * a;
            // Two hops per cycle (out and in).
            p[ROOT_Y] = 0.05 * a * (2.0 * PI * ph).sin().powi(2);
        }
        Move::Squat => {
            let s = (s * a).min(1.1);
            let hip = 95.0 * s;
            let knee = 115.0 * s;
            p[L_HIP_FLEX] = hip;
            p[R_HIP_FLEX] = hip;
            p[L_KNEE] = knee;
            p[R_KNEE] = knee;
            p[TRUNK_FLEX] = 35.0 * s;
            p[L_SH_FLEX] = 85.0 * s;
            p[R_SH_FLEX] = 85.0 * s;
            p[L_ELBOW] = 5.0;
            p[R_ELBOW] = 5.0;
            // Keep the ankles where they are: move the pelvis down and back.
            let (al, kl) = (hip.to_radians(), (knee - hip).to_radians());
            p[ROOT_Y] = b.thigh * al.cos() + b.shin * kl.cos() - (b.thigh + b.shin);
            p[ROOT_Z] = -(b.thigh * al.sin() - b.shin * kl.sin());
        }
        Move::ArmCircle => {
            let th = 360.0 * ph;
            p[L_SH_ABD] = th;
            p[R_SH_ABD] = th;
            p[L_SH_FLEX] = 20.0 * a;
            p[R_SH_FLEX] = 20.0 * a;
            p[L_ELBOW] = 5.0;
            p[R_ELBOW] = 5.0;
        }
        Move::GolfSwing => {
            // Keyframes: address, top of backswing, impact, follow-through,
            // finish, address again.
            let keys: [(f64, [f64; 10]); 6] = [
                // twist, trunk flex, L flex, L horiz, L elbow, R flex, R horiz, R elbow, knee, hip flex
                (
                    0.0,
                    [0.0, 30.0, 35.0, 20.0, 5.0, 35.0, 20.0, 10.0, 20.0, 25.0],
                ),
                (
                    0.40,
                    [
                        -85.0, 28.0, 110.0, 65.0, 5.0, 100.0, -10.0, 90.0, 25.0, 25.0,
                    ],
                ),
                (
                    0.55,
                    [10.0, 30.0, 35.0, 20.0, 5.0, 40.0, 25.0, 10.0, 20.0, 25.0],
                ),
                (
                    0.68,
                    [75.0, 20.0, 95.0, -15.0, 60.0, 110.0, 60.0, 5.0, 15.0, 15.0],
                ),
                (
                    0.80,
                    [90.0, 10.0, 140.0, 10.0, 90.0, 140.0, 40.0, 60.0, 10.0, 10.0],
                ),
                (
                    1.0,
                    [0.0, 30.0, 35.0, 20.0, 5.0, 35.0, 20.0, 10.0, 20.0, 25.0],
                ),
            ];
            let i = keys
                .windows(2)
                .position(|w| ph <= w[1].0)
                .unwrap_or(keys.len() - 2);
            let (t0, k0) = keys[i];
            let (t1, k1) = keys[i + 1];
            let w = ease((ph - t0) / (t1 - t0));
            let v: Vec<f64> = k0
                .iter()
                .zip(&k1)
                .map(|(x, y)| x * (1.0 - w) + y * w)
                .collect();
            p[TRUNK_TWIST] = v[0] * a;
            p[TRUNK_FLEX] = v[1];
            p[HEAD_FLEX] = 20.0;
            p[L_SH_FLEX] = v[2];
            p[L_SH_HORIZ] = v[3];
            p[L_ELBOW] = v[4];
            p[R_SH_FLEX] = v[5];
            p[R_SH_HORIZ] = v[6];
            p[R_ELBOW] = v[7];
            p[L_KNEE] = v[8];
            p[R_KNEE] = v[8];
            p[L_HIP_FLEX] = v[9];
            p[R_HIP_FLEX] = v[9];
            // Knees and hips bent: lower the pelvis so the feet stay on the ground.
            let (al, kl) = (v[9].to_radians(), (v[8] - v[9]).to_radians());
            p[ROOT_Y] = b.thigh * al.cos() + b.shin * kl.cos() - (b.thigh + b.shin);
            p[ROOT_Z] = -(b.thigh * al.sin() - b.shin * kl.sin());
        }
    }
    p
}

/// Generates the routine. Errors only on invalid parameters.
pub fn perform(params: &PerformerParams) -> Result<Performance> {
    params.validate()?;
    let body = Body::new(params.body_height_m);
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let unit = Normal::new(0.0, 1.0).map_err(|e| GeomError::param("variation", e.to_string()))?;
    let transition = (params.transition_seconds * params.fps).round() as usize;

    // Timeline: per frame, the pose; plus ground-truth segments.
    let mut poses: Vec<Pose> = Vec::new();
    let mut segments = Vec::with_capacity(params.moves.len());
    for (mi, &(mv, reps)) in params.moves.iter().enumerate() {
        if mi > 0 && transition > 0 {
            let from = poses.last().copied().unwrap_or([0.0; NP]);
            let to = move_pose(mv, 0.0, 1.0, &body);
            for f in 1..=transition {
                poses.push(lerp(&from, &to, ease(f as f64 / (transition + 1) as f64)));
            }
        }
        let start = poses.len();
        let mut rep_ranges = Vec::with_capacity(reps);
        let base = params.rep_seconds * mv.tempo_factor() * params.fps;
        for _ in 0..reps {
            let jitter_t: f64 = unit.sample(&mut rng);
            let jitter_a: f64 = unit.sample(&mut rng);
            let dur_f = base * (1.0 + params.variation * jitter_t.clamp(-2.5, 2.5));
            let n = (dur_f.round() as usize).max(4);
            let amp = 1.0 + params.variation * jitter_a.clamp(-2.5, 2.5);
            let r0 = poses.len();
            for f in 0..n {
                poses.push(move_pose(mv, f as f64 / n as f64, amp, &body));
            }
            rep_ranges.push(r0..poses.len());
        }
        segments.push(MoveSegment {
            kind: mv,
            frames: start..poses.len(),
            reps: rep_ranges,
        });
    }

    let t = poses.len();
    let mut p3 = Array3::<f64>::zeros((t, 17, 3));
    for (f, pose) in poses.iter().enumerate() {
        for (j, v) in pose_to_coco(pose, &body).iter().enumerate() {
            for k in 0..3 {
                p3[[f, j, k]] = v[k];
            }
        }
    }

    // Camera: the tallest reach (arms overhead plus a hop) fits in 80 % of
    // the height, the widest (arms out) in 90 % of the width; feet at 90 %.
    let (w, h) = (params.frame_size_px.0 as f64, params.frame_size_px.1 as f64);
    let scale_m = params.body_height_m / 1.75;
    let px_per_m = (0.8 * h / (2.4 * scale_m)).min(0.9 * w / (2.0 * scale_m));
    let ground_v = 0.9 * h;
    let cx = 0.5 * w;
    let noise = Normal::new(0.0, params.noise_px.max(0.0))
        .map_err(|e| GeomError::param("noise_px", e.to_string()))?;
    let mut p2 = Array3::<f64>::zeros((t, 17, 2));
    for f in 0..t {
        for j in 0..17 {
            let (x, y, z) = (p3[[f, j, 0]], p3[[f, j, 1]], p3[[f, j, 2]]);
            let (u, v) = match params.projection {
                Projection::Orthographic => (cx + px_per_m * x, ground_v - px_per_m * y),
                Projection::Perspective {
                    camera_distance_m: d,
                } => {
                    let y_cam = 1.0 * scale_m;
                    let k = d / (d - z).max(0.1);
                    (
                        cx + px_per_m * x * k,
                        ground_v - px_per_m * y_cam - px_per_m * (y - y_cam) * k,
                    )
                }
            };
            let (nu, nv) = if params.noise_px > 0.0 {
                (noise.sample(&mut rng), noise.sample(&mut rng))
            } else {
                (0.0, 0.0)
            };
            p2[[f, j, 0]] = u + nu;
            p2[[f, j, 1]] = v + nv;
        }
    }
    let conf = Array2::<f64>::ones((t, 17));
    let track_3d = Track::new(
        p3,
        Some(conf.clone()),
        params.fps,
        Units::Metres,
        Skeleton::coco17(),
    )?;
    let track_2d = Track::new(
        p2,
        Some(conf),
        params.fps,
        Units::Pixels,
        Skeleton::coco17(),
    )?;
    Ok(Performance {
        track_3d,
        track_2d,
        segments,
        px_per_m,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_are_periodic() {
        let b = Body::new(1.75);
        for mv in [
            Move::JumpingJack,
            Move::Squat,
            Move::ArmCircle,
            Move::GolfSwing,
        ] {
            let a = pose_to_coco(&move_pose(mv, 0.0, 1.0, &b), &b);
            let z = pose_to_coco(&move_pose(mv, 1.0, 1.0, &b), &b);
            for j in 0..17 {
                assert!((a[j] - z[j]).norm() < 1e-9, "{mv:?} joint {j}");
            }
        }
    }

    #[test]
    fn squat_keeps_feet_on_the_ground() {
        let b = Body::new(1.75);
        let stand = pose_to_coco(&move_pose(Move::Squat, 0.0, 1.0, &b), &b);
        let deep = pose_to_coco(&move_pose(Move::Squat, 0.5, 1.0, &b), &b);
        assert!((stand[15] - deep[15]).norm() < 1e-9);
        assert!(deep[11][1] < stand[11][1] - 0.3, "hips go down");
        assert!((stand[15][1] - b.ankle_h).abs() < 1e-9);
    }
}
