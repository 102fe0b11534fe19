//! The data-set readers on the real shared files. Expected values were read
//! with numpy from the same files.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::io::datasets::{
    fps_from_timestamps_us, AistPlusPlus, CmuFeatures, MediaPipeReference, MsrAction3D, PennAction,
};
use crate::{GeomError, Units};

/// The shared data file `rel`, or the test records its skip and returns.
macro_rules! data {
    ($rel:expr) => {
        crate::data_or_return!($rel)
    };
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn penn_action_train_split() {
    data!(PennAction::TRAIN_FILE);
    let p = PennAction::open_default().expect("Penn Action npz in the shared data");
    assert_eq!(p.len(), 1258);
    assert_eq!(p.clips().iter().map(|c| c.n_frames).sum::<usize>(), 87543);
    assert_eq!(p.actions().len(), 15);
    let c0 = p.clip_info(0).unwrap();
    assert_eq!(
        (c0.clip_id.as_str(), c0.action.as_str(), c0.view.as_str()),
        ("0002", "baseball_pitch", "back")
    );
    assert_eq!((c0.height_px, c0.width_px, c0.n_frames), (270, 480, 80));
    assert!(c0.train);
    let t = p.clip(0).unwrap();
    assert_eq!((t.n_frames(), t.n_joints(), t.dims()), (80, 13, 2));
    assert_eq!(t.skeleton().name, "penn13");
    assert_eq!(t.units(), Units::Pixels);
    assert_eq!(t.fps(), 30.0);
    assert_eq!((t.point(0, 0)[0], t.point(0, 0)[1]), (48.0, 52.0));
    // Visibility is the confidence: joint 2 of frame 0 is not visible.
    assert_eq!(t.confidence().row(0).to_vec()[..4], [1.0, 1.0, 0.0, 1.0]);
    let bb = p.bbox(0).unwrap();
    assert_eq!(bb.dim(), (80, 4));
    assert!(close(bb[[0, 0]], 19.333334, 1e-5) && close(bb[[0, 3]], 269.33334, 1e-4));
    // Clip 100 (`0161`): rows 8413..8511, left hip of frame 5 at (366, 144).
    let c = p.clip_info(100).unwrap();
    assert_eq!((c.clip_id.as_str(), c.rows.clone()), ("0161", 8413..8511));
    let t = p.clip(100).unwrap();
    assert_eq!((t.point(5, 7)[0], t.point(5, 7)[1]), (366.0, 144.0));
    assert_eq!(t.confidence()[[5, 1]], 0.0);
    let squats = p.clips_of_action("squat");
    assert_eq!(squats.len(), 114);
    assert_eq!(squats[0], 903);
    assert_eq!(p.find_clip("0161"), Some(100));
    assert!(p.clips_of_action("no_such_action").is_empty());
    assert!(matches!(p.clip(1258), Err(GeomError::InvalidParam { .. })));
}

#[test]
fn aistpp_nine_views_at_60_fps() {
    let a = AistPlusPlus::open(data!("aistpp_keypoints2d/gBR_sBM_cAll_d04_mBR0_ch01.npz")).unwrap();
    assert_eq!(a.views.len(), 9);
    assert_eq!(a.fps, 60.0);
    assert_eq!(a.timestamps_us.len(), 720);
    let v3 = &a.views[3];
    assert_eq!((v3.n_frames(), v3.n_joints(), v3.dims()), (720, 17, 2));
    assert_eq!(v3.skeleton().name, "coco17");
    assert_eq!(v3.fps(), 60.0);
    assert_eq!((v3.point(10, 5)[0], v3.point(10, 5)[1]), (912.0, 505.0));
    assert!(close(v3.confidence()[[10, 5]], 0.77744114, 1e-7));
    let v8 = &a.views[8];
    assert_eq!((v8.point(719, 16)[0], v8.point(719, 16)[1]), (960.0, 877.0));
    assert!(close(
        a.det_scores.as_ref().unwrap()[[8, 719]],
        0.69471884,
        1e-7
    ));
    assert_eq!(
        fps_from_timestamps_us(&[0, 16667, 33333, 50000]),
        Some(60.0)
    );
    assert_eq!(fps_from_timestamps_us(&[0, 40000, 80000]), Some(25.0));
    assert_eq!(fps_from_timestamps_us(&[0, 5, 5]), None);
}

#[test]
fn msr_action3d_odd_subjects() {
    data!(MsrAction3D::FILE);
    let m = MsrAction3D::open_default().unwrap();
    assert_eq!(m.len(), 292);
    let c = m.clip_info(0).unwrap();
    assert_eq!(
        (c.action, c.action_name, c.subject, c.rep, c.name.as_str()),
        (1, "high_arm_wave", 1, 1, "a01_s01_e01")
    );
    let t = m.clip(0).unwrap();
    assert_eq!((t.n_frames(), t.n_joints(), t.dims()), (54, 20, 3));
    assert_eq!(t.units(), Units::Metres);
    assert_eq!(t.fps(), 15.0);
    assert_eq!(t.skeleton().name, "msr20");
    let hip = t.point(0, 6);
    assert!(
        close(hip[0], -0.189501, 1e-6)
            && close(hip[1], 0.002549, 1e-6)
            && close(hip[2], 2.759828, 1e-6)
    );
    let head = t.point(0, 19);
    assert!(close(head[1], 0.659618, 1e-6));
    assert!(close(t.confidence()[[0, 5]], 0.971154, 1e-6));
    assert_eq!(t.confidence()[[0, 2]], 0.0);
    let c150 = m.clip_info(150).unwrap();
    assert_eq!(
        (
            c150.action,
            c150.action_name,
            c150.name.as_str(),
            c150.rows.clone()
        ),
        (11, "two_hand_wave", "a11_s01_e03", 5631..5671)
    );
    assert_eq!(m.clips_of_action(19).len(), 15);
    assert_eq!(m.clip_info(291).unwrap().action_name, "pick_up_and_throw");
    let subjects: std::collections::BTreeSet<u32> = m.clips().iter().map(|c| c.subject).collect();
    assert_eq!(
        subjects.into_iter().collect::<Vec<_>>(),
        vec![1, 3, 5, 7, 9]
    );
}

#[test]
fn cmu_features() {
    let c = CmuFeatures::open(data!("cmu_mocap6_exercise/13_29_features10fps.npz")).unwrap();
    let t = &c.track;
    assert_eq!((t.n_frames(), t.n_joints(), t.dims()), (382, 12, 1));
    assert_eq!(t.units(), Units::Unitless);
    assert_eq!(t.fps(), 10.0);
    assert!(close(t.point(0, 0)[0], -0.69772476, 1e-7));
    assert!(close(t.point(381, 11)[0], 0.2893792, 1e-7));
    assert_eq!(c.action_names.len(), 12);
    assert_eq!(c.action_names[0], "JumpJack");
    assert_eq!(c.label_name(0), Some("JumpJack"));
    assert_eq!(c.labels[381], 3);
    assert_eq!(c.label_name(381), Some("Squat"));
    assert_eq!(c.label_name(382), None);
    let segs = c.segments();
    assert_eq!(segs.len(), 6);
    assert_eq!(segs.iter().map(|s| s.1.len()).sum::<usize>(), 382);
}

#[test]
fn mediapipe_reference_golf_swing() {
    let r = MediaPipeReference::open(data!("reference_keypoints/golf_swing.npz")).unwrap();
    assert_eq!((r.width_px, r.height_px), (354, 492));
    assert!(close(r.fps, 29.97, 1e-12));
    assert_eq!(r.found.len(), 264);
    assert!(r.found.iter().all(|&f| f));
    let im = &r.image;
    assert_eq!((im.n_frames(), im.n_joints(), im.dims()), (264, 33, 2));
    assert_eq!(im.skeleton().name, "blazepose33");
    assert!(close(im.point(0, 0)[0], 221.7253, 1e-4) && close(im.point(0, 0)[1], 182.75296, 1e-4));
    assert!(close(im.confidence()[[0, 0]], 0.9994271, 1e-7));
    assert!(close(im.point(100, 16)[0], 147.32333, 1e-4));
    let w = r.world.point(100, 16);
    assert!(
        close(w[0], 0.03602155, 1e-7)
            && close(w[1], -0.361637, 1e-6)
            && close(w[2], -0.41304776, 1e-7)
    );
    assert_eq!(r.world.units(), Units::Metres);
    assert!(close(r.z[[100, 16]], -295.3628, 1e-3));
    assert!(close(r.presence[[100, 16]], 0.994547, 1e-6));
    let s = MediaPipeReference::open_smooth(data!("reference_keypoints/golf_swing.npz")).unwrap();
    assert!(close(s.image.point(100, 16)[0], 149.88939, 1e-4));
}

#[test]
fn mediapipe_reference_missing_frames_have_zero_confidence() {
    let r = MediaPipeReference::open(data!("reference_keypoints/007_pommel_practice.npz")).unwrap();
    assert_eq!(r.found.iter().filter(|&&f| f).count(), 100);
    assert!(!r.found[27] && r.found[26]);
    for t in [27, 32, 33] {
        assert!(r.image.confidence().row(t).iter().all(|&c| c == 0.0));
        assert!(r.world.confidence().row(t).iter().all(|&c| c == 0.0));
    }
    assert!(r.image.positions().iter().all(|v| v.is_finite()));
    assert!(close(r.image.point(149, 15)[0], 225.09244, 1e-4));
    assert!(close(r.image.confidence()[[149, 15]], 0.20136635, 1e-7));
    let none = MediaPipeReference::open(data!("reference_keypoints/028_bar_lift.npz")).unwrap();
    assert_eq!(none.image.n_frames(), 404);
    assert_eq!(none.image.valid_count(), 0);
}

#[test]
fn wrong_file_for_a_reader_is_a_clear_error() {
    let e = PennAction::open(data!("msr_action3d/msr_action3d_odd_subjects.npz")).unwrap_err();
    assert!(e.to_string().contains("`keypoints`"), "{e}");
    let e = MsrAction3D::open(data!("penn_action/penn_action_train.npz")).unwrap_err();
    assert!(e.to_string().contains("`joints`"), "{e}");
    let e = CmuFeatures::open(data!("reference_keypoints/golf_swing.npz")).unwrap_err();
    assert!(e.to_string().contains("`X`"), "{e}");
}
