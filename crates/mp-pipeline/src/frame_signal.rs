//! Step 1b: the frame signal that counting reads.
//!
//! Once a video's people are known, a second decoding pass reads grey
//! thumbnails of each analysed person's own box ([`frame_signal`]); the
//! main person's (or the whole frame's) are the usual signal.
//!
//! The thumbnails of the whole frame (or of the tracked person's own box)
//! miss a repetition that fills little of a cluttered, moving picture, and
//! the pose model often misses the person there too. So the motion energy of
//! the whole-frame thumbnails, with the camera's global motion discounted
//! (`mp_pose::motion`), locates where the picture moves on its own: for each
//! region side in [`REGION_SIDES`], the square region where that energy
//! gathers most (for a tracked person, among the squares inside their own
//! box: someone repeating beside them is not their repetition). Of these
//! regions' thumbnails and the usual ones, the most periodic signal — the
//! autocorrelation of its motion at its period
//! (`mp_abstract::estimate_period` with the frame settings), the periodicity
//! by which counting also chooses between keypoints and frames — is the frame
//! signal. The regions' cells are copied from the whole-frame thumbnails: no
//! extra decoding, and at most a quarter of their memory.

use std::path::Path;
use std::time::Instant;

use mp_abstract::estimate_period;
use mp_geom::{CancelToken, People, PersonId, Track};
use mp_pose::{grey_thumbnail_region, signal_side, VideoReader};
use mp_pose::{moving_regions, region_track, CellRegion, MotionEnergy, Thumbnails};

use crate::error::Result;
use crate::keypoints::Keypoints;
use crate::params::{Params, PoseParams};
use crate::progress::{check, Stage, Timings};

/// Sides of the candidate regions, as fractions of the thumbnail side: a
/// quarter, a third and half of the picture's side (a sixteenth to a
/// quarter of its area).
pub const REGION_SIDES: [f64; 3] = [0.25, 1.0 / 3.0, 0.5];

/// Which frame signal was chosen, and how periodic each candidate was.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameChoice {
    /// The chosen region of the whole-frame thumbnails; `None`: the usual
    /// thumbnails (the person's own box, or the whole frame).
    pub region: Option<CellRegion>,
    /// Periodicity of the usual thumbnails.
    pub base_periodicity: f64,
    /// Each moving region, its energy over the picture's mean, and its periodicity.
    pub regions: Vec<(CellRegion, f64, f64)>,
}

/// Periodicity of a frame signal (0 when it has no period).
fn periodicity(track: &Track, params: &Params) -> Result<f64> {
    let n = track.n_frames();
    if n < 4 {
        return Ok(0.0);
    }
    Ok(estimate_period(track, 0, n, &params.count.frame_period)?
        .map(|e| e.strength.max(0.0))
        .unwrap_or(0.0))
}

/// A person's own thumbnails and where they lie in the picture.
#[derive(Debug, Clone)]
pub(crate) struct OwnBox {
    /// Grey thumbnails of the person's own box.
    pub(crate) thumbnails: Thumbnails,
    /// The box `[x0, y0, x1, y1]` as fractions of the picture's width and
    /// height (`crate::PoseParams::own_box_region` over the frame size).
    pub(crate) place: [f64; 4],
}

