//! A long video's people from pieces of it tracked side by side.
//!
//! One tracker follows a video frame after frame: each frame's crops come
//! from the poses of the frame before, so a video's frames cannot be shared
//! among threads. Pieces of the video can: [`piece_ranges`] cuts the frames
//! into consecutive pieces, each after the first starting
//! [`PIECE_OVERLAP_S`] before the previous one ends; each piece is tracked on
//! its own (its own decoder and model), and [`join_pieces`] joins them where
//! they overlap. A piece's first frames are its tracker's warm-up (the
//! detector finds everyone anew); over the later half of the overlap, every
//! person of the earlier piece is matched to the person of the later piece
//! whose joints lie closest to theirs, relative to the person's size, and
//! continues as them from where the earlier piece ends. Someone the later
//! piece finds and the earlier did not is a new person from there on.
//!
//! On two cores, two pieces of a minute each at one model thread apiece took
//! 36.1 s where the same two minutes one after the other at two threads took
//! 48.9 s: a model's second thread gains far less than a second piece.

use mp_geom::{People, Person, Track};
use ndarray::{s, Array2, Array3};

use super::extract::PeopleExtraction;
use crate::error::{PoseError, Result};

/// Each piece after the first starts this long before the previous one
/// ends: the later piece's tracker finds everyone again within it.
pub const PIECE_OVERLAP_S: f64 = 2.0;

/// The shortest piece worth its own tracker: each boundary costs one
/// overlap of detection and warm-up.
pub const MIN_PIECE_S: f64 = 60.0;

/// People whose joints lie apart, on average, by more than this share of
/// the person's box diagonal over the overlap are not the same person.
pub const PIECE_MATCH_DISTANCE: f64 = 0.15;

/// The frames `[start, start + len)` of each of `pieces` pieces of a video
/// of `n_frames`, each after the first starting `overlap` frames before the
/// previous one ends and at a multiple of `align` (the pose model's stride,
/// so that the frames it runs on are the video's own). One piece where the
/// video is too short for `pieces`.
pub fn piece_ranges(
    n_frames: usize,
    pieces: usize,
    overlap: usize,
    align: usize,
) -> Vec<(usize, usize)> {
    let align = align.max(1);
    let k = pieces.max(1);
    if k == 1 || n_frames < k * (2 * overlap + align) {
        return vec![(0, n_frames)];
    }
    let mut out = Vec::with_capacity(k);
    let mut start = 0usize;
    for i in 1..=k {
        // This piece's frames end where the next piece's own frames begin;
        // the next starts `overlap` (aligned) before that.
        let end = n_frames * i / k;
        out.push((start, end - start));
        start = (end.saturating_sub(overlap) / align) * align;
    }
    out
}

/// Joins the people of consecutive pieces of one video (each piece's start
/// frame and what tracking it found, in order; see the module docs). The
/// frames up to the end of a piece are that piece's; the next piece's
/// frames take over after it. People are numbered 1, 2, … by first
/// appearance.
pub fn join_pieces(pieces: Vec<(usize, PeopleExtraction)>) -> Result<PeopleExtraction> {
    let mut it = pieces.into_iter();
    let Some((first_start, mut acc)) = it.next() else {
        return Err(PoseError::param("pieces", "no piece to join"));
    };
    if first_start != 0 {
        return Err(PoseError::param(
            "pieces",
            format!("the first piece starts at frame {first_start}, not 0"),
        ));
    }
    for (start, next) in it {
        acc = join_two(acc, start, next)?;
    }
    Ok(acc)
}

