//! Formats of other tools, read and written through `read_track` /
//! `write_track`: BVH export of joint positions, C3D, Parquet and
//! pose-format `.pose`, on real shared data, and their refusals of broken
//! files and of tracks they cannot hold.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::PathBuf;

use crate::io::datasets::{AistPlusPlus, MsrAction3D};
use crate::io::{
    read_people, read_track, read_track_rated, write_people, write_track, write_track_framed,
    RateSource,
};
use crate::{GeomError, People, Person, Skeleton, Track, Units};
use ndarray::{Array2, Array3};

/// The shared data file `rel`, or the test records its skip and returns.
macro_rules! data {
    ($rel:expr) => {
        crate::data_or_return!($rel)
    };
}

fn salsa(rel: &str) -> PathBuf {
    PathBuf::from("cmu_salsa_bvh").join(rel)
}

/// Largest distance (track units) between the joints found in `a` and the
/// same joints of `b` (matched by name).
fn max_error(a: &Track, b: &Track) -> f64 {
    let mut worst: f64 = 0.0;
    for (ja, name) in a.skeleton().joints.iter().enumerate() {
        let jb = b.skeleton().joint_index(name).expect("joint in both");
        for t in 0..a.n_frames() {
            if a.is_valid(t, ja, 0.0) {
                let d: f64 = (0..a.dims())
                    .map(|k| (a.point(t, ja)[k] - b.point(t, jb)[k]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                worst = worst.max(d);
            }
        }
    }
    worst
}

fn err_text(e: GeomError) -> String {
    e.to_string()
}

// ------------------------------------------------------------------ BVH

/// A BVH read from a file, written back from its joint positions and read
/// again: the hierarchy's bones are rigid, so forward kinematics gives the
/// same positions (to rounding).
#[test]
fn bvh_export_of_a_bvh_track_gives_back_its_positions() {
    let src = data!(salsa("60_01_scaled.bvh"));
    let t = read_track(&src).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("salsa.bvh");
    write_track(&out, &t).unwrap();
    let back = read_track_rated(&out, &Default::default()).unwrap();
    assert_eq!(back.rate, RateSource::File);
    assert!((back.track.fps() - t.fps()).abs() < 1e-9 * t.fps());
    assert_eq!(back.track.skeleton().joints, t.skeleton().joints);
    assert_eq!(back.track.skeleton().bones, t.skeleton().bones);
    assert_eq!(back.track.n_frames(), t.n_frames());
    let err = max_error(&t, &back.track);
    eprintln!(
        "salsa 60_01 BVH → track → BVH: max error {:.3e} mm",
        err * 1e3
    );
    assert!(err < 1e-6, "{err} m");
}

/// The parent of each joint in the tree the skeleton's bones make from its root.
fn tree_parents(sk: &Skeleton) -> Vec<Option<usize>> {
    let root = sk.root.unwrap();
    let mut parent = vec![None; sk.len()];
    let mut seen = vec![false; sk.len()];
    seen[root] = true;
    let mut queue = std::collections::VecDeque::from([root]);
    while let Some(i) = queue.pop_front() {
        for &(a, b) in &sk.bones {
            for (x, y) in [(a, b), (b, a)] {
                if x == i && !seen[y] {
                    seen[y] = true;
                    parent[y] = Some(i);
                    queue.push_back(y);
                }
            }
        }
    }
    parent
}

fn dist(t: &Track, f: usize, a: usize, b: usize) -> f64 {
    (0..3)
        .map(|k| (t.point(f, a)[k] - t.point(f, b)[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// A salsa BVH whose bones stretch and shrink from frame to frame (by up to
/// ±3 %, the directions kept): read back, every joint lies within the sum,
/// along its chain from the root, of |length − median length| of its bones.
#[test]
fn bvh_export_reads_back_within_the_bone_length_spread() {
    let src = data!(salsa("61_02_scaled.bvh"));
    let t = read_track(&src).unwrap();
    let parent = tree_parents(t.skeleton());
    let (n, j_n) = (t.n_frames(), t.n_joints());
    let mut pos = t.positions().to_owned();
    let mut s = 12345u64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    for f in 0..n {
        // Parents come first in BVH order.
        for j in 0..j_n {
            if let Some(p) = parent[j] {
                let stretch = 1.0 + 0.06 * (next() - 0.5);
                for k in 0..3 {
                    let bone = t.point(f, j)[k] - t.point(f, p)[k];
                    pos[[f, j, k]] = pos[[f, p, k]] + bone * stretch;
                }
            }
        }
    }
    let stretched = Track::new(pos, None, t.fps(), Units::Metres, t.skeleton().clone()).unwrap();
    let median: Vec<f64> = (0..j_n)
        .map(|j| match parent[j] {
            None => 0.0,
            Some(p) => {
                let mut v: Vec<f64> = (0..n).map(|f| dist(&stretched, f, j, p)).collect();
                v.sort_by(f64::total_cmp);
                if n % 2 == 1 {
                    v[n / 2]
                } else {
                    0.5 * (v[n / 2 - 1] + v[n / 2])
                }
            }
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("stretched.bvh");
    write_track(&out, &stretched).unwrap();
    let back = read_track(&out).unwrap();
    let (mut worst, mut worst_spread): (f64, f64) = (0.0, 0.0);
    for f in 0..n {
        for j in 0..j_n {
            let mut spread = 0.0;
            let mut k = j;
            while let Some(p) = parent[k] {
                spread += (dist(&stretched, f, k, p) - median[k]).abs();
                k = p;
            }
            let e: f64 = (0..3)
                .map(|k| (stretched.point(f, j)[k] - back.point(f, j)[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(
                e <= spread + 1e-9,
                "frame {f}, joint {}: {e} m from the source, spread {spread} m",
                t.skeleton().joints[j]
            );
            worst = worst.max(e);
            worst_spread = worst_spread.max(spread);
        }
    }
    eprintln!(
        "salsa 61_02 with bones stretched ±3 %: largest error {:.1} mm (largest chain spread \
         {:.1} mm)",
        worst * 1e3,
        worst_spread * 1e3
    );
    assert!(worst > 1e-3, "the stretch should show");
}

/// MSR Action3D joint positions (Kinect; the neck, spine and hip centre
/// are missing in almost every frame, so their places are made up from
/// their neighbours) written as BVH and read back by forward kinematics:
/// the found joints come back within a few centimetres.
#[test]
fn bvh_export_of_msr_joint_positions_reads_back_within_centimetres() {
    data!(MsrAction3D::FILE);
    let m = MsrAction3D::open_default().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("msr.bvh");
    let mut errs = Vec::new();
    let mut spread = Vec::new();
    for i in (0..m.len()).step_by(5) {
        let t = m.clip(i).unwrap();
        write_track(&out, &t).unwrap();
        let back = read_track(&out).unwrap();
        // The built-in skeleton comes back, in its order.
        assert_eq!(back.skeleton(), t.skeleton());
        assert_eq!(back.fps(), 15.0);
        assert_eq!(back.n_frames(), t.n_frames());
        for f in 0..t.n_frames() {
            for j in 0..20 {
                if t.is_valid(f, j, 0.0) {
                    errs.push(dist_between(&t, &back, f, j));
                }
            }
        }
        for &(a, b) in &t.skeleton().bones {
            let mut l: Vec<f64> = (0..t.n_frames())
                .filter(|&f| t.is_valid(f, a, 0.0) && t.is_valid(f, b, 0.0))
                .map(|f| dist(&t, f, a, b))
                .collect();
            l.sort_by(f64::total_cmp);
            if let Some(&med) = l.get(l.len() / 2) {
                spread.extend(l.iter().map(|x| (x - med).abs()));
            }
        }
    }
    errs.sort_by(f64::total_cmp);
    spread.sort_by(f64::total_cmp);
    let q = |v: &[f64], p: f64| v[((v.len() - 1) as f64 * p) as usize] * 1e3;
    eprintln!(
        "MSR → BVH → track ({} found joints): error median {:.1} mm, p95 {:.1} mm, max {:.1} mm; \
         bone length − median: median {:.1} mm, p95 {:.1} mm",
        errs.len(),
        q(&errs, 0.5),
        q(&errs, 0.95),
        q(&errs, 1.0),
        q(&spread, 0.5),
        q(&spread, 0.95),
    );
    assert!(q(&errs, 0.5) <= 15.0, "median {} mm", q(&errs, 0.5));
    assert!(q(&errs, 0.95) <= 100.0, "p95 {} mm", q(&errs, 0.95));
}

fn dist_between(a: &Track, b: &Track, f: usize, j: usize) -> f64 {
    (0..3)
        .map(|k| (a.point(f, j)[k] - b.point(f, j)[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

#[test]
fn bvh_export_refuses_2d_tracks_and_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let t = Track::new(
        Array3::zeros((3, 17, 2)),
        None,
        30.0,
        Units::Pixels,
        Skeleton::coco17(),
    )
    .unwrap();
    let out = dir.path().join("flat.bvh");
    let e = err_text(write_track(&out, &t).unwrap_err());
    assert!(e.contains("flat.bvh") && e.contains("3D"), "{e}");
    assert!(!out.exists());
}

// ------------------------------------------------------------------ C3D

fn aist_view(test_rel: &str) -> Option<Track> {
    let p = crate::test_support::data_file_or_skip(
        test_rel,
        &crate::test_support::current_test_name(),
    )?;
    Some(AistPlusPlus::open(p).unwrap().views[3].clone())
}

/// MSR Action3D clips through C3D: positions within 0.001 mm (32-bit
/// floats of millimetres), the rate, the joint names (so MSR-20 again) and
/// which joints were found; confidence itself is not kept (found → 1).
#[test]
fn c3d_round_trip_of_msr_clips() {
    data!(MsrAction3D::FILE);
    let m = MsrAction3D::open_default().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("msr.c3d");
    let mut worst: f64 = 0.0;
    for i in [0, 101, 250] {
        let t = m.clip(i).unwrap();
        write_track(&out, &t).unwrap();
        let back = read_track_rated(&out, &Default::default()).unwrap();
        assert_eq!(back.rate, RateSource::File);
        let b = back.track;
        assert_eq!(b.fps(), 15.0);
        assert_eq!(b.units(), Units::Metres);
        assert_eq!(b.skeleton(), t.skeleton());
        assert_eq!(b.n_frames(), t.n_frames());
        for f in 0..t.n_frames() {
            for j in 0..20 {
                assert_eq!(
                    b.is_valid(f, j, 0.0),
                    t.is_valid(f, j, 0.0),
                    "frame {f} joint {j}"
                );
                if t.is_valid(f, j, 0.0) {
                    assert_eq!(b.confidence()[[f, j]], 1.0);
                    worst = worst.max(dist_between(&t, &b, f, j));
                }
            }
        }
    }
    eprintln!("MSR → C3D → track: max error {:.2e} mm", worst * 1e3);
    assert!(worst < 1e-6, "{worst} m");
}

/// A BVH's 31 joints (custom names) at 120 fps through C3D; a rate that is
/// not whole (29.97) comes back as written.
#[test]
fn c3d_round_trip_of_a_bvh_track_and_a_fractional_rate() {
    let t = read_track(data!(salsa("60_02_scaled.bvh"))).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("salsa.c3d");
    write_track(&out, &t).unwrap();
    let b = read_track(&out).unwrap();
    assert_eq!(b.skeleton().joints, t.skeleton().joints);
    // Frame Time 0.008333 s: 120.0048 fps, kept to 32-bit float precision.
    assert!(
        (b.fps() - t.fps()).abs() < 1e-6 * t.fps(),
        "{} vs {}",
        b.fps(),
        t.fps()
    );
    assert!(max_error(&t, &b) < 1e-6);
    let t = t.slice_frames(0, 50).unwrap().with_fps(29.97).unwrap();
    write_track(&out, &t).unwrap();
    assert_eq!(read_track(&out).unwrap().fps(), 29.97);
}

#[test]
fn c3d_refuses_2d_tracks_and_broken_files() {
    let dir = tempfile::tempdir().unwrap();
    let flat = Track::new(
        Array3::zeros((2, 17, 2)),
        None,
        30.0,
        Units::Pixels,
        Skeleton::coco17(),
    )
    .unwrap();
    let out = dir.path().join("flat.c3d");
    let e = err_text(write_track(&out, &flat).unwrap_err());
    assert!(e.contains("flat.c3d") && e.contains("3D points"), "{e}");
    assert!(!out.exists());
    // A real file cut short, a file cut inside its header, and junk.
    let t = Track::new(
        Array3::from_shape_fn((40, 3, 3), |(f, j, k)| (f + j + k) as f64 * 0.01),
        None,
        50.0,
        Units::Metres,
        Skeleton::generic(3),
    )
    .unwrap();
    let good = dir.path().join("good.c3d");
    write_track(&good, &t).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let cut = dir.path().join("cut.c3d");
    // 40 frames of 3 points need 1920 bytes after the header and parameter blocks.
    for (len, says) in [(1024 + 1900, "truncated"), (700, "too short")] {
        std::fs::write(&cut, &bytes[..len]).unwrap();
        let e = err_text(read_track(&cut).unwrap_err());
        assert!(
            e.contains("cut.c3d") && e.contains(says),
            "{len} bytes: {e}"
        );
    }
    std::fs::write(&cut, vec![7u8; 4096]).unwrap();
    let e = err_text(read_track(&cut).unwrap_err());
    assert!(e.contains("not a C3D file"), "{e}");
    // Every cut of the file is an error or a track, never a panic.
    for len in (0..bytes.len()).step_by(37) {
        std::fs::write(&cut, &bytes[..len]).unwrap();
        let _ = read_track(&cut);
    }
}

// ------------------------------------------------------------------ Parquet

/// Missing joints in a track: `every`-th (frame, joint) cell has confidence 0.
fn with_gaps(t: &Track, every: usize) -> Track {
    let (pos, mut conf, fps, units, sk) = t.clone().into_parts();
    for (i, c) in conf.iter_mut().enumerate() {
        if i % every == 0 {
            *c = 0.0;
        }
    }
    Track::new(pos, Some(conf), fps, units, sk).unwrap()
}

/// AIST++ 2D keypoints (COCO-17, 60 fps, detector confidence) through
/// Parquet: positions and confidence exact, rate, skeleton and frame size
/// kept, missing joints still missing (null coordinates).
#[test]
fn parquet_round_trip_of_aist_keypoints() {
    let Some(t) = aist_view("aistpp_keypoints2d/gBR_sBM_cAll_d04_mBR0_ch01.npz") else {
        return;
    };
    let t = with_gaps(&t, 7);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("aist.parquet");
    write_track_framed(&out, &t, Some((1920, 1080))).unwrap();
    let back = read_track_rated(&out, &Default::default()).unwrap();
    assert_eq!(back.rate, RateSource::File);
    assert_eq!(back.frame_size, Some((1920, 1080)));
    let b = back.track;
    assert_eq!((b.fps(), b.units()), (60.0, Units::Pixels));
    assert_eq!(b.skeleton(), t.skeleton());
    assert_eq!(b.confidence(), t.confidence());
    for f in 0..t.n_frames() {
        for j in 0..17 {
            if t.is_valid(f, j, 0.0) {
                assert_eq!(b.point(f, j), t.point(f, j));
            }
        }
    }
    assert_eq!(
        b.confidence().iter().filter(|c| **c == 0.0).count(),
        t.confidence().iter().filter(|c| **c == 0.0).count()
    );
}

/// Two people with different spans through Parquet (a `person` column).
#[test]
fn parquet_and_pose_keep_people() {
    let Some(t) = aist_view("aistpp_keypoints2d/gBR_sBM_cAll_d04_mBR0_ch02.npz") else {
        return;
    };
    let a = t.slice_frames(0, 300).unwrap();
    let b = t.slice_frames(200, 720).unwrap();
    let people = People::new(
        720,
        60.0,
        vec![
            Person {
                id: 1,
                first_frame: 0,
                track: a,
            },
            Person {
                id: 2,
                first_frame: 200,
                track: b,
            },
        ],
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    for ext in ["parquet", "pose"] {
        let out = dir.path().join(format!("two.{ext}"));
        write_people(&out, &people).unwrap();
        let back = read_people(&out).unwrap();
        assert_eq!(back.len(), 2, "{ext}");
        assert_eq!(back.n_frames(), 720, "{ext}");
        for (p, q) in people.people().iter().zip(back.people()) {
            assert_eq!((q.id, q.first_frame), (p.id, p.first_frame), "{ext}");
            assert_eq!(q.track.n_frames(), p.track.n_frames(), "{ext}");
            let tol = if ext == "pose" { 1e-3 } else { 0.0 };
            assert!(max_error(&p.track, &q.track) <= tol, "{ext}");
        }
        // As a single track: the main person over the whole video.
        let main = read_track(&out).unwrap();
        assert_eq!(main.n_frames(), 720, "{ext}");
    }
}

#[test]
fn parquet_refuses_broken_files() {
    let dir = tempfile::tempdir().unwrap();
    let t = Track::new(
        Array3::from_shape_fn((30, 5, 2), |(f, j, k)| (f * 10 + j + k) as f64),
        None,
        25.0,
        Units::Pixels,
        Skeleton::generic(5),
    )
    .unwrap();
    let good = dir.path().join("good.parquet");
    write_track(&good, &t).unwrap();
    assert_eq!(read_track(&good).unwrap(), t);
    let bytes = std::fs::read(&good).unwrap();
    let cut = dir.path().join("cut.parquet");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = err_text(read_track(&cut).unwrap_err());
    assert!(e.contains("cut.parquet") && e.contains("Parquet"), "{e}");
    std::fs::write(&cut, b"PAR1 not really").unwrap();
    assert!(matches!(read_track(&cut), Err(GeomError::Format { .. })));
    // Flipped bytes in the middle: an error or a track, never a panic.
    for i in (8..bytes.len() - 8).step_by(53) {
        let mut b = bytes.clone();
        b[i] ^= 0x5a;
        std::fs::write(&cut, &b).unwrap();
        let _ = read_track(&cut);
    }
}

// ------------------------------------------------------------------ .pose

/// MediaPipe BlazePose keypoints of the golf swing (with joints missing)
/// through `.pose`: written as MediaPipe's `POSE_LANDMARKS`, read
/// back as BlazePose-33 within 32-bit float rounding, gaps kept.
#[test]
fn pose_round_trip_of_blazepose_keypoints() {
    let src = data!("reference_keypoints/golf_swing.npz");
    let t = with_gaps(&read_track(&src).unwrap(), 11);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("golf.pose");
    write_track_framed(&out, &t, Some((1280, 720))).unwrap();
    let f = crate::io::pose::PoseFile::parse(&std::fs::read(&out).unwrap(), &out).unwrap();
    assert_eq!(f.components[0].name, "POSE_LANDMARKS");
    assert_eq!(f.components[0].points[31], "LEFT_FOOT_INDEX");
    let back = read_track_rated(&out, &Default::default()).unwrap();
    assert_eq!(back.frame_size, Some((1280, 720)));
    let b = back.track;
    assert_eq!(b.skeleton().name, "blazepose33");
    assert!(
        (b.fps() - t.fps()).abs() < 1e-4,
        "{} vs {}",
        b.fps(),
        t.fps()
    );
    let err = max_error(&t, &b);
    eprintln!("golf BlazePose → .pose → track: max error {err:.2e} px");
    assert!(err < 1e-3, "{err} px");
    for (x, y) in t.confidence().iter().zip(b.confidence()) {
        assert!((x - y).abs() < 1e-7 && ((*x == 0.0) == (*y == 0.0)));
    }
}

/// AIST++ COCO-17 and MSR 3D (metres, no frame size) through `.pose`.
#[test]
fn pose_round_trip_of_coco_and_3d_tracks() {
    let Some(t) = aist_view("aistpp_keypoints2d/gBR_sBM_cAll_d04_mBR0_ch03.npz") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("aist.pose");
    write_track(&out, &t).unwrap();
    let back = read_track_rated(&out, &Default::default()).unwrap();
    assert_eq!(back.frame_size, None);
    assert_eq!(back.track.skeleton(), t.skeleton());
    assert_eq!(
        (back.track.fps(), back.track.units()),
        (60.0, Units::Pixels)
    );
    assert!(max_error(&t, &back.track) < 1e-3);
    data!(MsrAction3D::FILE);
    let m = MsrAction3D::open_default().unwrap().clip(3).unwrap();
    write_track(&out, &m).unwrap();
    let b = read_track(&out).unwrap();
    assert_eq!((b.units(), b.dims(), b.fps()), (Units::Metres, 3, 15.0));
    assert_eq!(b.skeleton(), m.skeleton());
    assert!(max_error(&m, &b) < 1e-6);
}

#[test]
fn pose_refuses_broken_files() {
    let dir = tempfile::tempdir().unwrap();
    let t = Track::new(
        Array3::from_shape_fn((12, 17, 2), |(f, j, k)| (f * 3 + j + k) as f64),
        Some(Array2::from_elem((12, 17), 0.5)),
        30.0,
        Units::Pixels,
        Skeleton::coco17(),
    )
    .unwrap();
    let good = dir.path().join("good.pose");
    write_track(&good, &t).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let cut = dir.path().join("cut.pose");
    std::fs::write(&cut, &bytes[..bytes.len() - 10]).unwrap();
    let e = err_text(read_track(&cut).unwrap_err());
    assert!(e.contains("cut.pose") && e.contains("truncated"), "{e}");
    std::fs::write(&cut, &bytes[..30]).unwrap();
    assert!(err_text(read_track(&cut).unwrap_err()).contains("truncated"));
    std::fs::write(&cut, b"\x00\x00\x80\x3f rest").unwrap();
    assert!(err_text(read_track(&cut).unwrap_err()).contains("version"));
    for len in 0..bytes.len().min(600) {
        std::fs::write(&cut, &bytes[..len]).unwrap();
        assert!(read_track(&cut).is_err(), "{len} bytes");
    }
}

/// Every format here names the file when writing fails for what the track is.
#[test]
fn writers_name_the_file_they_refuse() {
    let dir = tempfile::tempdir().unwrap();
    let t = Track::new(
        Array3::zeros((2, 3, 1)),
        None,
        30.0,
        Units::Unitless,
        Skeleton::generic(3),
    )
    .unwrap();
    for ext in ["bvh", "c3d", "parquet", "pose"] {
        let out = dir.path().join(format!("one_d.{ext}"));
        let e = err_text(write_track(&out, &t).unwrap_err());
        assert!(e.contains(&format!("one_d.{ext}")), "{ext}: {e}");
        assert!(!out.exists());
    }
}

/// The procedural performer's 3D COCO-17 track (limbs of fixed length that
/// swing freely from the shoulders and hips, a torso that bends): the
/// export gives each limb its own joint where the shoulders and hips carry
/// bones whose angles change, so the joints come back within the torso's
/// bending; read back as COCO-17.
#[test]
fn bvh_export_of_the_performer_splits_branching_joints() {
    let p = crate::performer::perform(&Default::default()).unwrap();
    let t = &p.track_3d;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("performer.bvh");
    write_track(&out, t).unwrap();
    let raw = crate::io::bvh::Bvh::read(&out).unwrap();
    assert!(
        raw.joints().len() > 17,
        "zero-length joints between branches"
    );
    assert!(raw.joints().iter().any(|j| j.name.contains('-')));
    let b = read_track(&out).unwrap();
    assert_eq!(b.skeleton(), t.skeleton());
    let mut e: Vec<f64> = Vec::new();
    for f in 0..t.n_frames() {
        for j in 0..t.n_joints() {
            e.push(dist_between(t, &b, f, j));
        }
    }
    e.sort_by(f64::total_cmp);
    let q = |p: f64| e[((e.len() - 1) as f64 * p) as usize] * 1e3;
    eprintln!(
        "performer 3D → BVH → track: median {:.2} mm, p95 {:.1} mm, max {:.1} mm",
        q(0.5),
        q(0.95),
        q(1.0)
    );
    assert!(q(0.5) <= 1.0 && q(0.95) <= 10.0 && q(1.0) <= 80.0);
}
