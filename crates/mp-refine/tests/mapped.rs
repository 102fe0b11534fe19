//! Refinement of BlazePose-33 world landmarks (MediaPipe's own, on the
//! shared golf swing) through the 20 MSR joints: the output keeps the
//! input's skeleton and frames, is finite, and stays close to the input.
//! Skipped, with a message, where the shared data are absent.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use mp_geom::nanmean;
use mp_geom::MediaPipeReference;
use mp_refine::refine_any;
use mp_refine::{NetRefineParams, NetRefiner};

#[test]
fn blazepose_world_landmarks_are_refined_on_their_own_skeleton() {
    let path = mp_geom::data_or_return!("reference_keypoints/golf_swing.npz");
    let world = MediaPipeReference::open(&path)
        .unwrap()
        .world
        .slice_frames(0, 90)
        .unwrap();
    let (nets, concepts) = common::shipped();
    let params = NetRefineParams::default();
    let refiner = NetRefiner::new(&nets, &concepts, &params).unwrap();
    let r = refine_any(&refiner, &world, None).unwrap();
    assert_eq!(r.track.skeleton().name, "blazepose33");
    assert_eq!(r.track.n_frames(), world.n_frames());
    assert_eq!(r.msr.track.skeleton().name, "msr20");
    assert!(r.track.positions().iter().all(|v| v.is_finite()));
    // the refinement corrects flaws; it does not move a clean capture far
    let change: Vec<f64> = (0..world.n_frames())
        .flat_map(|f| {
            let (a, b) = (&r.track, &world);
            (0..33).map(move |j| {
                let d = &a.point(f, j) - &b.point(f, j);
                d.dot(&d).sqrt()
            })
        })
        .collect();
    let mean = nanmean(&change);
    println!(
        "golf swing, 90 frames: mean landmark change {:.1} mm",
        mean * 1e3
    );
    assert!(mean < 0.05, "mean change {mean} m");
}
