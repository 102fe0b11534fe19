//! The in-between poses `mp interpolate` warps to, on real motion: every
//! 8th frame of real keypoint tracks kept, the guide built as the product
//! builds it (`Guide::from_track`, default parameters), its target poses at
//! the dropped frames against the true keypoints, and the same with the
//! kept keypoints interpolated linearly. Needs the shared data (skipped with
//! a message when it is absent).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_concrete::InBetween;
use mp_geom::Track;
use mp_geom::{AistPlusPlus, PennAction};
use mp_video::Guide;
use mp_video::InterpParams;

/// Sums of distances (default rule, linear) and entries over the dropped frames.
fn score(track: &Track, k: usize, frame_px: f64) -> (f64, f64, usize) {
    let kept = track.subsample(k).unwrap();
    let n_kept = kept.n_frames();
    let params = mp_pipeline::Params::default();
    let mut guide = Guide::from_track(kept, Some(frame_px), &params, &InterpParams::default())
        .expect("guide of the kept keypoints");
    let (mut s_def, mut s_lin, mut n) = (0.0, 0.0, 0);
    for f in (0..(n_kept - 1) * k).filter(|f| f % k != 0) {
        let (i, w) = (f / k, (f % k) as f64 / k as f64);
        guide.inbetween = InBetween::default();
        let def = guide.target_pose(i, w).unwrap();
        guide.inbetween = InBetween::Linear;
        let lin = guide.target_pose(i, w).unwrap();
        for j in 0..track.n_joints() {
            if !track.is_valid(f, j, 0.3) {
                continue;
            }
            let (Some(Some(a)), Some(Some(b))) = (def.get(j), lin.get(j)) else {
                continue;
            };
            let q = track.point(f, j);
            s_def += (a[0] - q[0]).hypot(a[1] - q[1]);
            s_lin += (b[0] - q[0]).hypot(b[1] - q[1]);
            n += 1;
        }
    }
    (s_def, s_lin, n)
}

#[test]
fn on_tennis_serves_at_8x_the_in_between_poses_beat_the_chord() {
    let path = mp_geom::data_or_return!(PennAction::TRAIN_FILE);
    let pa = PennAction::open(path).unwrap();
    let (mut d, mut l, mut n) = (0.0, 0.0, 0);
    for &i in pa.clips_of_action("tennis_serve").iter().take(12) {
        let info = pa.clip_info(i).unwrap();
        let frame_px = info.height_px.max(info.width_px) as f64;
        let (a, b, m) = score(&pa.clip(i).unwrap(), 8, frame_px);
        d += a;
        l += b;
        n += m;
    }
    let (d, l) = (d / n as f64, l / n as f64);
    eprintln!("tennis serves ×8: default {d:.3} px, linear {l:.3} px over {n} keypoints");
    assert!(n > 3000, "{n}");
    assert!(d < 0.95 * l, "default {d} px vs linear {l} px");
}

#[test]
fn on_a_dance_at_4x_the_in_between_poses_beat_the_chord() {
    let path = mp_geom::data_or_return!("aistpp_keypoints2d/gBR_sBM_cAll_d04_mBR0_ch04.npz");
    let a = AistPlusPlus::open(path).unwrap();
    // Camera 1 at 30 fps, the rate of the videos.
    let track = a.views[0].subsample(2).unwrap();
    let (d, l, n) = score(&track, 4, 1920.0);
    let (d, l) = (d / n as f64, l / n as f64);
    eprintln!("AIST++ ch04 c01 ×4: default {d:.3} px, linear {l:.3} px over {n} keypoints");
    assert!(n > 3000, "{n}");
    assert!(d < 0.9 * l, "default {d} px vs linear {l} px");
}