/// `acc` (frames `0..acc_n`) and `next` (frames `start..start + next_n`).
fn join_two(
    acc: PeopleExtraction,
    start: usize,
    next: PeopleExtraction,
) -> Result<PeopleExtraction> {
    let cut = acc.people_per_frame.len();
    let next_n = next.people_per_frame.len();
    if start > cut || start + next_n < cut {
        return Err(PoseError::param(
            "pieces",
            format!(
                "a piece at frames {start}..{} does not meet the frames 0..{cut} before it",
                start + next_n
            ),
        ));
    }
    let n = start + next_n;
    let fps = acc.people.fps();
    // Matched over the later half of the overlap, where the later piece's
    // tracker has found everyone.
    let window = (start + (cut - start) / 2)..cut;
    let earlier = acc.people.into_people();
    let later = next.people.into_people();
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (a, p) in earlier.iter().enumerate() {
        for (b, q) in later.iter().enumerate() {
            if let Some(d) = distance(p, q, start, window.clone()) {
                if d < PIECE_MATCH_DISTANCE {
                    pairs.push((d, a, b));
                }
            }
        }
    }
    pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut to_later: Vec<Option<usize>> = vec![None; earlier.len()];
    let mut taken = vec![false; later.len()];
    for (_, a, b) in pairs {
        if to_later[a].is_none() && !taken[b] {
            to_later[a] = Some(b);
            taken[b] = true;
        }
    }
    let mut people = Vec::with_capacity(earlier.len() + later.len());
    for (p, m) in earlier.iter().zip(&to_later) {
        people.push(match m {
            Some(b) => continued(p, &later[*b], start, cut)?,
            None => p.clone(),
        });
    }
    for (q, _) in later.iter().zip(&taken).filter(|(_, t)| !**t) {
        if let Some(p) = from_frame(q, start, cut)? {
            people.push(p);
        }
    }
    // Numbered by first appearance.
    people.sort_by_key(|p| (p.first_frame, p.id));
    for (k, p) in people.iter_mut().enumerate() {
        p.id = k as u32 + 1;
    }
    let take = |a: Vec<usize>, b: &[usize]| -> Vec<usize> {
        let mut v = a;
        v.extend_from_slice(&b[cut - start..]);
        v
    };
    let mut posed = acc.posed;
    posed.extend_from_slice(&next.posed[cut - start..]);
    let mut estimate_ms = acc.estimate_ms;
    estimate_ms.extend_from_slice(&next.estimate_ms);
    let refused_first = match (acc.refused.1, next.refused.1) {
        (Some(a), _) => Some(a),
        (None, b) => b.map(|f| f + start),
    };
    Ok(PeopleExtraction {
        people: People::new(n, fps, people)?,
        people_per_frame: take(acc.people_per_frame, &next.people_per_frame),
        posed,
        detector_runs: acc.detector_runs + next.detector_runs,
        estimate_ms,
        // The pieces run side by side: the longest is the wall time.
        total_ms: acc.total_ms.max(next.total_ms),
        width: acc.width,
        height: acc.height,
        max_people: acc.max_people,
        most_seen: acc.most_seen.max(next.most_seen),
        refused: (acc.refused.0 + next.refused.0, refused_first),
    })
}

/// Mean over the frames of `window` (video frames) where both are found of
/// the mean distance between their joints seen by both, over `p`'s box
/// diagonal on that frame; `None` with fewer than three such frames. `q`'s
/// frames start at video frame `offset` plus its own first frame.
fn distance(p: &Person, q: &Person, offset: usize, window: std::ops::Range<usize>) -> Option<f64> {
    let (pp, pc) = (p.track.positions(), p.track.confidence());
    let (qp, qc) = (q.track.positions(), q.track.confidence());
    let mut sum = 0.0;
    let mut frames = 0usize;
    for f in window {
        let (Some(tp), Some(tq)) = (
            f.checked_sub(p.first_frame)
                .filter(|&t| t < p.track.n_frames()),
            f.checked_sub(offset + q.first_frame)
                .filter(|&t| t < q.track.n_frames()),
        ) else {
            continue;
        };
        let Some([x0, y0, x1, y1]) = p.box_at(f) else {
            continue;
        };
        let diag = (x1 - x0).hypot(y1 - y0);
        if diag.is_nan() || diag <= 0.0 {
            continue;
        }
        let (mut d, mut joints) = (0.0, 0usize);
        for j in 0..p.track.n_joints().min(q.track.n_joints()) {
            if pc[[tp, j]] > 0.0 && qc[[tq, j]] > 0.0 {
                d += (pp[[tp, j, 0]] - qp[[tq, j, 0]]).hypot(pp[[tp, j, 1]] - qp[[tq, j, 1]]);
                joints += 1;
            }
        }
        if joints > 0 {
            sum += d / joints as f64 / diag;
            frames += 1;
        }
    }
    (frames >= 3).then(|| sum / frames as f64)
}

