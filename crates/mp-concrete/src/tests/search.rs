//! The branch-and-bound segmentation of `Program::synthesize` finds the
//! optimum of the exhaustive DP over the full cost table
//! (`Segmentation::exhaustive`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::dp::Segmentation;
use crate::synth::segment_costs;
use crate::synthetic::synthetic_track;
use crate::{Lambda, Scale, SynthParams};
use mp_geom::ErrorNorm;
use mp_geom::{PrimitiveKind, Skeleton, Track, Units};
use ndarray::{Array2, Array3};
use proptest::prelude::*;

/// The fast optimum has the exhaustive optimum's cost (1e-9 relative), and its
/// segmentation costs exactly that under the reference table (ties may pick
/// another segmentation of the same cost).
fn same_optimum(track: &Track, params: &SynthParams) -> (Segmentation, Segmentation) {
    let fast = Segmentation::search(track, params).unwrap();
    let reference = Segmentation::exhaustive(track, params).unwrap();
    let tol = 1e-9 * (1.0 + reference.cost.abs());
    assert!(
        (fast.cost - reference.cost).abs() <= tol,
        "fast {} reference {}",
        fast.cost,
        reference.cost
    );
    if fast.boundaries != reference.boundaries {
        let table = segment_costs(track, params).unwrap();
        let c: f64 = fast
            .boundaries
            .windows(2)
            .map(|w| table.get(w[0], w[1]))
            .sum();
        assert!(
            (c - reference.cost).abs() <= tol,
            "tie {c} vs {}",
            reference.cost
        );
    }
    (fast, reference)
}

fn track_from(t: usize, j: usize, d: usize, coords: &[f64], conf: Option<&[f64]>) -> Track {
    let mut pos = Array3::zeros((t, j, d));
    for ti in 0..t {
        for ji in 0..j {
            for k in 0..d {
                pos[[ti, ji, k]] = coords[((ti * j + ji) * d + k) % coords.len()];
            }
        }
    }
    let conf = conf.map(|c| Array2::from_shape_fn((t, j), |(ti, ji)| c[(ti * j + ji) % c.len()]));
    Track::new(pos, conf, 30.0, Units::Pixels, Skeleton::generic(j)).unwrap()
}

fn px_params(lambda: f64, w: usize) -> SynthParams {
    SynthParams {
        lambda: Lambda::fixed(lambda),
        max_segment_frames: w,
        scale: Scale::UnitScale { unit_scale: 1.0 },
        ..SynthParams::paper()
    }
}

