//! What a command is given: frame rates that travel with the data (`--fps`,
//! a CSV `time` column, a warning when 30 fps is assumed) and, for the usual
//! mistakes, errors that name the right command.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use common::{ok, refused};

/// `period_frames` and `fps` of the first counted interval of `mp loops --json`.
fn period_s(args: &[&str]) -> f64 {
    let (out, _) = ok(args);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let fps = v["fps"].as_f64().unwrap();
    let iv = &v["repetitions"]["intervals"][0];
    let first = &iv["repetitions"][0];
    let frames = first[1].as_f64().unwrap() + 1.0 - first[0].as_f64().unwrap();
    frames / fps
}

#[test]
fn a_track_keeps_its_rate_through_csv_and_npy_takes_fps() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name).to_string_lossy().into_owned();
    ok(&["performer", "-o", &p("perf.npz")]);
    ok(&["fit", &p("perf.npz"), "-o", &p("prog.txt"), "--quiet"]);
    for ext in ["npz", "csv"] {
        ok(&[
            "execute",
            &p("prog.txt"),
            "--fps",
            "60",
            "-o",
            &p(&format!("e60.{ext}")),
        ]);
    }
    let npz = period_s(&["loops", &p("e60.npz"), "--json"]);
    let csv = period_s(&["loops", &p("e60.csv"), "--json"]);
    assert!((npz - csv).abs() < 1e-9, "npz {npz} s, csv {csv} s");
    let text = std::fs::read_to_string(p("e60.csv")).unwrap();
    assert!(text.starts_with("frame,time,"), "{}", &text[..30]);

    // A CSV without its time column states no rate: 30 fps, with a warning,
    // unless --fps says otherwise.
    let stripped: String = text
        .lines()
        .map(|l| {
            let mut f: Vec<&str> = l.split(',').collect();
            f.remove(1);
            f.join(",") + "\n"
        })
        .collect();
    std::fs::write(p("no_time.csv"), stripped).unwrap();
    let (_, err) = ok(&["loops", &p("no_time.csv")]);
    assert!(
        err.contains("30 fps assumed") && err.contains("--fps"),
        "{err}"
    );
    let assumed = period_s(&["loops", &p("no_time.csv"), "--json"]);
    assert!((assumed - 2.0 * npz).abs() < 1e-9, "{assumed} vs 2 × {npz}");
    let given = period_s(&["loops", &p("no_time.csv"), "--json", "--fps", "60"]);
    assert!((given - npz).abs() < 1e-9, "{given} vs {npz}");
    let (_, err) = ok(&["loops", &p("no_time.csv"), "--fps", "60"]);
    assert!(!err.contains("assumed"), "{err}");
}

#[test]
fn mistakes_get_the_right_advice() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name).to_string_lossy().into_owned();
    std::fs::write(p("photo.jpg"), b"not really").unwrap();
    std::fs::write(p("clip.mp4"), b"not really").unwrap();
    std::fs::write(p("README.md"), b"# notes").unwrap();
    std::fs::create_dir(p("videos")).unwrap();
    std::fs::write(p("videos/a.mp4"), b"").unwrap();
    ok(&["performer", "-o", &p("perf.npz")]);

    let e = refused(&["run", &p("photo.jpg"), "--out", &p("o")]);
    assert!(e.contains("still image") && e.contains("mp extract"), "{e}");
    let e = refused(&["run", &p("videos"), "--out", &p("o")]);
    assert!(e.contains("mp batch"), "{e}");
    let e = refused(&["fit", &p("clip.mp4"), "-o", &p("p.txt")]);
    assert!(
        e.contains("is a video") && e.contains("mp extract") && e.contains("mp run"),
        "{e}"
    );
    let e = refused(&["fit", &p("photo.jpg"), "-o", &p("p.txt")]);
    assert!(e.contains("is an image") && e.contains("mp extract"), "{e}");
    let e = refused(&["extract", &p("perf.npz"), "-o", &p("x.npz")]);
    assert!(
        e.contains("already a keypoint track") && e.contains("mp run"),
        "{e}"
    );
    let e = refused(&["run", &p("perf.npz"), "--out", &p("README.md")]);
    assert!(e.contains("README.md is a file"), "{e}");
    assert_eq!(std::fs::read_to_string(p("README.md")).unwrap(), "# notes");
}

