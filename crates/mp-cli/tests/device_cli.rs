//! `--device`: where the pose model runs. An unknown device is refused by
//! name; CUDA asked for on an ONNX Runtime without it (the CPU build the
//! set-up installs) is refused with the reason and how to get the GPU build;
//! `auto` (the default) and `cpu` run, and give the same keypoints.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use common::{ok, refused};

fn golf() -> String {
    mp_geom::data_file("golfdb/golf_swing.mp4")
        .expect("the shared golf swing")
        .display()
        .to_string()
}

#[test]
fn devices_are_checked_and_the_cpu_build_says_why_not_cuda() {
    let video = golf();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("k.npz");
    let out = out.to_str().unwrap();
    let err = refused(&["extract", &video, "-o", out, "--device", "tpu"]);
    assert!(err.contains("device") && err.contains("tpu"), "{err}");
    let err = refused(&["run", &video, "--out", out, "--device", "cuda:x"]);
    assert!(err.contains("device"), "{err}");
    let cuda = mp_pose::Device::cuda_available().expect("ONNX Runtime loads");
    if !cuda {
        let err = refused(&[
            "extract",
            &video,
            "-o",
            out,
            "--max-frames",
            "2",
            "--device",
            "cuda",
        ]);
        assert!(
            err.contains("cannot run on cuda:0") && err.contains("setup.sh gpu"),
            "{err}"
        );
        assert!(!std::path::Path::new(out).exists());
    }
    let mut tracks = Vec::new();
    for device in ["auto", "cpu"] {
        let path = dir.path().join(format!("{device}.npz"));
        ok(&[
            "extract",
            &video,
            "-o",
            path.to_str().unwrap(),
            "--max-frames",
            "3",
            "--device",
            device,
            "--quiet",
        ]);
        tracks.push(mp_geom::read_track(&path).unwrap());
    }
    let (a, b) = (&tracks[0], &tracks[1]);
    assert_eq!(a.n_frames(), 3);
    // On the CPU both are the same run; on a GPU within a pixel.
    let worst = (a.positions().to_owned() - b.positions())
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(worst < 1.0, "auto and cpu differ by {worst} px");
}