/// Smooth random motion: random walk of velocity plus noise, per joint.
fn smooth_coords(t: usize, j: usize, seed: &[f64], noise: f64) -> Vec<f64> {
    let mut out = vec![0.0; t * j * 2];
    for ji in 0..j {
        let mut p = [200.0 + 10.0 * ji as f64, 250.0];
        let mut v = [0.0, 0.0];
        for ti in 0..t {
            let s = |o: usize| seed[(ti * 7 + ji * 3 + o) % seed.len()];
            v[0] = 0.9 * v[0] + 2.0 * (s(0) - 0.5);
            v[1] = 0.9 * v[1] + 2.0 * (s(1) - 0.5);
            p[0] += v[0];
            p[1] += v[1];
            out[(ti * j + ji) * 2] = p[0] + noise * (s(2) - 0.5);
            out[(ti * j + ji) * 2 + 1] = p[1] + noise * (s(3) - 0.5);
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Uniformly random points (rough tracks): many short segments.
    #[test]
    fn random_points(
        t in 2usize..=40,
        w in 1usize..=30,
        j in 1usize..=3,
        lambda in 0.0..3000.0f64,
        coords in prop::collection::vec(0.0..200.0f64, 40),
    ) {
        let track = track_from(t, j, 2, &coords, None);
        same_optimum(&track, &px_params(lambda, w));
    }

    /// Smooth random motion with noise and missing frames, all norms and kind sets.
    #[test]
    fn smooth_tracks(
        t in 5usize..=120,
        w in 2usize..=60,
        j in 1usize..=4,
        lambda in 10.0..4000.0f64,
        noise in 0.0..4.0f64,
        seed in prop::collection::vec(0.0..1.0f64, 97),
        conf in prop::collection::vec(prop_oneof![4 => Just(1.0f64), 1 => Just(0.0f64)], 13),
        squared in any::<bool>(),
        kinds in 0usize..4,
    ) {
        let coords = smooth_coords(t, j, &seed, noise);
        let mut conf = conf;
        conf[0] = 1.0; // every joint observed somewhere
        conf[1] = 1.0;
        conf[2] = 1.0;
        conf[3] = 1.0;
        let track = track_from(t, j, 2, &coords, Some(&conf));
        let mut p = px_params(lambda, w);
        if squared {
            p.fit.norm = ErrorNorm::Squared;
            p.lambda = Lambda::fixed(lambda * 5.0);
        }
        p.fit.kinds = match kinds {
            0 => vec![PrimitiveKind::Stationary, PrimitiveKind::Line, PrimitiveKind::Circle],
            1 => vec![PrimitiveKind::Line, PrimitiveKind::Circle],
            2 => vec![PrimitiveKind::Stationary, PrimitiveKind::Line, PrimitiveKind::Circle, PrimitiveKind::Spline],
            _ => vec![PrimitiveKind::Stationary, PrimitiveKind::Circle],
        };
        same_optimum(&track, &p);
    }

    /// 3D tracks (exact per-joint fits, bounds only from the other joints).
    #[test]
    fn tracks_3d(
        t in 3usize..=30,
        w in 1usize..=20,
        lambda in 0.0..2000.0f64,
        coords in prop::collection::vec(0.0..100.0f64, 90),
    ) {
        let track = track_from(t, 2, 3, &coords, None);
        same_optimum(&track, &px_params(lambda, w));
    }
}

#[test]
fn synthetic_track_same_optimum() {
    let track = synthetic_track(600, 7).unwrap();
    for lambda in [100.0, 1600.0, 6400.0] {
        let (fast, _) = same_optimum(&track, &px_params(lambda, 60));
        assert!(fast.n_segments() > 3);
    }
    let auto = SynthParams {
        lambda: Lambda::adaptive(),
        ..SynthParams::paper()
    };
    same_optimum(&track, &auto);
}

/// The search's counts add up: every candidate is dropped on λ, by the
/// bounds, on the single-precision bounds, in the exact stage, or was the best so far for its end frame (at
/// least one per end frame); every segment's end frame saw the candidate
/// that won; and the counts are those of the same search run twice.
#[test]
fn search_stats_account_for_every_candidate() {
    let track = synthetic_track(600, 7).unwrap();
    let params = px_params(1600.0, 60);
    let (seg, st) = Segmentation::search_with_stats(&track, &params).unwrap();
    assert_eq!(seg, Segmentation::search(&track, &params).unwrap());
    let t = track.n_frames() as u64;
    // n − 1 … n − W for every end frame n (fewer at the start).
    let expected: u64 = (1..=t).map(|n| n.min(60)).sum();
    assert_eq!(st.candidates, expected);
    assert_eq!(
        st.candidates,
        st.pruned_lambda + st.pruned_bounds + st.survivors
    );
    let improved = st.survivors - st.dropped_coarse - st.dropped_exact;
    assert!(improved >= t, "{improved} improvements for {t} end frames");
    assert!(st.pruned_lambda > 0 && st.pruned_bounds > 0, "{st:?}");
    let j = track.n_joints() as u64;
    assert!(st.exact_joints >= improved * j && st.exact_joints <= st.survivors * j);
    assert!(st.exact_frames >= st.exact_joints && st.exact_frames <= st.exact_joints * 60);
    // Every survivor gets at least one single-precision joint pass before
    // any exact one pass (2D, Euclidean: every joint has them), and most are
    // dropped there.
    assert!(st.coarse_joints >= st.survivors && st.coarse_joints <= st.survivors * j);
    assert!(st.coarse_frames >= st.coarse_joints && st.coarse_frames <= st.coarse_joints * 60);
    assert!(st.dropped_coarse > st.dropped_exact, "{st:?}");
    assert!(st.circle_frames >= 3 * st.circle_fits && st.circle_frames <= 60 * st.circle_fits);
    assert!(st.joints_per_survivor() >= 1.0 && st.joints_per_survivor() <= j as f64);
    assert_eq!(
        Segmentation::search_with_stats(&track, &params).unwrap().1,
        st
    );
}

/// Real tracks: Penn Action clips of several actions (occluded joints, both
/// norms), the same optimum as the exhaustive DP.
#[test]
fn penn_action_same_optimum() {
    use crate::UnobservedJoints;
    use mp_geom::PennAction;
    let path = mp_geom::data_or_return!(PennAction::TRAIN_FILE);
    let pa = PennAction::open(&path).unwrap();
    let mut n = 0;
    for action in [
        "golf_swing",
        "jumping_jacks",
        "tennis_serve",
        "baseball_pitch",
    ] {
        for &i in pa.clips_of_action(action).iter().take(2) {
            let info = pa.clip_info(i).unwrap();
            let frame_px = info.height_px.max(info.width_px) as f64;
            let track = pa.clip(i).unwrap();
            for squared in [false, true] {
                let mut p = SynthParams {
                    scale: Scale::FrameSize { frame_px },
                    unobserved_joints: UnobservedJoints::Ignore,
                    ..SynthParams::paper()
                };
                if squared {
                    p.fit.norm = ErrorNorm::Squared;
                    p.lambda = Lambda::fixed(4000.0);
                }
                let (fast, _) = same_optimum(&track, &p);
                assert!(fast.n_segments() >= 2, "{action} clip {i}");
                n += 1;
            }
        }
    }
    assert_eq!(n, 16);
}
