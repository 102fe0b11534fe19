//! Pose only where it is needed: the pose model on a subset of a video's
//! frames, the frames between filled from the motion itself.
//!
//! [`PoseRate`] says how often the model runs: on every frame, at least `N`
//! times a second (every `⌊fps / N⌋`-th frame, and the last), or at the
//! automatic rate [`AUTO_POSE_FPS`]. [`fill_track`] and [`fill_people`]
//! then give every skipped frame the pose between its two posed
//! neighbours, per joint, with `mp_concrete`'s in-between rule
//! ([`mp_concrete::InBetween::default`]): the cubic spline primitive through
//! the two keypoints, its velocities from the neighbouring keypoints
//! (Catmull–Rom), kept within half the chord of the chord. That rule was
//! chosen over linear interpolation and over the fitted program's own
//! velocities on held-out frames of four datasets (`cargo xtask eval
//! inbetween`). A joint seen at one end only is held there; a joint seen at
//! neither end stays missing, so no keypoint is invented where the model
//! saw nothing.

use mp_concrete::{InBetween, InBetweenPoses};
use mp_geom::{People, Person, Track};
use ndarray::Axis;

use crate::error::{PipelineError, Result};

/// The rate [`PoseRate::Auto`] asks for: at least 12 poses a second, five
/// or more per cycle of repetitions as fast as 0.4 s (rope skipping). Every
/// frame of a video below 24 fps, every second frame at 24–30 fps, every
/// fifth at 60 fps.
pub const AUTO_POSE_FPS: f64 = 12.0;

/// How often the pose model runs on a video.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[non_exhaustive]
pub enum PoseRate {
    /// On every frame. Default.
    #[default]
    Every,
    /// At least this many times a second: every `⌊fps / N⌋`-th frame (every
    /// frame when the video has no more than `N` frames a second).
    Fps(f64),
    /// `AUTO_POSE_FPS`.
    Auto,
}

impl PoseRate {
    /// Parses `all` (every frame), `auto`, or a number of poses a second.
    pub fn parse(text: &str) -> Result<Self> {
        let t = text.trim().to_ascii_lowercase();
        let rate = match t.as_str() {
            "all" | "every" => PoseRate::Every,
            "auto" => PoseRate::Auto,
            other => match other.parse::<f64>() {
                Ok(n) => PoseRate::Fps(n),
                Err(_) => {
                    return Err(PipelineError::param(
                        "pose_fps",
                        format!("`{text}` is neither `all`, `auto` nor a number of poses a second"),
                    ))
                }
            },
        };
        rate.validate()?;
        Ok(rate)
    }

    /// Checks the rate: a number of poses a second must be finite and > 0.
    pub fn validate(&self) -> Result<()> {
        match self {
            PoseRate::Fps(n) if !(n.is_finite() && *n > 0.0) => Err(PipelineError::param(
                "pose_fps",
                format!("must be a number of poses a second > 0, got {n}"),
            )),
            _ => Ok(()),
        }
    }

    /// The model runs on every `stride`-th frame of a video at `video_fps`.
    pub fn stride(&self, video_fps: f64) -> usize {
        let n = match self {
            PoseRate::Every => return 1,
            PoseRate::Fps(n) => *n,
            PoseRate::Auto => AUTO_POSE_FPS,
        };
        if !(video_fps.is_finite() && video_fps > 0.0 && n.is_finite() && n > 0.0) {
            return 1;
        }
        // A little tolerance: 29.97 fps at 14.985 a second is every second frame.
        (video_fps / n + 0.01).floor().max(1.0) as usize
    }

    /// Short form: `all`, `auto` or the number.
    pub fn label(&self) -> String {
        match self {
            PoseRate::Every => "all".into(),
            PoseRate::Auto => "auto".into(),
            PoseRate::Fps(n) => format!("{n}"),
        }
    }
}

/// Confidence of a filled joint: the lower of its two ends' confidences
/// where both show it, the one end's where only one does.
fn filled_confidence(a: f64, b: f64) -> f64 {
    match (a > 0.0, b > 0.0) {
        (true, true) => a.min(b),
        (true, false) => a,
        (false, true) => b,
        (false, false) => 0.0,
    }
}

/// `track` with its frames where `posed` is false filled from the posed
/// frames around them (see the module docs). Frames before the first posed
/// frame and after the last stay as they are.
pub fn fill_track(track: &Track, posed: &[bool]) -> Result<Track> {
    let n = track.n_frames();
    if posed.len() != n {
        return Err(PipelineError::param(
            "posed",
            format!("has {} frames, the track {n}", posed.len()),
        ));
    }
    let idx: Vec<usize> = (0..n).filter(|&i| posed[i]).collect();
    if idx.len() == n || idx.len() < 2 {
        return Ok(track.clone());
    }
    let sub = Track::new(
        track.positions().select(Axis(0), &idx),
        Some(track.confidence().select(Axis(0), &idx)),
        track.fps(),
        track.units(),
        track.skeleton().clone(),
    )?;
    let between = InBetweenPoses::new(&sub, None, InBetween::default(), 0.0)?;
    let mut pos = track.positions().to_owned();
    let mut conf = track.confidence().to_owned();
    let sub_conf = sub.confidence();
    for (k, pair) in idx.windows(2).enumerate() {
        let (a, b) = (pair[0], pair[1]);
        for f in a + 1..b {
            let w = (f - a) as f64 / (b - a) as f64;
            let Some(pose) = between.pose(k, w)? else {
                continue;
            };
            for (j, p) in pose.into_iter().enumerate() {
                let Some(p) = p else { continue };
                for (d, v) in p.iter().enumerate() {
                    pos[[f, j, d]] = *v;
                }
                conf[[f, j]] = filled_confidence(sub_conf[[k, j]], sub_conf[[k + 1, j]]);
            }
        }
    }
    Ok(Track::new(
        pos,
        Some(conf),
        track.fps(),
        track.units(),
        track.skeleton().clone(),
    )?)
}

