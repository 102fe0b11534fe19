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

/// A video tracked in two pieces side by side gives the people of the
/// one-piece pass: the same people, numbered alike, their keypoints where
/// both passes follow them within a few pixels; and the same frames for the
/// report, each copied by the decoder of the piece it falls in.
#[test]
fn a_video_in_two_pieces_gives_the_people_of_one_pass() {
    let dir = tempfile::tempdir().unwrap();
    let Some(video) = two_panels(dir.path(), 10.0) else {
        return;
    };
    let pass = |pieces: usize| {
        let mut params = Params::default();
        params.pose.pieces = pieces;
        // Every 28th frame shown: few enough to be copied while decoding.
        params.output.report_frames = 10;
        let keep = mp_pipeline::Keep {
            report_frames: true,
            ..mp_pipeline::Keep::default()
        };
        let input = Input::open(&video, None).unwrap();
        mp_pipeline::keypoints(input, &params, keep, &Silent, &CancelToken::new())
            .unwrap()
            .0
    };
    let (one, two) = (pass(1), pass(2));
    let (a, b) = (one.people.as_ref().unwrap(), two.people.as_ref().unwrap());
    // 027_fitness ends after 277 frames.
    let n = a.n_frames();
    assert!(n > 250, "{n} frames");
    assert_eq!(b.n_frames(), n);
    let shown = |k: &mp_pipeline::Keypoints| -> Vec<usize> {
        let store = k.frames.as_ref().unwrap();
        assert!(store.frames.iter().all(|(_, j)| j.len() > 1000));
        store.frames.iter().map(|(i, _)| *i).collect()
    };
    let step = n.div_ceil(10);
    assert_eq!(shown(&one), (0..n).step_by(step).collect::<Vec<_>>());
    assert_eq!(shown(&two), shown(&one));
    let long = |p: &mp_geom::People| -> Vec<(u32, usize)> {
        p.people()
            .iter()
            .filter(|q| q.frames_found() > n / 2)
            .map(|q| (q.id, q.frames_found()))
            .collect()
    };
    let (la, lb) = (long(a), long(b));
    assert_eq!(la.len(), 2, "{la:?}");
    assert_eq!(
        la.iter().map(|x| x.0).collect::<Vec<_>>(),
        lb.iter().map(|x| x.0).collect::<Vec<_>>(),
        "{la:?} vs {lb:?}"
    );
    for ((id, fa), (_, fb)) in la.iter().zip(&lb) {
        assert!(
            fa.abs_diff(*fb) <= 10,
            "person {id}: found in {fa} and {fb} frames"
        );
        let (p, q) = (a.get(*id).unwrap(), b.get(*id).unwrap());
        let mut d = Vec::new();
        for f in 0..n {
            let (Some(tp), Some(tq)) = (
                f.checked_sub(p.first_frame)
                    .filter(|&t| t < p.track.n_frames()),
                f.checked_sub(q.first_frame)
                    .filter(|&t| t < q.track.n_frames()),
            ) else {
                continue;
            };
            for j in 0..p.track.n_joints() {
                if p.track.confidence()[[tp, j]] > 0.5 && q.track.confidence()[[tq, j]] > 0.5 {
                    let (pp, qp) = (p.track.positions(), q.track.positions());
                    d.push(
                        (pp[[tp, j, 0]] - qp[[tq, j, 0]]).hypot(pp[[tp, j, 1]] - qp[[tq, j, 1]]),
                    );
                }
            }
        }
        d.sort_by(f64::total_cmp);
        assert!(d.len() > 2000, "person {id}: {} joints compared", d.len());
        let median = d[d.len() / 2];
        assert!(
            median < 2.0,
            "person {id}: median {median:.2} px between the passes"
        );
    }
}
