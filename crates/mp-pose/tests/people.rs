//! Several people: real footage of one person per panel, put side by side
//! with FFmpeg, through the multi-person estimator and its tracker.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use mp_pose::{
    extract_people, open_source, ExtractOptions, MultiPose, MultiPoseParams, PeopleParams,
};

/// `inputs` side by side, each scaled to 360 px high at 30 fps, the first
/// `seconds` of them; `None` (skip recorded) without the shared data.
fn panels(dir: &Path, name: &str, inputs: &[&str], seconds: f64) -> Option<PathBuf> {
    let mut paths = Vec::new();
    for stem in inputs {
        paths.push(common::data(&format!("quva_repetition/videos/{stem}.mp4"))?);
    }
    let out = dir.join(name);
    let mut cmd = Command::new("ffmpeg");
    cmd.args(["-v", "error", "-y"]);
    for p in &paths {
        cmd.arg("-i").arg(p);
    }
    let mut filter: Vec<String> = (0..paths.len())
        .map(|k| format!("[{k}:v]fps=30,scale=-2:360,setsar=1[p{k}]"))
        .collect();
    let ins: String = (0..paths.len()).map(|k| format!("[p{k}]")).collect();
    filter.push(format!("{ins}hstack=inputs={}[v]", paths.len()));
    let status = cmd
        .args(["-filter_complex", &filter.join(";"), "-map", "[v]"])
        .args([
            "-t",
            &seconds.to_string(),
            "-c:v",
            "libx264",
            "-preset",
            "veryfast",
            "-crf",
            "20",
        ])
        .args(["-pix_fmt", "yuv420p"])
        .arg(&out)
        .status()
        .expect("ffmpeg runs");
    assert!(status.success(), "ffmpeg made {name}");
    Some(out)
}

fn run(video: &Path, people: PeopleParams) -> mp_pose::PeopleExtraction {
    let mut est = MultiPose::new(MultiPoseParams {
        people,
        ..Default::default()
    })
    .expect("models open");
    extract_people(
        open_source(video).expect("video opens"),
        &mut est,
        &ExtractOptions::default(),
        |_, _| {},
    )
    .expect("extraction runs")
}

#[test]
fn two_exercising_people_side_by_side_get_one_id_each_for_the_whole_clip() {
    let dir = tempfile::tempdir().unwrap();
    let Some(video) = panels(dir.path(), "two.mp4", &["020_fitness", "027_fitness"], 3.0) else {
        return;
    };
    let ex = run(&video, PeopleParams::default());
    let people = &ex.people;
    let n = people.n_frames();
    assert_eq!(n, 90);
    // Each half holds one person found on at least 80 % of the frames.
    for half in 0..2 {
        let (x0, x1) = (640.0 * half as f64, 640.0 * (half + 1) as f64);
        let inside: Vec<_> = people
            .people()
            .iter()
            .filter(|p| {
                let b = p.mean_box().unwrap();
                let c = (b[0] + b[2]) / 2.0;
                c >= x0 && c < x1 && p.frames_found() as f64 >= 0.8 * n as f64
            })
            .collect();
        assert_eq!(
            inside.len(),
            1,
            "half {half}: {:?}",
            people
                .people()
                .iter()
                .map(|p| (p.id, p.mean_box(), p.frames_found()))
                .collect::<Vec<_>>()
        );
    }
    // No other person for long (a crop on the gym's machines would be).
    for p in people.people() {
        assert!(
            p.frames_found() as f64 >= 0.8 * n as f64 || p.frames_found() < 15,
            "person {} found on {} frames",
            p.id,
            p.frames_found()
        );
    }
    assert!(ex.warning().is_none());
    // Ids are 1, 2, … in order of appearance.
    let ids: Vec<u32> = people.people().iter().map(|p| p.id).collect();
    assert_eq!(ids, (1..=ids.len() as u32).collect::<Vec<_>>());
}

#[test]
fn more_people_than_max_people_are_tracked_up_to_the_limit_with_a_message() {
    let dir = tempfile::tempdir().unwrap();
    let Some(video) = panels(
        dir.path(),
        "three.mp4",
        &["020_fitness", "027_fitness", "038_monkey_bars"],
        1.0,
    ) else {
        return;
    };
    let ex = run(
        &video,
        PeopleParams {
            max_people: 2,
            ..Default::default()
        },
    );
    // Never more than two people on a frame.
    assert!(
        ex.people_per_frame.iter().all(|&k| k <= 2),
        "{:?}",
        ex.people_per_frame
    );
    assert!(ex.people_per_frame.iter().filter(|&&k| k == 2).count() > 20);
    let w = ex.warning().expect("a message about the people left out");
    assert!(w.contains("max_people = 2"), "{w}");
    assert!(ex.most_seen >= 3);
}

#[test]
fn a_video_with_nobody_gives_no_person() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("empty.mp4");
    let status = Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-y",
            "-f",
            "lavfi",
            "-i",
            "testsrc2=size=640x360:rate=30:duration=1",
        ])
        .args([
            "-c:v", "libx264", "-preset", "veryfast", "-pix_fmt", "yuv420p",
        ])
        .arg(&video)
        .status()
        .expect("ffmpeg runs");
    assert!(status.success());
    let ex = run(&video, PeopleParams::default());
    assert_eq!(ex.people.n_frames(), 30);
    assert!(
        ex.people.is_empty(),
        "{:?}",
        ex.people.people().iter().map(|p| p.id).collect::<Vec<_>>()
    );
    assert_eq!(ex.found_fraction(), 0.0);
}

#[test]
fn tracker_parameters_are_checked_before_the_models_open() {
    let bad = MultiPoseParams {
        people: PeopleParams {
            max_people: 0,
            ..Default::default()
        },
        ..Default::default()
    };
    let err = MultiPose::new(bad).err().expect("refused");
    assert!(err.to_string().contains("max_people"), "{err}");
}