/// `kd` of `mp stats TRACK PROGRAM --json`: how far the program is from the track.
fn kd(track: &str, program: &str) -> f64 {
    let (out, _) = ok(&["stats", track, program, "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    v["kd"].as_f64().unwrap()
}

/// The formats of other tools through the commands: a 3D track as C3D and
/// its program executed as BVH, a 2D track as Parquet and `.pose`, each read
/// back to the positions of its npz (a program's distance to them the
/// same); 2D keypoints refused for C3D and BVH with the option that gives
/// 3D ones.
#[test]
fn commands_read_and_write_c3d_bvh_parquet_and_pose() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name).to_string_lossy().into_owned();
    ok(&["performer", "--3d", "-o", &p("p3.c3d")]);
    ok(&["performer", "--3d", "-o", &p("p3.npz")]);
    ok(&["fit", &p("p3.npz"), "-o", &p("p3.txt"), "--quiet"]);
    let (c3d, npz) = (
        kd(&p("p3.c3d"), &p("p3.txt")),
        kd(&p("p3.npz"), &p("p3.txt")),
    );
    assert!((c3d - npz).abs() < 1e-6, "C3D {c3d} m, npz {npz} m");
    ok(&["fit", &p("p3.c3d"), "-o", &p("c3d.txt"), "--quiet"]);
    let (out, err) = ok(&["execute", &p("p3.txt"), "-o", &p("e3.bvh")]);
    assert!(
        out.contains("e3.bvh") || err.contains("e3.bvh"),
        "{out}{err}"
    );
    let text = std::fs::read_to_string(p("e3.bvh")).unwrap();
    assert!(text.starts_with("HIERARCHY\nROOT "), "{}", &text[..40]);
    // Read back by forward kinematics, as COCO-17, within centimetres of
    // the program it was executed from.
    let (stats, _) = ok(&["stats", &p("e3.bvh"), &p("p3.txt"), "--json"]);
    let v: serde_json::Value = serde_json::from_str(&stats).unwrap();
    assert_eq!(v["n_joints"], 17);
    assert!(v["kd"].as_f64().unwrap() < 0.02, "{stats}");

    ok(&["performer", "-o", &p("p2.npz")]);
    ok(&["fit", &p("p2.npz"), "-o", &p("p2.txt"), "--quiet"]);
    let want = std::fs::read_to_string(p("p2.txt")).unwrap();
    ok(&["performer", "-o", &p("p2.parquet")]);
    ok(&["fit", &p("p2.parquet"), "-o", &p("parquet.txt"), "--quiet"]);
    assert_eq!(std::fs::read_to_string(p("parquet.txt")).unwrap(), want);
    ok(&["performer", "-o", &p("p2.pose")]);
    let (pose, npz) = (
        kd(&p("p2.pose"), &p("p2.txt")),
        kd(&p("p2.npz"), &p("p2.txt")),
    );
    assert!((pose - npz).abs() < 1e-3, ".pose {pose} px, npz {npz} px");

    let e = refused(&["performer", "-o", &p("flat.c3d")]);
    assert!(e.contains("flat.c3d") && e.contains("3D points"), "{e}");
    std::fs::write(p("clip.mp4"), b"not really").unwrap();
    for ext in ["c3d", "bvh"] {
        let e = refused(&["extract", &p("clip.mp4"), "-o", &p(&format!("k.{ext}"))]);
        assert!(e.contains("--world"), "{e}");
    }
}