/// The frame signal: the usual thumbnails (`own`, the person's own box, or
/// else `whole`, the whole-frame thumbnails, square) or the thumbnails of
/// the region of `whole` that moves on its own, whichever is the more
/// periodic (the usual ones on ties) — see the module docs. With a person's
/// own box, only regions inside it are considered: a person's repetitions
/// are read where that person is, not from someone or something beside
/// them.
///
/// The thumbnails are held as 4-byte floats; only the usual signal and the
/// regions are made tracks (8 bytes a cell), one at a time.
pub(crate) fn choose_frame_signal(
    whole: Thumbnails,
    own: Option<OwnBox>,
    params: &Params,
) -> Result<(Track, FrameChoice)> {
    let size = whole.side();
    let place = own.as_ref().map(|o| o.place);
    let usual = match own {
        Some(o) => o.thumbnails.track()?,
        None => whole.track()?,
    };
    let base_periodicity = periodicity(&usual, params)?;
    let mut choice = FrameChoice {
        region: None,
        base_periodicity,
        regions: Vec::new(),
    };
    if whole.n_frames() < 4 {
        return Ok((usual, choice));
    }
    let energy = MotionEnergy::of_thumbnails(&whole)?.energy();
    let sides: Vec<usize> = REGION_SIDES
        .iter()
        .map(|f| ((f * size as f64).round() as usize).clamp(1, size))
        .collect();
    // One region's cells at a time (at most a quarter of the picture's: 2 KB
    // a frame for 32-cell thumbnails); the chosen one is copied again.
    let mut best: Option<(CellRegion, f64)> = None;
    let inside = |r: &CellRegion| {
        place.is_none_or(|b| {
            let s = size as f64;
            r.c0 as f64 >= b[0] * s - 1e-9
                && r.c1 as f64 <= b[2] * s + 1e-9
                && r.r0 as f64 >= b[1] * s - 1e-9
                && r.r1 as f64 <= b[3] * s + 1e-9
        })
    };
    for (reg, ratio) in moving_regions(&energy, size, &sides, inside) {
        let p = periodicity(&region_track(&whole, reg)?, params)?;
        choice.regions.push((reg, ratio, p));
        if p > best.map_or(base_periodicity, |b| b.1) {
            best = Some((reg, p));
        }
    }
    Ok(match best {
        Some((reg, _)) => {
            choice.region = Some(reg);
            drop(usual);
            (region_track(&whole, reg)?, choice)
        }
        None => (usual, choice),
    })
}

/// What the frame signal of a video is read from once its people are
/// known ([`frame_signal`]): the video (for the boxes' own pass) and the
/// whole frame's thumbnails gathered while decoding.
pub(crate) struct PendingSignal {
    pub(crate) path: std::path::PathBuf,
    pub(crate) whole: Option<Thumbnails>,
}

/// The frame signal and the other people's thumbnails ([`frame_signal`]).
pub(crate) struct FrameSignal {
    pub(crate) thumbnails: Option<Track>,
    pub(crate) frame_choice: Option<FrameChoice>,
    pub(crate) others: Vec<(PersonId, Option<Thumbnails>)>,
}

impl FrameSignal {
    /// Into the keypoints they belong to.
    pub(crate) fn apply(self, kp: &mut Keypoints) {
        kp.thumbnails = self.thumbnails;
        kp.frame_choice = self.frame_choice;
        kp.others = self.others;
    }
}

/// Step 1b for a video: grey thumbnails of each person's own box (a second
/// decoding pass), then the frame signal — the main person's box's (or the
/// whole frame's) thumbnails, or those of the region that moves on its own,
/// the more periodic. It reads only the keypoints' people and track, so it
/// may run beside anything else that reads them (the overlay video).
pub(crate) fn frame_signal(
    kp: &Keypoints,
    pending: PendingSignal,
    params: &Params,
    timings: &mut Timings<'_>,
    cancel: &CancelToken,
) -> Result<FrameSignal> {
    let n = kp.track.n_frames();
    let rest: Vec<PersonId> = kp.others.iter().map(|(id, _)| *id).collect();
    let (own, others) = match &kp.people {
        Some(people) if kp.person.is_some() || !rest.is_empty() => {
            let t1 = Instant::now();
            let mut boxes =
                box_thumbnails(&pending.path, people, kp.person, &rest, n, params, cancel)?;
            timings.push(Stage::Boxes, t1.elapsed(), n);
            let own = kp.person.and_then(|id| boxes.remove(&id));
            let others = rest
                .iter()
                .map(|id| (*id, boxes.remove(id).map(|o| o.thumbnails)))
                .collect();
            (own, others)
        }
        _ => (None, rest.iter().map(|id| (*id, None)).collect()),
    };
    // The frame signal: the own box's (or the whole frame's) thumbnails, or
    // those of the region that moves on its own, the more periodic.
    let (thumbnails, frame_choice) = match pending.whole {
        Some(whole) => {
            let t1 = Instant::now();
            let (signal, choice) = choose_frame_signal(whole, own, params)?;
            timings.push(Stage::Motion, t1.elapsed(), n);
            (Some(signal), Some(choice))
        }
        None => (own.map(|o| o.thumbnails.track()).transpose()?, None),
    };
    Ok(FrameSignal {
        thumbnails,
        frame_choice,
        others,
    })
}

