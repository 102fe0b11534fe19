//! Several people in one video through `mp run`'s pipeline: two real
//! exercising people side by side, each with their own count and programs,
//! the main person at the top level, and the choice of person.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::{Path, PathBuf};
use std::process::Command;

use mp_geom::CancelToken;
use mp_pipeline::{analyse_input, run, Input, Params, PersonChoice, Silent};

fn data(rel: &str) -> Option<PathBuf> {
    mp_geom::test_support::data_file_or_skip(rel, &mp_geom::test_support::current_test_name())
}

/// 020_fitness (left, 5 squat-jumps) and 027_fitness (right) side by side,
/// 360 px high, 30 fps, the first `seconds`.
fn two_panels(dir: &Path, seconds: f64) -> Option<PathBuf> {
    let a = data("quva_repetition/videos/020_fitness.mp4")?;
    let b = data("quva_repetition/videos/027_fitness.mp4")?;
    let out = dir.join("two.mp4");
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(&a)
        .arg("-i")
        .arg(&b)
        .args([
            "-filter_complex",
            "[0:v]fps=30,scale=-2:360,setsar=1[a];[1:v]fps=30,scale=-2:360,setsar=1[b];[a][b]hstack=inputs=2[v]",
            "-map",
            "[v]",
            "-t",
            &seconds.to_string(),
            "-c:v",
            "libx264",
            "-preset",
            "veryfast",
            "-pix_fmt",
            "yuv420p",
        ])
        .arg(&out)
        .status()
        .expect("ffmpeg runs");
    assert!(status.success());
    Some(out)
}

#[test]
fn each_person_gets_their_own_programs_and_count() {
    let dir = tempfile::tempdir().unwrap();
    let Some(video) = two_panels(dir.path(), 4.0) else {
        return;
    };
    let out_dir = dir.path().join("out");
    let mut params = Params::default();
    params.output.report = false;
    params.output.overlay_video = false;
    let s = run(
        Input::open(&video, None).unwrap(),
        &out_dir,
        &params,
        &Silent,
        &CancelToken::new(),
    )
    .unwrap();
    let o = &s.outcome;
    let long: Vec<_> = o.people.iter().filter(|p| p.counts.is_some()).collect();
    assert_eq!(
        long.len(),
        2,
        "two people analysed: {:?}",
        o.people
            .iter()
            .map(|p| (p.id, p.frames_found))
            .collect::<Vec<_>>()
    );
    let main = long.iter().find(|p| p.main).expect("one main person");
    assert_eq!(o.keypoints.person, Some(main.id));
    // The main person's entry is the top level's count.
    assert_eq!(main.counts.as_ref().unwrap().total, o.counts.total);
    // One person per half.
    let centres: Vec<f64> = long
        .iter()
        .map(|p| {
            let b = p.mean_box.unwrap();
            (b[0] + b[2]) / 2.0
        })
        .collect();
    assert!(
        centres.iter().any(|&c| c < 640.0) && centres.iter().any(|&c| c >= 640.0),
        "{centres:?}"
    );
    // loops.json lists both; the other person's programs are in people/<id>/.
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("loops.json")).unwrap()).unwrap();
    assert_eq!(v["person"].as_u64(), Some(main.id as u64));
    let listed = v["people"].as_array().unwrap();
    assert!(listed.len() >= 2);
    let other = long.iter().find(|p| !p.main).unwrap();
    let entry = listed
        .iter()
        .find(|e| e["id"].as_u64() == Some(other.id as u64))
        .unwrap();
    assert_eq!(
        entry["repetitions"]["total"].as_u64().unwrap() as usize,
        other.counts.as_ref().unwrap().total
    );
    assert_eq!(entry["box"].as_array().unwrap().len(), 4);
    for f in ["program.txt", "abstract.txt"] {
        assert!(
            out_dir.join(format!("people/{}/{f}", other.id)).is_file(),
            "{f}"
        );
    }
    // track.npz holds everyone along a person axis and reads back as people.
    let people = mp_geom::read_people(out_dir.join("track.npz")).unwrap();
    assert_eq!(people.len(), o.people.len());
    let main_track = mp_geom::read_track(out_dir.join("track.npz")).unwrap();
    assert_eq!(main_track.n_frames(), o.keypoints.track.n_frames());

    // Asking for the other person puts them at the top level, alone.
    let mut one = Params::default();
    one.person.choice = PersonChoice::Id(other.id);
    let o2 = analyse_input(
        Input::open(&video, None).unwrap(),
        &one,
        &Silent,
        &CancelToken::new(),
    )
    .unwrap();
    assert_eq!(o2.keypoints.person, Some(other.id));
    assert!(o2
        .people
        .iter()
        .filter(|p| p.counts.is_some())
        .all(|p| p.id == other.id));

    // An id nobody has is a clear error.
    one.person.choice = PersonChoice::Id(99);
    let err = analyse_input(
        Input::open(&video, None).unwrap(),
        &one,
        &Silent,
        &CancelToken::new(),
    )
    .err()
    .expect("no person 99");
    assert!(err.to_string().contains("no person 99"), "{err}");
}

#[test]
fn the_person_choice_is_parsed_with_a_clear_error() {
    assert_eq!(PersonChoice::parse("all").unwrap(), PersonChoice::All);
    assert_eq!(PersonChoice::parse("Main").unwrap(), PersonChoice::Main);
    assert_eq!(PersonChoice::parse("3").unwrap(), PersonChoice::Id(3));
    let err = PersonChoice::parse("bob").unwrap_err().to_string();
    assert!(err.contains("all, main or a person's id"), "{err}");
    let mut p = Params::default();
    p.person.choice = PersonChoice::Id(0);
    assert!(p.validate().is_err());
    p = Params::default();
    p.person.min_seen_s = f64::NAN;
    assert!(p.validate().is_err());
}
