//! The project's own formats (npz, JSON, CSV, npy), OpenPose / AlphaPose
//! JSON, and the `read_track` / `write_track` dispatch.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::io::csv::{read_csv, write_csv, CsvLayout};
use crate::io::datasets::PennAction;
use crate::io::native::{read_track_json, read_track_npz, write_track_npy};
use crate::io::openpose::{body25_skeleton, coco18_skeleton, read_alphapose, read_openpose_dir};
use crate::io::{read_track, read_track_with, write_track, ReadOptions};
use crate::{GeomError, Skeleton, Track, Units};
use ndarray::{Array2, Array3};
use proptest::prelude::*;

/// A Penn Action clip, or `None` (skip recorded) without the shared data.
fn penn_clip(test: &str) -> Option<Track> {
    crate::test_support::data_file_or_skip(PennAction::TRAIN_FILE, test)?;
    Some(
        PennAction::open_default()
            .expect("Penn Action npz")
            .clip(7)
            .unwrap(),
    )
}

fn msr_like(t: usize) -> Track {
    let mut p = Array3::zeros((t, 20, 3));
    for ((f, j, k), v) in p.indexed_iter_mut() {
        *v = (f as f64 * 0.1).sin() * (j + 1) as f64 / 7.0 + k as f64 / 3.0;
    }
    let mut c = Array2::from_elem((t, 20), 0.5);
    c[[1, 3]] = 0.0;
    Track::new(p, Some(c), 15.0, Units::Metres, Skeleton::msr20()).unwrap()
}

#[test]
fn npz_and_json_round_trip_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let Some(penn) = penn_clip("npz_and_json_round_trip_exactly") else {
        return;
    };
    for tr in [penn, msr_like(9)] {
        for ext in ["npz", "json"] {
            let p = dir.path().join(format!("t.{ext}"));
            write_track(&p, &tr).unwrap();
            let back = read_track(&p).unwrap();
            assert_eq!(back, tr, "{ext} round trip of {}", tr.skeleton().name);
        }
    }
    // Only the final files remain: temporary files were renamed into place.
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, vec!["t.json", "t.npz"]);
}

#[test]
fn npz_written_with_custom_skeleton_keeps_it() {
    let sk = Skeleton::custom(
        "bvh",
        vec!["hip".into(), "knee".into(), "left_wrist".into()],
        vec![(0, 1), (1, 2)],
        Some(0),
    );
    let p = Array3::from_shape_fn((4, 3, 3), |(f, j, k)| (f * 9 + j * 3 + k) as f64 * 0.25);
    let tr = Track::new(p, None, 120.0, Units::Metres, sk).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("c.npz");
    write_track(&f, &tr).unwrap();
    let back = read_track_npz(&f).unwrap();
    assert_eq!(back.skeleton().coco17[9], Some(2));
    assert_eq!(back.skeleton().root, Some(0));
    assert_eq!(back, tr);
}

