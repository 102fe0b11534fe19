//! Frame rates and frame sizes travel with the data: the rate a file states
//! (a CSV `time` column, the project's formats), the rate a caller gives,
//! the rate assumed when neither says (reported as such), and the video
//! frame an npz's pixels are in.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::io::native::write_track_npy;
use crate::io::{
    read_people_with, read_track_rated, write_people_framed, write_track, write_track_framed,
    RateSource, ReadOptions, DEFAULT_FPS,
};
use crate::People;
use crate::{Skeleton, Track, Units};
use ndarray::Array3;

fn track(fps: f64) -> Track {
    let p = Array3::from_shape_fn((40, 17, 2), |(t, j, k)| {
        100.0 + 30.0 * ((t as f64) * 0.3 + j as f64).sin() + k as f64
    });
    Track::new(p, None, fps, Units::Pixels, Skeleton::coco17()).unwrap()
}

fn given(fps: f64) -> ReadOptions {
    ReadOptions {
        fps: Some(fps),
        ..Default::default()
    }
}

#[test]
fn csv_states_its_rate_in_a_time_column() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("t60.csv");
    write_track(&f, &track(60.0)).unwrap();
    let text = std::fs::read_to_string(&f).unwrap();
    assert!(text.starts_with("frame,time,"), "{}", &text[..40]);
    let r = read_track_rated(&f, &ReadOptions::default()).unwrap();
    let (t, src) = (r.track, r.rate);
    assert_eq!((t.fps(), src), (60.0, RateSource::File));
    // A rate given by the caller wins over the file's.
    let r = read_track_rated(&f, &given(25.0)).unwrap();
    let (t, src) = (r.track, r.rate);
    assert_eq!((t.fps(), src), (25.0, RateSource::Given));
}

#[test]
fn long_csv_time_column_and_hand_written_times() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("long.csv");
    // Times to the millisecond at 29.97 fps (NTSC), two joints per frame.
    let mut s = String::from("frame,joint,x,y,time\n");
    for fr in 0..300 {
        let time = format!("{:.3}", fr as f64 / 29.97);
        for j in 0..2 {
            s.push_str(&format!("{fr},{j},{},{},{time}\n", fr + j, 2 * fr));
        }
    }
    std::fs::write(&f, s).unwrap();
    let r = read_track_rated(&f, &ReadOptions::default()).unwrap();
    let (t, src) = (r.track, r.rate);
    assert_eq!(src, RateSource::File);
    assert!((t.fps() - 29.97).abs() < 0.01, "{}", t.fps());
}

#[test]
fn times_that_go_back_are_an_error_naming_the_column() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("bad.csv");
    std::fs::write(&f, "frame,time,a_x,a_y\n0,0.0,1,2\n1,0.5,1,2\n2,0.25,1,2\n").unwrap();
    let e = read_track_rated(&f, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("`time`") && e.contains("frame 2"), "{e}");
}

#[test]
fn formats_without_a_rate_report_the_assumed_one() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("a.npy");
    write_track_npy(&f, &track(50.0)).unwrap();
    let r = read_track_rated(&f, &ReadOptions::default()).unwrap();
    let (t, src) = (r.track, r.rate);
    assert_eq!((t.fps(), src), (DEFAULT_FPS, RateSource::Assumed));
    let r = read_track_rated(&f, &given(50.0)).unwrap();
    let (t, src) = (r.track, r.rate);
    assert_eq!((t.fps(), src), (50.0, RateSource::Given));
    // A CSV without a time column states none either.
    let c = dir.path().join("no_time.csv");
    std::fs::write(&c, "frame,a_x,a_y\n0,1,2\n1,2,3\n").unwrap();
    let r = read_track_rated(&c, &ReadOptions::default()).unwrap();
    let (t, src) = (r.track, r.rate);
    assert_eq!((t.fps(), src), (DEFAULT_FPS, RateSource::Assumed));
}

#[test]
fn the_projects_formats_keep_their_rate_and_people_take_a_given_one() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["npz", "json", "mpt"] {
        let f = dir.path().join(format!("t.{ext}"));
        write_track(&f, &track(120.0)).unwrap();
        let r = read_track_rated(&f, &ReadOptions::default()).unwrap();
        let (t, src) = (r.track, r.rate);
        assert_eq!((t.fps(), src), (120.0, RateSource::File), "{ext}");
        let p = read_people_with(&f, &given(24.0)).unwrap();
        assert_eq!(p.fps(), 24.0, "{ext}");
        assert!(p.people().iter().all(|q| q.track.fps() == 24.0), "{ext}");
    }
}

#[test]
fn npz_files_keep_the_video_frame_they_are_in() {
    let dir = tempfile::tempdir().unwrap();
    let t = track(30.0);
    let (a, b, c) = (
        dir.path().join("a.npz"),
        dir.path().join("b.npz"),
        dir.path().join("c.npz"),
    );
    write_track_framed(&a, &t, Some((640, 360))).unwrap();
    write_people_framed(
        &b,
        &People::from_track(t.clone()).unwrap(),
        Some((1920, 1080)),
    )
    .unwrap();
    write_track(&c, &t).unwrap();
    let frame = |f: &std::path::Path| {
        read_track_rated(f, &ReadOptions::default())
            .unwrap()
            .frame_size
    };
    assert_eq!(frame(&a), Some((640, 360)));
    assert_eq!(frame(&b), Some((1920, 1080)));
    assert_eq!(frame(&c), None);
    // The track itself reads as before.
    let back = read_track_rated(&a, &ReadOptions::default()).unwrap().track;
    assert_eq!(back, t);
    // Other formats state no frame.
    let j = dir.path().join("a.json");
    write_track_framed(&j, &t, Some((640, 360))).unwrap();
    assert_eq!(frame(&j), None);
}
