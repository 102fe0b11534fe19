//! `mp overlay`: a track's skeleton drawn on its video with the renderer of
//! `mp run`'s overlay and report, as a contact sheet or a video.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use common::{ok, refused};

#[test]
fn overlay_draws_the_track_on_a_contact_sheet_and_a_video() {
    let Some(video) = mp_geom::test_support::data_file_or_skip(
        "golfdb/golf_swing.mp4",
        &mp_geom::test_support::current_test_name(),
    ) else {
        return;
    };
    let video = video.display().to_string();
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name).to_string_lossy().into_owned();
    ok(&[
        "extract",
        &video,
        "-o",
        &p("track.npz"),
        "--max-frames",
        "20",
        "--single-person",
        "--quiet",
    ]);
    let track = p("track.npz");
    let sheet = |name: &str, extra: &[&str]| {
        let mut args = vec!["overlay", video.as_str(), track.as_str()];
        let out = p(name);
        args.extend_from_slice(&[
            "-o",
            &out,
            "--frames",
            "6",
            "--cols",
            "3",
            "--tile-width",
            "160",
        ]);
        args.extend_from_slice(extra);
        ok(&args);
        image::open(p(name)).unwrap().to_rgb8()
    };
    let drawn = sheet("sheet.png", &[]);
    let bare = sheet("bare.png", &["--min-confidence", "1.0"]);
    // Three columns of 160-pixel tiles with 8-pixel gaps; two rows under the title.
    let src = mp_pose::open_source(&video).unwrap();
    let tile_h = (160.0 * src.height as f64 / src.width as f64).round() as u32;
    assert_eq!(
        drawn.dimensions(),
        (3 * 160 + 4 * 8, 40 + 2 * tile_h + 3 * 8)
    );
    assert_eq!(bare.dimensions(), drawn.dimensions());
    // The skeleton changes pixels; with every joint below the threshold, nothing is drawn.
    let changed = drawn
        .pixels()
        .zip(bare.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(changed > 500, "only {changed} pixels differ");

    let (out, _) = ok(&[
        "overlay",
        &video,
        &p("track.npz"),
        "-o",
        &p("overlay.mp4"),
        "--quiet",
    ]);
    assert!(out.is_empty());
    assert!(std::fs::metadata(p("overlay.mp4")).unwrap().len() > 10_000);
    let err = refused(&["overlay", &video, &p("track.npz"), "-o", &p("x.gif")]);
    assert!(err.contains("must be .png or .mp4"), "{err}");
}