#[test]
fn csv_long_and_wide_round_trip() {
    let Some(tr) = penn_clip("csv_long_and_wide_round_trip") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for layout in [CsvLayout::Long, CsvLayout::Wide] {
        let p = dir.path().join(format!("{layout:?}.csv"));
        write_csv(&p, &tr, layout).unwrap();
        let back = read_csv(&p, &ReadOptions::default()).unwrap();
        assert_eq!(
            back.skeleton().name,
            "penn13",
            "{layout:?}: names select the built-in skeleton"
        );
        assert_eq!(back.positions(), tr.positions());
        assert_eq!(back.confidence(), tr.confidence());
        assert_eq!(back.fps(), 30.0);
    }
    // 3D wide CSV via write_track's `.csv`.
    let m = msr_like(5);
    let p = dir.path().join("m.csv");
    write_track(&p, &m).unwrap();
    let back = read_track_with(
        &p,
        &ReadOptions {
            fps: Some(15.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(back, m);
}

#[test]
fn csv_long_by_index_with_gaps() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("l.csv");
    std::fs::write(
        &p,
        "# two joints\nframe,joint,x,y,score\n0,0,1,2,0.9\n0,1,3,4,1\n2,1,5,6,0.5\n",
    )
    .unwrap();
    let t = read_track(&p).unwrap();
    assert_eq!((t.n_frames(), t.n_joints(), t.dims()), (3, 2, 2));
    assert_eq!(t.skeleton().name, "generic");
    assert_eq!(
        t.confidence().to_owned(),
        ndarray::array![[0.9, 1.0], [0.0, 0.0], [0.0, 0.5]]
    );
    assert_eq!(t.point(2, 1).to_vec(), vec![5.0, 6.0]);
    std::fs::write(&p, "frame,joint,x,y\n0,0,1,zz\n").unwrap();
    let e = read_track(&p).unwrap_err();
    assert!(
        e.to_string().contains("line 2") && e.to_string().contains("`zz`"),
        "{e}"
    );
    std::fs::write(&p, "frame,joint,x,y\n0,0,1\n").unwrap();
    assert!(read_track(&p)
        .unwrap_err()
        .to_string()
        .contains("line 2 has 3 fields"));
    std::fs::write(&p, "a_x,a_q\n1,2\n").unwrap();
    assert!(read_track(&p)
        .unwrap_err()
        .to_string()
        .contains("unknown suffix"));
}

#[test]
fn npy_positions() {
    let tr = msr_like(6);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.npy");
    write_track_npy(&p, &tr).unwrap();
    let back = read_track_with(
        &p,
        &ReadOptions {
            fps: Some(15.0),
            skeleton: Some(Skeleton::msr20()),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(back.positions(), tr.positions());
    assert_eq!(back.units(), Units::Metres);
    let generic = read_track(&p).unwrap();
    assert_eq!(generic.skeleton().name, "generic");
    let e = read_track_with(
        &p,
        &ReadOptions {
            skeleton: Some(Skeleton::coco17()),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("20 joints"), "{e}");
}

fn op_frame(people: &[(f64, usize)]) -> String {
    // Each person: (confidence, joint count); x = 10 * joint, y = confidence * 100.
    let ps: Vec<String> = people
        .iter()
        .map(|&(c, n)| {
            let kp: Vec<String> = (0..n)
                .map(|j| format!("{},{},{}", 10 * j, c * 100.0, if j == 3 { 0.0 } else { c }))
                .collect();
            format!(
                "{{\"person_id\":[-1],\"pose_keypoints_2d\":[{}]}}",
                kp.join(",")
            )
        })
        .collect();
    format!("{{\"version\":1.3,\"people\":[{}]}}", ps.join(","))
}

#[test]
fn openpose_folder_body25_and_coco18() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("v_000000000000_keypoints.json"),
        op_frame(&[(0.3, 25), (0.8, 25)]),
    )
    .unwrap();
    std::fs::write(
        dir.path().join("v_000000000001_keypoints.json"),
        op_frame(&[]),
    )
    .unwrap();
    std::fs::write(
        dir.path().join("v_000000000002_keypoints.json"),
        op_frame(&[(0.6, 25)]),
    )
    .unwrap();
    let t = read_track(dir.path()).unwrap();
    assert_eq!((t.n_frames(), t.n_joints()), (3, 25));
    assert_eq!(t.skeleton(), &body25_skeleton());
    assert_eq!(t.point(0, 0)[1], 80.0, "the more confident person is kept");
    assert_eq!(t.confidence()[[0, 3]], 0.0, "0,0,0 joints are missing");
    assert!(
        t.confidence().row(1).iter().all(|&c| c == 0.0),
        "empty frame"
    );
    assert_eq!(t.point(2, 4).to_vec(), vec![40.0, 60.0]);
    let coco = t.to_coco17().unwrap();
    assert_eq!(
        coco.point(2, 9).to_vec(),
        vec![70.0, 60.0],
        "left wrist = BODY_25 joint 7"
    );
    assert_eq!(
        coco.point(2, 12).to_vec(),
        vec![90.0, 60.0],
        "right hip = BODY_25 joint 9"
    );

    let d18 = tempfile::tempdir().unwrap();
    std::fs::write(
        d18.path().join("a_0_keypoints.json"),
        op_frame(&[(0.9, 18)]),
    )
    .unwrap();
    let t = read_openpose_dir(
        d18.path(),
        &ReadOptions {
            fps: Some(25.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(t.skeleton(), &coco18_skeleton());
    assert_eq!(t.fps(), 25.0);
    assert_eq!(
        t.to_coco17().unwrap().point(0, 11).to_vec(),
        vec![110.0, 90.0],
        "left hip = COCO-18 joint 11"
    );
    std::fs::write(
        d18.path().join("a_1_keypoints.json"),
        op_frame(&[(0.9, 20)]),
    )
    .unwrap();
    let e = read_openpose_dir(d18.path(), &ReadOptions::default()).unwrap_err();
    assert!(
        e.to_string().contains("a_1_keypoints.json") && e.to_string().contains("20 keypoints"),
        "{e}"
    );
    let empty = tempfile::tempdir().unwrap();
    assert!(matches!(
        read_track(empty.path()),
        Err(GeomError::Format { .. })
    ));
}

#[test]
fn alphapose_results() {
    let kp = |x0: f64, s: f64| -> String {
        (0..17)
            .map(|j| format!("{},{},{}", x0 + j as f64, 2.0 * j as f64, s))
            .collect::<Vec<_>>()
            .join(",")
    };
    let json = format!(
        "[{{\"image_id\":\"0.jpg\",\"category_id\":1,\"keypoints\":[{}],\"score\":1.2}},\
          {{\"image_id\":\"0.jpg\",\"category_id\":1,\"keypoints\":[{}],\"score\":2.5}},\
          {{\"image_id\":\"1.jpg\",\"category_id\":1,\"keypoints\":[{}],\"score\":0.9}}]",
        kp(100.0, 0.5),
        kp(300.0, 0.7),
        kp(200.0, 0.9)
    );
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("alphapose-results.json");
    std::fs::write(&p, json).unwrap();
    let t = read_track(&p).unwrap();
    assert_eq!((t.n_frames(), t.n_joints()), (2, 17));
    assert_eq!(t.skeleton().name, "coco17");
    assert_eq!(t.point(0, 0)[0], 300.0, "highest score wins");
    assert_eq!(t.point(1, 16).to_vec(), vec![216.0, 32.0]);
    assert_eq!(t.confidence()[[0, 5]], 0.7);
    std::fs::write(&p, "[{\"image_id\":\"0.jpg\",\"keypoints\":[1,2,3]}]").unwrap();
    let e = read_alphapose(&p, &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("entry 0"), "{e}");
}

#[test]
fn read_track_dispatch_and_errors() {
    // Data-set files that hold one track are read directly.
    let golf = crate::data_or_return!("reference_keypoints/golf_swing.npz");
    let t = read_track(&golf).unwrap();
    assert_eq!(
        (t.n_frames(), t.skeleton().name.as_str()),
        (264, "blazepose33")
    );
    let cmu = crate::data_or_return!("cmu_mocap6_exercise/13_30_features10fps.npz");
    assert_eq!(read_track(&cmu).unwrap().n_frames(), 205);
    // Multi-track files point to their reader.
    let penn = crate::data_or_return!("penn_action/penn_action_train.npz");
    assert!(read_track(&penn)
        .unwrap_err()
        .to_string()
        .contains("PennAction"));
    let aist = crate::data_or_return!("aistpp_keypoints2d/gBR_sBM_cAll_d04_mBR0_ch02.npz");
    assert!(read_track(&aist)
        .unwrap_err()
        .to_string()
        .contains("AistPlusPlus"));

    let dir = tempfile::tempdir().unwrap();
    let e = read_track(dir.path().join("absent.npz")).unwrap_err();
    assert!(
        matches!(e, GeomError::Io { .. }) && e.to_string().contains("absent.npz"),
        "{e}"
    );
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "{\"format\": \"mp-track\", \"version\": 1").unwrap();
    assert!(read_track(&bad)
        .unwrap_err()
        .to_string()
        .contains("invalid JSON"));
    std::fs::write(&bad, "{\"hello\": 1}").unwrap();
    assert!(matches!(read_track(&bad), Err(GeomError::Format { .. })));
    // A JSON track with a ragged frame.
    let mut text = crate::io::native::track_to_json_string(&msr_like(3)).unwrap();
    text = text.replacen("[[[", "[[[9,", 1);
    std::fs::write(&bad, text).unwrap();
    let e = read_track_json(&bad).unwrap_err();
    assert!(
        e.to_string()
            .contains("frame 0, joint 1: 3 values, expected 4"),
        "{e}"
    );
    let junk = dir.path().join("junk.npz");
    std::fs::write(&junk, b"PK\x03\x04 this is not really a zip file").unwrap();
    assert!(matches!(read_track(&junk), Err(GeomError::Format { .. })));
    assert!(read_track(dir.path().join("x.xyz")).is_err());
    std::fs::write(dir.path().join("x.xyz"), "1").unwrap();
    assert!(read_track(dir.path().join("x.xyz"))
        .unwrap_err()
        .to_string()
        .contains("extension"));
    assert!(write_track(dir.path().join("x.txt"), &msr_like(2)).is_err());
    let e = read_track_with(
        &golf,
        &ReadOptions {
            fps: Some(0.0),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, GeomError::InvalidParam { name: "fps", .. }));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn random_tracks_round_trip(
        t in 1usize..6, j in 1usize..5, d in 2usize..4,
        seed in any::<u64>(), fps in 1.0f64..240.0,
    ) {
        let mut s = seed;
        let mut next = || { s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407); (s >> 11) as f64 / (1u64 << 53) as f64 };
        let p = Array3::from_shape_fn((t, j, d), |_| (next() - 0.5) * 1e4);
        let c = Array2::from_shape_fn((t, j), |_| next());
        let units = if d == 2 { Units::Pixels } else { Units::Metres };
        let tr = Track::new(p, Some(c), fps, units, Skeleton::generic(j)).unwrap();
        let dir = tempfile::tempdir().unwrap();
        for ext in ["npz", "json", "csv"] {
            let f = dir.path().join(format!("r.{ext}"));
            write_track(&f, &tr).unwrap();
            let back = read_track_with(&f, &ReadOptions::default()).unwrap();
            if ext == "csv" {
                // CSV states the rate through its `time` column (to the
                // nanosecond; a rate within 0.01 % of a whole number is read
                // as that number); one frame states none.
                if t > 1 {
                    prop_assert!((back.fps() - fps).abs() <= 1e-4 * fps, "{} vs {fps}", back.fps());
                }
                prop_assert_eq!(&back.with_fps(fps).unwrap(), &tr);
            } else {
                prop_assert_eq!(&back, &tr);
            }
        }
    }
}