/// `p` up to video frame `cut`, then `q` (of the piece starting at video
/// frame `start`) from `cut` on.
fn continued(p: &Person, q: &Person, start: usize, cut: usize) -> Result<Person> {
    let q_first = start + q.first_frame;
    let q_end = q_first + q.track.n_frames();
    let p_end = (p.first_frame + p.track.n_frames()).min(cut);
    let end = q_end.max(p_end);
    let (j, d) = (p.track.n_joints(), p.track.dims());
    let mut pos = Array3::<f64>::zeros((end - p.first_frame, j, d));
    let mut conf = Array2::<f64>::zeros((end - p.first_frame, j));
    let own = p_end - p.first_frame;
    pos.slice_mut(s![..own, .., ..])
        .assign(&p.track.positions().slice(s![..own, .., ..]));
    conf.slice_mut(s![..own, ..])
        .assign(&p.track.confidence().slice(s![..own, ..]));
    let from = cut.max(q_first);
    if from < q_end {
        let (a, b) = (from - q_first, q_end - q_first);
        let (c, e) = (from - p.first_frame, q_end - p.first_frame);
        pos.slice_mut(s![c..e, .., ..])
            .assign(&q.track.positions().slice(s![a..b, .., ..]));
        conf.slice_mut(s![c..e, ..])
            .assign(&q.track.confidence().slice(s![a..b, ..]));
    }
    Ok(Person {
        id: p.id,
        first_frame: p.first_frame,
        track: rebuilt(p.track.fps(), pos, conf, &p.track)?,
    })
}

/// `q` (of the piece starting at video frame `start`) from video frame
/// `cut` on, starting at its first frame found there; `None` when it is not
/// found from `cut` on.
fn from_frame(q: &Person, start: usize, cut: usize) -> Result<Option<Person>> {
    let q_first = start + q.first_frame;
    let conf = q.track.confidence();
    let from = cut.saturating_sub(q_first);
    let Some(t0) = (from..q.track.n_frames()).find(|&t| conf.row(t).iter().any(|&c| c > 0.0))
    else {
        return Ok(None);
    };
    let pos = q.track.positions().slice(s![t0.., .., ..]).to_owned();
    let conf = conf.slice(s![t0.., ..]).to_owned();
    Ok(Some(Person {
        id: q.id,
        first_frame: q_first + t0,
        track: rebuilt(q.track.fps(), pos, conf, &q.track)?,
    }))
}

