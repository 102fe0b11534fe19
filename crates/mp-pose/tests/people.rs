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

/// OpenCV's pedestrian scene (`vtest.avi`, 768 × 576, 10 fps; fetched by the
/// set-up from Debian's opencv-doc): a lamp post with a sign, a tripod and
/// traffic cones among people walking past. The first 6 s.
#[test]
fn a_street_scene_tracks_the_pedestrians_and_nothing_on_the_lamp_post_or_the_tripod() {
    let test = mp_geom::test_support::current_test_name();
    let Some(video) = mp_geom::test_support::footage_file_or_skip("vtest.avi", &test) else {
        return;
    };
    let mut est = MultiPose::new(MultiPoseParams::default()).expect("models open");
    let ex = extract_people(
        open_source(&video).expect("video opens"),
        &mut est,
        &ExtractOptions {
            max_frames: Some(60),
            ..Default::default()
        },
        |_, _| {},
    )
    .expect("extraction runs");
    let people = &ex.people;
    assert_eq!(people.n_frames(), 60);
    // The three people on the first frame (the centre of their joints,
    // read off the picture), each found under one id over its first 1.5 s.
    for (x, y) in [(514.0, 186.0), (267.0, 253.0), (660.0, 272.0)] {
        let near = |p: &&mp_geom::Person, f: usize| {
            p.box_at(f).is_some_and(|b| {
                let (cx, cy) = ((b[0] + b[2]) / 2.0, (b[1] + b[3]) / 2.0);
                (cx - x).hypot(cy - y) < 40.0
            })
        };
        let who: Vec<_> = people.people().iter().filter(|p| near(p, 2)).collect();
        assert_eq!(who.len(), 1, "one person at ({x}, {y}) on frame 2");
        let covered = (0..15).filter(|&f| who[0].box_at(f).is_some()).count();
        assert!(
            covered >= 13,
            "person at ({x}, {y}): {covered} of 15 frames"
        );
    }
    // Nobody on the objects: no pose box lies half inside the lamp post's
    // pole, the tripod in the grass or the tripod behind the cones.
    let objects = [
        ("pole", [410.0, 20.0, 445.0, 185.0]),
        ("tripod", [455.0, 335.0, 528.0, 485.0]),
        ("far tripod", [428.0, 112.0, 468.0, 182.0]),
    ];
    for p in people.people() {
        for f in p.first_frame..=p.last_frame() {
            let Some(b) = p.box_at(f) else { continue };
            for (name, o) in objects {
                let ix = (b[2].min(o[2]) - b[0].max(o[0])).max(0.0);
                let iy = (b[3].min(o[3]) - b[1].max(o[1])).max(0.0);
                let area = (b[2] - b[0]) * (b[3] - b[1]);
                assert!(
                    ix * iy < 0.5 * area,
                    "person {} on the {name} on frame {f}: box {b:?}",
                    p.id
                );
            }
        }
    }
    // People walk: every person found for 2 s or more moves.
    for p in people.people().iter().filter(|p| p.frames_found() >= 20) {
        let (a, b) = (
            p.box_at(p.first_frame).unwrap(),
            p.box_at(p.last_frame()).unwrap(),
        );
        let moved = ((a[0] + a[2]) / 2.0 - (b[0] + b[2]) / 2.0)
            .hypot((a[1] + a[3]) / 2.0 - (b[1] + b[3]) / 2.0);
        assert!(moved > 20.0, "person {} stays put ({moved:.0} px)", p.id);
    }
}
