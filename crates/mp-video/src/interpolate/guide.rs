//! The pose model's keypoints, the program fitted to them, and the target
//! pose (with the control points of the warp) at an in-between time.

use std::path::Path;

use mp_concrete::{InBetween, InBetweenPoses, Program};
use mp_geom::{CancelToken, Track};
use mp_pipeline::{Input, Keep, Params, Silent};

use super::{motion_supported, Frames, InterpParams};
use crate::error::{Result, VideoError};

/// The keypoints of a video and the program fitted to them.
pub struct Guide {
    /// Keypoints (COCO-17, pixels).
    pub track: Track,
    /// The concrete program fitted to them.
    pub program: Program,
    /// How the pose between two frames is made ([`InterpParams::inbetween`]).
    pub inbetween: InBetween,
    /// Confidence above which a joint is seen ([`InterpParams::min_confidence`]).
    pub min_confidence: f64,
}

impl Guide {
    /// Runs the pose model over `input` and fits the program, as `mp run`
    /// does, with the pose model's recovery of `params`; then
    /// [`Guide::from_track`].
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
        Self::from_track(track, frame_px, analysis, params)
    }

    /// The guide of keypoints already found (the frames of the video to be
    /// interpolated, `frame_px` its larger side): fits the program with
    /// `mp_pipeline::concrete_program` and the in-between rule of `params`.
    /// What [`Guide::fit`] does after the pose model.
    pub fn from_track(
        track: Track,
        frame_px: Option<f64>,
        analysis: &Params,
        params: &InterpParams,
    ) -> Result<Self> {
        params.validate()?;
        if track.valid_count() == 0 || track.n_frames() < 2 {
            return Err(VideoError::param(
                "track",
                format!(
                    "needs at least 2 frames and a seen joint, got {} frames and {} seen keypoints",
                    track.n_frames(),
                    track.valid_count()
                ),
            ));
        }
        let syn = mp_pipeline::concrete_program(&track, frame_px, analysis)?;
        Ok(Guide {
            track,
            program: syn.program,
            inbetween: params.inbetween,
            min_confidence: params.min_confidence,
        })
    }

    /// The in-between poses of the track ([`InBetweenPoses`]).
    pub fn poses(&self) -> Result<InBetweenPoses<'_>> {
        InBetweenPoses::new(
            &self.track,
            Some(&self.program),
            self.inbetween,
            self.min_confidence,
        )
        .map_err(|e| VideoError::Program(e.to_string()))
    }

    pub(super) fn seen(&self, t: usize, j: usize) -> bool {
        t < self.track.n_frames() && self.track.is_valid(t, j, self.min_confidence)
    }

    /// The pose the in-between frame at time `i + w` (`0 ≤ w ≤ 1`) is warped
    /// to, per joint (`None` where neither neighbour shows the joint): the
    /// in-between rule ([`InterpParams::inbetween`], [`InBetweenPoses`])
    /// between the detected keypoints of frames `i` and `i + 1`.
    ///
    /// This is the pose before the pixels are consulted: the warp of
    /// [`super::interpolate_frames`] also leaves in place the joints whose detected
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
    pub(super) fn pixel_support(
        &self,
        i: usize,
        frames: &Frames<'_>,
        params: &InterpParams,
    ) -> Vec<bool> {
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
    pub(super) fn targets(
        &self,
        i: usize,
        w: f64,
        support: Option<&[bool]>,
    ) -> Result<Option<Vec<Option<Target>>>> {
        let Some(pose) = self
            .poses()?
            .pose(i, w)
            .map_err(|e| VideoError::Program(e.to_string()))?
        else {
            return Ok(None);
        };
        let nj = pose.len();
        let mut targets = vec![None; nj];
        for (j, tp) in pose.iter().enumerate() {
            let (va, vb) = (self.seen(i, j), self.seen(i + 1, j));
            let ka = [self.track.point(i, j)[0], self.track.point(i, j)[1]];
            let kb = [self.track.point(i + 1, j)[0], self.track.point(i + 1, j)[1]];
            // Between two seen keypoints the in-between rule; seen in one
            // frame only, held there ([`InBetweenPoses::pose`]).
            let Some(tp) = tp else { continue };
            let t = [tp[0], tp.get(1).copied().unwrap_or(f64::NAN)];
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
    pub(super) fn controls(
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
pub(super) struct Target {
    /// Where the body is drawn (the target pose).
    at: [f64; 2],
    /// Where frame `i` shows the joint and where its pixels there go; `None`
    /// where frame `i` does not show it.
    a: Option<([f64; 2], [f64; 2])>,
    /// The same for frame `i + 1`.
    b: Option<([f64; 2], [f64; 2])>,
}

/// COCO-17 shoulder–hip diagonals, so the body mask covers the torso.
const TORSO_DIAGONALS: [(usize, usize); 2] = [(5, 12), (6, 11)];

pub(super) type Segment = ([f64; 2], [f64; 2]);

pub(super) struct Controls {
    pub(super) a: Vec<([f64; 2], [f64; 2])>,
    pub(super) b: Vec<([f64; 2], [f64; 2])>,
    pub(super) sigma: f64,
    pub(super) radius: f64,
    pub(super) seg_t: Vec<Segment>,
    pub(super) seg_a: Vec<Segment>,
    pub(super) seg_b: Vec<Segment>,
    /// (segment at the target pose, the same segment in frame `i`).
    pub(super) bone_a: Vec<(Segment, Segment)>,
    /// (segment at the target pose, the same segment in frame `i + 1`).
    pub(super) bone_b: Vec<(Segment, Segment)>,
}