/// Grey thumbnails of each person's own (mean) box, from a second decoding
/// pass: the top-level person's (`top`) over the whole video, as the video's
/// frame signal; every other person's (`rest`) over their own frames only,
/// from their first to their last (their counts are theirs, and a long video
/// with many people holds each person's thumbnails once, not once per
/// frame of the video), all of them at the side their frames together allow.
/// None for a person whose box lies mostly outside the picture
/// ([`PoseParams::own_box_region`]).
fn box_thumbnails(
    path: &Path,
    people: &People,
    top: Option<PersonId>,
    rest: &[PersonId],
    n: usize,
    params: &Params,
    cancel: &CancelToken,
) -> Result<std::collections::HashMap<PersonId, OwnBox>> {
    let size = params.pose.thumbnail_size;
    let reader = VideoReader::open(path)?;
    let (fps, width, height) = (reader.info().fps, reader.info().width, reader.info().height);
    // Each person's box and the frames `a..b` read for them.
    let regions: Vec<(PersonId, [f64; 4], std::ops::Range<usize>)> = top
        .iter()
        .chain(rest)
        .filter_map(|id| {
            let p = people.get(*id)?;
            let r = PoseParams::own_box_region(p.mean_box()?, width, height)?;
            let frames = if Some(*id) == top {
                0..n
            } else {
                p.first_frame.min(n)..(p.last_frame() + 1).min(n)
            };
            Some((*id, r, frames))
        })
        .collect();
    // The top-level person's thumbnails at the side the video's length
    // allows (`mp_pose::MAX_SIGNAL_VALUES`), the other people's at the side
    // their frames together allow: an hour with a few people in view at a
    // time holds about an hour of them.
    let others_frames: usize = regions
        .iter()
        .filter(|(id, _, _)| Some(*id) != top)
        .map(|(_, _, f)| f.len())
        .sum();
    let sides: Vec<usize> = regions
        .iter()
        .map(|(id, _, f)| {
            signal_side(
                size,
                if Some(*id) == top {
                    f.len()
                } else {
                    others_frames
                },
            )
        })
        .collect();
    // Each person's thumbnails written straight into their place (frames ×
    // side × side), one frame at a time: no second copy.
    let mut thumbs: Vec<(ndarray::Array3<f32>, usize)> = regions
        .iter()
        .zip(&sides)
        .map(|((_, _, f), &side)| (ndarray::Array3::zeros((f.len(), side, side)), 0))
        .collect();
    let last = regions.iter().map(|(_, _, f)| f.end).max().unwrap_or(0);
    for frame in reader.take(last) {
        check(cancel)?;
        let frame = frame?;
        for (k, (_, r, frames)) in regions.iter().enumerate() {
            if frames.contains(&frame.index) {
                let cells = grey_thumbnail_region(&frame, sides[k], *r)?;
                let (values, filled) = &mut thumbs[k];
                let mut row = values.index_axis_mut(ndarray::Axis(0), *filled);
                row.iter_mut().zip(&cells).for_each(|(d, s)| *d = *s);
                *filled += 1;
            }
        }
    }
    let mut out = std::collections::HashMap::new();
    let (w, h) = (width as f64, height as f64);
    for ((id, r, frames), (values, filled)) in regions.into_iter().zip(thumbs) {
        if filled == frames.len() && filled > 0 {
            let place = [
                (r[0] / w).clamp(0.0, 1.0),
                (r[1] / h).clamp(0.0, 1.0),
                (r[2] / w).clamp(0.0, 1.0),
                (r[3] / h).clamp(0.0, 1.0),
            ];
            let thumbnails = Thumbnails::new(values, fps)?;
            out.insert(id, OwnBox { thumbnails, place });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::s;

    /// 32 × 32 thumbnails of a picture whose every cell flickers at random
    /// (clutter, ±10 grey levels), with, when `rep`, a 6 × 6 patch at rows
    /// 3..9, columns 20..26 that brightens and darkens every 20 frames (more
    /// motion per frame than the flicker, much less over the picture).
    fn scene(n: usize, rep: bool) -> Thumbnails {
        let mut state = 12345u64;
        let mut rnd = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as f64 / (1u64 << 31) as f64
        };
        let thumbs: Vec<f32> = (0..n)
            .flat_map(|t| {
                (0..1024)
                    .map(|k| {
                        let (r, c) = (k / 32, k % 32);
                        let patch = rep && (3..9).contains(&r) && (20..26).contains(&c);
                        let v = if patch {
                            100.0 + 60.0 * (std::f64::consts::TAU * t as f64 / 20.0).sin()
                        } else {
                            100.0 + 20.0 * rnd()
                        };
                        v as f32
                    })
                    .collect::<Vec<f32>>()
            })
            .collect();
        Thumbnails::from_flat(thumbs, 32, 30.0).unwrap()
    }

    #[test]
    fn a_small_repetition_in_clutter_is_chosen() {
        let whole = scene(200, true);
        let params = Params::default();
        let (tr, choice) = choose_frame_signal(whole, None, &params).unwrap();
        let reg = choice.region.expect("a region");
        assert!(
            reg.r0 <= 3 && reg.r1 >= 9 && reg.c0 <= 20 && reg.c1 >= 26,
            "{reg:?}"
        );
        assert_eq!(tr.n_joints(), reg.r1 - reg.r0);
        let chosen = choice
            .regions
            .iter()
            .find(|r| r.0 == reg)
            .map(|r| r.2)
            .unwrap();
        assert!(chosen > choice.base_periodicity, "{choice:?}");
        assert!(chosen > 0.5, "{choice:?}");
        let est = estimate_period(&tr, 0, 200, &params.count.frame_period)
            .unwrap()
            .unwrap();
        assert!((est.period_frames as i64 - 20).abs() <= 1, "{est:?}");
    }

    #[test]
    fn a_person_s_signal_is_not_read_from_a_repetition_beside_them() {
        // The repeating patch is at the top right (columns 20..26); a person
        // on the left half of the picture keeps their own thumbnails (here
        // the cells of the top left quarter, as a 16 × 16 grid).
        let whole = scene(200, true);
        let left =
            Thumbnails::new(whole.values().slice(s![.., 0..16, 0..16]).to_owned(), 30.0).unwrap();
        let own = |place| OwnBox {
            thumbnails: left.clone(),
            place,
        };
        let params = Params::default();
        let (tr, choice) =
            choose_frame_signal(whole.clone(), Some(own([0.0, 0.0, 0.5, 1.0])), &params).unwrap();
        assert_eq!(choice.region, None, "{choice:?}");
        assert_eq!(tr.n_joints(), 16);
        assert_eq!(tr.dims(), 16);
        assert_eq!(tr, left.track().unwrap());
        for (reg, _, _) in &choice.regions {
            assert!(reg.c1 <= 16, "{reg:?} reaches out of the left half");
        }
        // A person whose box holds the patch has it read.
        let (_, choice) =
            choose_frame_signal(whole, Some(own([0.5, 0.0, 1.0, 0.5])), &params).unwrap();
        let reg = choice.region.expect("the patch's region");
        assert!(reg.c0 <= 20 && reg.c1 >= 26, "{reg:?}");
    }

    #[test]
    fn clutter_alone_keeps_the_usual_signal_or_a_weak_one() {
        let whole = scene(200, false);
        let (_, choice) = choose_frame_signal(whole.clone(), None, &Params::default()).unwrap();
        // Random flicker has no period anywhere.
        for (_, _, p) in &choice.regions {
            assert!(*p < 0.3, "{choice:?}");
        }
        // Too short to say anything: the usual signal, untouched.
        let short =
            Thumbnails::new(whole.values().slice(s![0..3, .., ..]).to_owned(), 30.0).unwrap();
        let (tr, c) = choose_frame_signal(short, None, &Params::default()).unwrap();
        assert_eq!(c.region, None);
        assert_eq!(tr.n_frames(), 3);
    }
}