/// Every person of `people` through [`fill_track`]; `posed` is per video
/// frame.
pub fn fill_people(people: People, posed: &[bool]) -> Result<People> {
    let (n, fps) = (people.n_frames(), people.fps());
    if posed.len() != n {
        return Err(PipelineError::param(
            "posed",
            format!("has {} frames, the video {n}", posed.len()),
        ));
    }
    let filled = people
        .into_people()
        .into_iter()
        .map(|p| {
            let end = p.first_frame + p.track.n_frames();
            let mask = posed.get(p.first_frame..end).ok_or_else(|| {
                PipelineError::param(
                    "posed",
                    format!(
                        "person {} lasts to frame {end}, the video has {n} frames",
                        p.id
                    ),
                )
            })?;
            Ok(Person {
                track: fill_track(&p.track, mask)?,
                ..p
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(People::new(n, fps, filled)?)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use mp_geom::{Skeleton, Units};
    use ndarray::{Array2, Array3};

    /// A joint moving along a circle of radius 100 px, 2 s per turn, at 30 fps.
    fn circle(n: usize) -> Track {
        let mut pos = Array3::zeros((n, 1, 2));
        for t in 0..n {
            let a = std::f64::consts::PI * t as f64 / 30.0;
            pos[[t, 0, 0]] = 300.0 + 100.0 * a.cos();
            pos[[t, 0, 1]] = 200.0 + 100.0 * a.sin();
        }
        let conf = Array2::from_elem((n, 1), 0.9);
        Track::new(pos, Some(conf), 30.0, Units::Pixels, Skeleton::generic(1)).unwrap()
    }

    #[test]
    fn strides_follow_the_video_rate() {
        assert_eq!(PoseRate::Every.stride(30.0), 1);
        assert_eq!(PoseRate::Auto.stride(30.0), 2);
        assert_eq!(PoseRate::Auto.stride(29.0), 2);
        assert_eq!(PoseRate::Auto.stride(25.0), 2);
        assert_eq!(PoseRate::Auto.stride(23.976), 2);
        assert_eq!(PoseRate::Auto.stride(20.0), 1);
        assert_eq!(PoseRate::Auto.stride(60.0), 5);
        assert_eq!(PoseRate::Fps(10.0).stride(30.0), 3);
        assert_eq!(PoseRate::Fps(60.0).stride(30.0), 1);
    }

    #[test]
    fn rates_parse_and_bad_ones_are_named() {
        assert_eq!(PoseRate::parse("all").unwrap(), PoseRate::Every);
        assert_eq!(PoseRate::parse("AUTO").unwrap(), PoseRate::Auto);
        assert_eq!(PoseRate::parse("15").unwrap(), PoseRate::Fps(15.0));
        for bad in ["0", "-3", "nan", "inf", "fast"] {
            let e = PoseRate::parse(bad).unwrap_err().to_string();
            assert!(e.contains("pose_fps"), "{bad}: {e}");
        }
    }

    #[test]
    fn skipped_frames_are_filled_close_to_the_motion() {
        let full = circle(61);
        let posed: Vec<bool> = (0..61).map(|i| i % 3 == 0).collect();
        let mut holed = full.clone();
        for (t, p) in posed.iter().enumerate() {
            if !p {
                holed.positions_mut()[[t, 0, 0]] = 0.0;
                holed.positions_mut()[[t, 0, 1]] = 0.0;
                holed.confidence_mut()[[t, 0]] = 0.0;
            }
        }
        let filled = fill_track(&holed, &posed).unwrap();
        let (mut inner, mut ends) = (0.0f64, 0.0f64);
        for t in 0..61 {
            let dx = filled.positions()[[t, 0, 0]] - full.positions()[[t, 0, 0]];
            let dy = filled.positions()[[t, 0, 1]] - full.positions()[[t, 0, 1]];
            let e = dx.hypot(dy);
            if (3..58).contains(&t) {
                inner = inner.max(e);
            } else {
                ends = ends.max(e);
            }
            assert!((filled.confidence()[[t, 0]] - 0.9).abs() < 1e-12);
        }
        // The chord over three frames (18°) is up to 100·(1 − cos 9°) ≈ 1.2 px
        // off the circle; the spline, with both neighbours, far closer. The
        // first and last gaps have one neighbour: about the chord.
        assert!(inner < 0.1, "inner {inner} px");
        assert!(ends < 1.3, "ends {ends} px");
    }

    #[test]
    fn a_joint_missing_at_both_ends_stays_missing() {
        let mut holed = circle(7);
        let posed = [true, false, false, true, false, false, true];
        for t in [0usize, 1, 2, 3] {
            holed.confidence_mut()[[t, 0]] = 0.0;
        }
        let filled = fill_track(&holed, &posed).unwrap();
        assert_eq!(filled.confidence()[[1, 0]], 0.0);
        assert_eq!(filled.confidence()[[2, 0]], 0.0);
        assert!(filled.confidence()[[4, 0]] > 0.0);
        assert!(fill_track(&holed, &posed[..5]).is_err());
    }
}
