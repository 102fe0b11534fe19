//! BVH parsing, forward kinematics, writing, slicing and concatenation, on
//! a hand-checked toy hierarchy and on the real CMU salsa files.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::io::bvh::{Bvh, BvhTrackParams, Channel};
use crate::io::read_track;
use crate::test_support::data_file_or_skip;
use crate::{GeomError, Units};

const TOY: &str = "HIERARCHY
ROOT hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT lThigh
  {
    OFFSET 1 0 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    JOINT lShin
    {
      OFFSET 0 -2 0
      CHANNELS 3 Zrotation Yrotation Xrotation
      End Site
      {
        OFFSET 0 -1 0
      }
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.5
0 0 0 0 0 0 0 0 0 0 0 0
1 2 3 90 0 0 0 0 0 0 0 0
0 0 0 0 0 0 0 0 0 0 0 90
";

/// The six salsa BVH files, or `None` (skip recorded) without the shared data.
fn salsa_files(test: &str) -> Option<Vec<std::path::PathBuf>> {
    let d = data_file_or_skip("cmu_salsa_bvh", test)?;
    let mut v: Vec<_> = std::fs::read_dir(&d)
        .unwrap_or_else(|e| panic!("{}: {e}", d.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "bvh"))
        .collect();
    v.sort();
    assert_eq!(
        v.len(),
        6,
        "six salsa BVH files expected in {}",
        d.display()
    );
    Some(v)
}

fn approx(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

#[test]
fn toy_forward_kinematics_by_hand() {
    let b = Bvh::parse(TOY, "toy.bvh").unwrap();
    assert_eq!((b.n_frames(), b.n_channels(), b.joints().len()), (3, 12, 3));
    assert_eq!(b.fps(), 2.0);
    assert_eq!(
        b.joints()[2].channels,
        vec![Channel::Zrotation, Channel::Yrotation, Channel::Xrotation]
    );
    let t = b
        .to_track(&BvhTrackParams {
            include_end_sites: true,
            ..Default::default()
        })
        .unwrap();
    assert_eq!(
        t.skeleton().joints,
        vec!["hips", "lThigh", "lShin", "lShin_end"]
    );
    assert_eq!(t.skeleton().bones, vec![(0, 1), (1, 2), (2, 3)]);
    assert_eq!(t.skeleton().root, Some(0));
    // COCO mapping by BVH names: lThigh = left hip, lShin = left knee.
    assert_eq!(t.skeleton().coco17[11], Some(1));
    assert_eq!(t.skeleton().coco17[13], Some(2));
    // Frame 0: rest pose.
    assert!(approx(&t.point(0, 2).to_vec(), &[1.0, -2.0, 0.0], 1e-12));
    assert!(approx(&t.point(0, 3).to_vec(), &[1.0, -3.0, 0.0], 1e-12));
    // Frame 1: root at (1,2,3), rotated 90° about z: local +x → +y, −y → +x.
    assert!(approx(&t.point(1, 0).to_vec(), &[1.0, 2.0, 3.0], 1e-12));
    assert!(approx(&t.point(1, 1).to_vec(), &[1.0, 3.0, 3.0], 1e-12));
    assert!(approx(&t.point(1, 2).to_vec(), &[3.0, 3.0, 3.0], 1e-12));
    assert!(approx(&t.point(1, 3).to_vec(), &[4.0, 3.0, 3.0], 1e-12));
    // Frame 2: knee rotated 90° about x: the end site swings from −y to −z.
    assert!(approx(&t.point(2, 3).to_vec(), &[1.0, -2.0, -1.0], 1e-12));
    // length_scale scales offsets and translations.
    let s = b.world_positions(0.01, false).unwrap();
    assert!(approx(
        &s.slice(ndarray::s![1, 2, ..]).to_vec(),
        &[0.03, 0.03, 0.03],
        1e-12
    ));
}

#[test]
fn toy_errors_name_the_line() {
    let cases = [
        (
            TOY.replace(
                "Zrotation Xrotation Yrotation",
                "Zrotation Xrotation Wrotation",
            ),
            "unknown channel `Wrotation`",
        ),
        (
            TOY.replace("Frames: 3", "Frames: 4"),
            "header says 4 frames",
        ),
        (TOY.replace("Frames: 3", "Frames: 2"), "after the 2 frames"),
        (
            TOY.replace("0 0 0 0 0 0 0 0 0 0 0 90", "0 0 0 0 0 0 0 0 0 0 0 abc"),
            "frame 2, channel 11",
        ),
        (TOY.replace("OFFSET 1 0 0", "OFFSET 1 0"), "line 9"),
        (
            TOY.replace("Frame Time: 0.5", "Frame Time: 0"),
            "frame time",
        ),
        ("HIERARCHY\nMOTION\n".to_string(), "no ROOT"),
        (String::new(), "expected `HIERARCHY`"),
    ];
    for (text, needle) in cases {
        let e = Bvh::parse(&text, "bad.bvh").unwrap_err();
        assert!(matches!(e, GeomError::Format { .. }));
        assert!(
            e.to_string().contains(needle),
            "expected `{needle}` in: {e}"
        );
        assert!(e.to_string().starts_with("bad.bvh"), "{e}");
    }
    let dir = tempfile::tempdir().unwrap();
    assert!(matches!(
        Bvh::read(dir.path().join("none.bvh")),
        Err(GeomError::Io { .. })
    ));
}

#[test]
fn toy_write_slice_concat() {
    let b = Bvh::parse(TOY, "toy.bvh").unwrap();
    let again = Bvh::parse(&b.to_bvh_string(), "again.bvh").unwrap();
    assert_eq!(again, b);
    let a = b.slice_frames(0, 2).unwrap();
    let c = b.slice_frames(2, 3).unwrap();
    assert_eq!(a.concat(&c).unwrap(), b);
    assert!(b.slice_frames(2, 2).is_err());
    assert!(b.slice_frames(0, 4).is_err());
    let mut moved = b.clone();
    moved.translate_root([10.0, 0.0, -1.0]);
    assert_eq!(moved.root_channels(1), Some([11.0, 2.0, 2.0]));
    let other = Bvh::parse(&TOY.replace("JOINT lShin", "JOINT lKnee"), "o.bvh").unwrap();
    assert!(b.concat(&other).unwrap_err().to_string().contains("lShin"));
}

#[test]
fn salsa_files_forward_kinematics() {
    let Some(files) = salsa_files("salsa_files_forward_kinematics") else {
        return;
    };
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let header_frames: usize = text
            .lines()
            .find_map(|l| l.strip_prefix("Frames:"))
            .and_then(|v| v.trim().parse().ok())
            .unwrap();
        let b = Bvh::read(&path).unwrap();
        assert_eq!(b.n_frames(), header_frames, "{}", path.display());
        assert_eq!(b.joints().len(), 43);
        assert_eq!(b.n_channels(), 132);
        assert_eq!(b.frame_time_s(), 0.008333);
        assert!((b.fps() - 120.0).abs() < 0.01);
        // Subsample frames to keep the test fast; FK over the whole file runs in read_track below.
        let t = b.to_track(&BvhTrackParams::default()).unwrap();
        assert_eq!(
            (t.n_frames(), t.n_joints(), t.dims()),
            (header_frames, 43, 3)
        );
        assert_eq!(t.units(), Units::Metres);
        assert_eq!(t.skeleton().joints[0], "hip");
        assert_eq!(
            t.skeleton().joints[t.skeleton().coco17[5].unwrap()],
            "lShldr"
        );
        assert_eq!(
            t.skeleton().joints[t.skeleton().coco17[16].unwrap()],
            "rFoot"
        );
        // Root position equals the root channels (root offset is 0).
        for f in (0..t.n_frames()).step_by(97) {
            let rc = b.root_channels(f).unwrap();
            assert!(approx(&t.point(f, 0).to_vec(), &rc, 1e-12), "frame {f}");
        }
        // Every bone keeps its length (the hierarchy offset) in every frame.
        for &(p, c) in &t.skeleton().bones {
            let o = b.joints()[c].offset;
            let want = (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt();
            for f in (0..t.n_frames()).step_by(13) {
                let d: f64 = (0..3)
                    .map(|k| (t.point(f, c)[k] - t.point(f, p)[k]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!(
                    (d - want).abs() < 1e-9,
                    "{}: bone {p}->{c} frame {f}: {d} vs {want}",
                    path.display()
                );
            }
        }
        // A whole body, y up: ankles to head joint spans 1.1–1.6 m (these
        // skeletons are small: thigh 0.29 m, shin 0.35 m).
        let (lo, hi) = t.bounds().unwrap();
        assert!(
            hi[1] - lo[1] > 1.1 && hi[1] - lo[1] < 1.6,
            "height {}",
            hi[1] - lo[1]
        );
        let head = t.skeleton().joint_index("head").unwrap();
        let foot = t.skeleton().joint_index("lFoot").unwrap();
        assert!(t.point(0, head)[1] > t.point(0, foot)[1] + 1.0);
    }
}

#[test]
fn salsa_write_parse_fk_round_trip() {
    let Some(files) = salsa_files("salsa_write_parse_fk_round_trip") else {
        return;
    };
    let path = &files[0];
    let b = Bvh::read(path).unwrap();
    let part = b.slice_frames(100, 220).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("part.bvh");
    part.write_bvh(&out).unwrap();
    let back = Bvh::read(&out).unwrap();
    assert_eq!(back, part);
    let fk_back = back.world_positions(1.0, true).unwrap();
    let fk_full = b.world_positions(1.0, true).unwrap();
    assert_eq!(
        fk_back,
        fk_full.slice(ndarray::s![100..220, .., ..]).to_owned()
    );
    // Stitch two segments: frame count adds up and the seam frames are the originals.
    let a = b.slice_frames(0, 50).unwrap();
    let c = b.slice_frames(300, 360).unwrap();
    let j = a.concat(&c).unwrap();
    assert_eq!(j.n_frames(), 110);
    assert_eq!(j.motion().row(50), b.motion().row(300));
    // read_track dispatches on the extension.
    let t = read_track(&out).unwrap();
    assert_eq!((t.n_frames(), t.n_joints()), (120, 43));
    assert!((t.fps() - 1.0 / 0.008333).abs() < 1e-9);
}