/// A track of `pos` and `conf` in `like`'s units and skeleton.
fn rebuilt(fps: f64, pos: Array3<f64>, conf: Array2<f64>, like: &Track) -> Result<Track> {
    Ok(Track::new(
        pos,
        Some(conf),
        fps,
        like.units(),
        like.skeleton().clone(),
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_geom::{Skeleton, Units};

    #[test]
    fn pieces_cover_the_frames_with_their_overlap() {
        assert_eq!(piece_ranges(1000, 1, 60, 1), vec![(0, 1000)]);
        let r = piece_ranges(1000, 2, 60, 1);
        assert_eq!(r, vec![(0, 500), (440, 560)]);
        let r = piece_ranges(1001, 3, 60, 2);
        assert_eq!(r[0], (0, 333));
        for w in r.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert!(
                b.0 % 2 == 0 && b.0 < a.0 + a.1 && a.0 + a.1 - b.0 >= 60,
                "{r:?}"
            );
        }
        assert_eq!(r.last().map(|l| l.0 + l.1), Some(1001));
        // Too short for its pieces: one.
        assert_eq!(piece_ranges(200, 2, 60, 1), vec![(0, 200)]);
    }

    /// A person walking right at 2 px a frame over `frames` video frames
    /// from `first`, seen by a piece starting at `start`, with `dx` added.
    fn walker(id: u32, first: usize, frames: usize, start: usize, dx: f64) -> Person {
        let sk = Skeleton::coco17();
        let j = sk.len();
        let mut pos = Array3::<f64>::zeros((frames, j, 2));
        for t in 0..frames {
            let x = 2.0 * (first + t) as f64 + dx;
            for k in 0..j {
                pos[[t, k, 0]] = x + 3.0 * k as f64;
                pos[[t, k, 1]] = 100.0 + 10.0 * k as f64;
            }
        }
        let conf = Array2::<f64>::ones((frames, j));
        Person {
            id,
            first_frame: first - start,
            track: Track::new(pos, Some(conf), 30.0, Units::Pixels, sk).unwrap(),
        }
    }

    fn extraction(n: usize, people: Vec<Person>) -> PeopleExtraction {
        let mut per = vec![0; n];
        for p in &people {
            for t in 0..p.track.n_frames() {
                per[p.first_frame + t] += 1;
            }
        }
        PeopleExtraction {
            people: People::new(n, 30.0, people).unwrap(),
            people_per_frame: per,
            posed: vec![true; n],
            detector_runs: 1,
            estimate_ms: vec![1.0; n],
            total_ms: n as f64,
            width: 640,
            height: 360,
            max_people: 8,
            most_seen: 2,
            refused: (0, None),
        }
    }

    #[test]
    fn people_continue_across_pieces_and_newcomers_are_numbered_by_first_frame() {
        // Video of 200 frames, pieces 0..120 and 100..200.
        let a = extraction(
            120,
            vec![walker(1, 0, 120, 0, 0.0), walker(2, 30, 90, 0, 300.0)],
        );
        // The later piece: the same two (ids swapped, a pixel off), and
        // someone new at frame 150; person 1's twin ends at 180.
        let b = extraction(
            100,
            vec![
                walker(1, 100, 100, 100, 301.0),
                walker(2, 100, 80, 100, 1.0),
                walker(3, 150, 50, 100, 900.0),
            ],
        );
        let j = join_pieces(vec![(0, a), (100, b)]).unwrap();
        assert_eq!(j.people.n_frames(), 200);
        assert_eq!(j.people_per_frame.len(), 200);
        assert_eq!(j.posed.len(), 200);
        let ids: Vec<(u32, usize, usize)> = j
            .people
            .people()
            .iter()
            .map(|p| (p.id, p.first_frame, p.track.n_frames()))
            .collect();
        assert_eq!(ids, vec![(1, 0, 180), (2, 30, 170), (3, 150, 50)]);
        // Person 1 is the earlier piece's until frame 120, then the later one's.
        let p1 = &j.people.people()[0];
        assert_eq!(p1.track.positions()[[119, 0, 0]], 238.0);
        assert_eq!(p1.track.positions()[[120, 0, 0]], 241.0);
        // Per frame: the earlier piece's counts before 120, the later's after.
        assert_eq!(j.people_per_frame[110], 2);
        assert_eq!(j.people_per_frame[160], 3);
        assert_eq!(j.people_per_frame[190], 2);
        assert_eq!(j.detector_runs, 2);
    }

    #[test]
    fn pieces_that_do_not_meet_are_refused() {
        let a = extraction(100, vec![walker(1, 0, 100, 0, 0.0)]);
        let b = extraction(50, vec![walker(1, 120, 50, 120, 0.0)]);
        let e = join_pieces(vec![(0, a), (120, b)]).unwrap_err().to_string();
        assert!(e.contains("does not meet"), "{e}");
        assert!(join_pieces(Vec::new()).is_err());
    }
}
