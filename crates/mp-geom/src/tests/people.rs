//! Several tracked people: validation, the main-person rule, boxes, and the
//! npz / JSON / binary people formats (exact round trips, the single-track
//! view, corrupt and truncated input).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::io::npz::Npz;
use crate::io::people::people_to_npz_bytes;
use crate::io::people::{
    people_from_bincode, people_from_json_str, people_from_npz, people_to_bincode,
    people_to_json_string, BINARY_MAGIC, BINARY_VERSION,
};
use crate::io::{read_people, read_track, write_people, write_track};
use crate::{GeomError, People, Person, PersonId, Skeleton, Track, Units};
use ndarray::{Array2, Array3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A COCO-17 figure of `n` frames centred at `(cx, cy)`, `size` pixels
/// across, drifting a little; confidence 0 on the frames in `missing`.
fn figure(n: usize, cx: f64, cy: f64, size: f64, missing: &[usize]) -> Track {
    let p = Array3::from_shape_fn((n, 17, 2), |(t, j, k)| {
        let u = (j as f64 / 16.0 - 0.5) * size;
        let v = ((j * 7 % 17) as f64 / 16.0 - 0.5) * size;
        let drift = t as f64 * 0.25;
        if k == 0 {
            cx + u + drift
        } else {
            cy + v - drift * 0.5
        }
    });
    let mut c = Array2::from_elem((n, 17), 0.75);
    for &t in missing {
        c.row_mut(t).fill(0.0);
    }
    Track::new(p, Some(c), 30.0, Units::Pixels, Skeleton::coco17()).unwrap()
}

fn person(id: PersonId, first_frame: usize, track: Track) -> Person {
    Person {
        id,
        first_frame,
        track,
    }
}

/// Three people in a 40-frame video: a performer (id 2, large, long), a
/// passer-by (id 1, brief) and a small figure in the back (id 3).
fn crowd() -> People {
    People::new(
        40,
        30.0,
        vec![
            person(2, 3, figure(35, 320.0, 240.0, 200.0, &[4, 5])),
            person(1, 0, figure(6, 50.0, 200.0, 180.0, &[])),
            person(3, 10, figure(30, 600.0, 100.0, 20.0, &[0])),
        ],
    )
    .unwrap()
}

fn samples() -> Vec<People> {
    let metres = |n: usize| {
        let p = Array3::from_shape_fn((n, 20, 3), |(t, j, k)| {
            (t as f64 * 0.1).sin() * (j + 1) as f64 / 7.0 + k as f64 / 3.0 - 1e-300
        });
        let mut c = Array2::from_elem((n, 20), 0.5);
        c[[0, 3]] = 0.0;
        Track::new(p, Some(c), 29.97, Units::Metres, Skeleton::msr20()).unwrap()
    };
    vec![
        crowd(),
        People::from_track(figure(5, 10.0, 20.0, 5.0, &[2])).unwrap(),
        People::new(
            7,
            29.97,
            vec![person(9, 6, metres(1)), person(4, 0, metres(7))],
        )
        .unwrap(),
        People::new(12, 25.0, Vec::new()).unwrap(),
    ]
}

#[test]
fn people_are_sorted_and_looked_up_by_id() {
    let p = crowd();
    assert_eq!(p.len(), 3);
    assert!(!p.is_empty());
    assert_eq!((p.n_frames(), p.fps()), (40, 30.0));
    let ids: Vec<PersonId> = p.people().iter().map(|q| q.id).collect();
    assert_eq!(ids, vec![1, 2, 3]);
    assert_eq!(p.get(3).unwrap().first_frame, 10);
    assert!(p.get(7).is_none());
    assert_eq!(p.get(2).unwrap().last_frame(), 37);
    assert_eq!(p.get(1).unwrap().last_frame(), 5);
}

#[test]
fn found_frames_and_boxes_skip_confidence_zero() {
    let mut tr = figure(4, 0.0, 0.0, 10.0, &[1]);
    // Frame 2: only two joints found, at (1, 2) and (5, -4).
    tr.confidence_mut().row_mut(2).fill(0.0);
    tr.confidence_mut()[[2, 3]] = 0.5;
    tr.confidence_mut()[[2, 8]] = 1.0;
    tr.positions_mut()[[2, 3, 0]] = 1.0;
    tr.positions_mut()[[2, 3, 1]] = 2.0;
    tr.positions_mut()[[2, 8, 0]] = 5.0;
    tr.positions_mut()[[2, 8, 1]] = -4.0;
    // Frame 3: one joint, far away, with confidence 0 must not count.
    tr.positions_mut()[[3, 0, 0]] = 1e6;
    tr.confidence_mut()[[3, 0]] = 0.0;
    let p = person(5, 100, tr);
    assert_eq!(p.frames_found(), 3);
    assert_eq!(p.box_at(102), Some([1.0, -4.0, 5.0, 2.0]));
    assert_eq!(p.box_at(101), None, "not found on that frame");
    assert_eq!(p.box_at(99), None, "before the span");
    assert_eq!(p.box_at(104), None, "after the span");
    assert_eq!(p.last_frame(), 103);
    let b0 = p.box_at(100).unwrap();
    let b3 = p.box_at(103).unwrap();
    assert!(
        b3[2] < 1e3,
        "a joint of confidence 0 widened the box: {b3:?}"
    );
    let mean = p.mean_box().unwrap();
    let b2 = [1.0, -4.0, 5.0, 2.0];
    for k in 0..4 {
        let want = (b0[k] + b2[k] + b3[k]) / 3.0;
        assert!((mean[k] - want).abs() < 1e-12, "{k}: {mean:?} vs {want}");
    }
    let never = person(6, 0, figure(3, 0.0, 0.0, 10.0, &[0, 1, 2]));
    assert_eq!(never.frames_found(), 0);
    assert_eq!(never.mean_box(), None);
    assert_eq!(never.box_at(1), None);
}

/// A COCO-17 figure of `n` frames whose joints swing `amplitude` pixels once
/// a second around `(cx, cy)` (an exercise), plus a `jitter` that flips sign
/// every frame (keypoint noise), and walks `speed` pixels a frame.
fn mover(n: usize, cx: f64, size: f64, amplitude: f64, jitter: f64, speed: f64) -> Track {
    let p = Array3::from_shape_fn((n, 17, 2), |(t, j, k)| {
        let phase = 2.0 * std::f64::consts::PI * t as f64 / 30.0;
        let swing = amplitude * (phase + j as f64).sin();
        let noise = if (t + j) % 2 == 0 { jitter } else { -jitter };
        let u = (j as f64 / 16.0 - 0.5) * size;
        if k == 0 {
            cx + u + swing + noise + speed * t as f64
        } else {
            200.0 + (j as f64 / 16.0) * size + noise
        }
    });
    Track::new(
        p,
        Some(Array2::from_elem((n, 17), 0.8)),
        30.0,
        Units::Pixels,
        Skeleton::coco17(),
    )
    .unwrap()
}

#[test]
fn main_person_is_the_one_who_moves_most() {
    let p = crowd();
    assert_eq!(p.main_person().unwrap().id, 2);
    // A trainer standing beside the performer, larger and found as long,
    // with jittery keypoints, loses to the exercising person.
    let q = People::new(
        300,
        30.0,
        vec![
            person(1, 0, mover(300, 100.0, 250.0, 0.0, 2.0, 0.0)),
            person(2, 0, mover(300, 400.0, 150.0, 25.0, 2.0, 0.0)),
        ],
    )
    .unwrap();
    assert!(q.get(2).unwrap().activity() > 5.0 * q.get(1).unwrap().activity());
    assert_eq!(q.main_person().unwrap().id, 2);
    // A passer-by crossing the frame in a second loses to ten seconds of exercise.
    let r = People::new(
        300,
        30.0,
        vec![
            person(1, 100, mover(30, 0.0, 200.0, 0.0, 1.0, 20.0)),
            person(2, 0, mover(300, 400.0, 150.0, 25.0, 1.0, 0.0)),
        ],
    )
    .unwrap();
    assert_eq!(r.main_person().unwrap().id, 2);
    // Frames where a person was not found do not count.
    let s = People::new(
        50,
        30.0,
        vec![
            person(
                1,
                0,
                figure(50, 100.0, 100.0, 100.0, &(0..45).collect::<Vec<_>>()),
            ),
            person(2, 0, figure(20, 300.0, 300.0, 100.0, &[])),
        ],
    )
    .unwrap();
    assert_eq!(s.main_person().unwrap().id, 2);
}

#[test]
fn main_person_ties_go_to_the_smaller_id() {
    let same = || figure(10, 100.0, 100.0, 50.0, &[]);
    let p = People::new(
        20,
        30.0,
        vec![
            person(7, 5, same()),
            person(3, 0, same()),
            person(5, 10, same()),
        ],
    )
    .unwrap();
    assert_eq!(p.main_person().unwrap().id, 3);
    // Nobody found at all: every score is 0, the smallest id wins.
    let q = People::new(
        4,
        30.0,
        vec![
            person(8, 0, figure(4, 0.0, 0.0, 1.0, &[0, 1, 2, 3])),
            person(2, 1, figure(2, 0.0, 0.0, 1.0, &[0, 1])),
        ],
    )
    .unwrap();
    assert_eq!(q.main_person().unwrap().id, 2);
    let empty = People::new(3, 30.0, Vec::new()).unwrap();
    assert!(empty.main_person().is_none());
    assert!(empty.is_empty());
    assert!(matches!(empty.main_track(), Err(GeomError::NoData(_))));
}

#[test]
fn full_track_pads_with_confidence_zero() {
    let p = crowd();
    let full = p.full_track(3).unwrap();
    assert_eq!(full.n_frames(), 40);
    assert_eq!(full.fps(), 30.0);
    let own = &p.get(3).unwrap().track;
    assert_eq!(full.slice_frames(10, 40).unwrap(), *own);
    assert!(full
        .confidence()
        .slice(ndarray::s![..10, ..])
        .iter()
        .all(|&c| c == 0.0));
    assert!(full
        .positions()
        .slice(ndarray::s![..10, .., ..])
        .iter()
        .all(|&v| v == 0.0));
    assert_eq!(p.main_track().unwrap(), p.full_track(2).unwrap());
    let e = p.full_track(42).unwrap_err();
    assert!(
        matches!(e, GeomError::Unknown { kind: "person", .. }),
        "{e}"
    );
    assert!(e.to_string().contains("42"), "{e}");
}

#[test]
fn retain_min_frames_drops_brief_people() {
    let mut p = crowd();
    // Found frames: id 1 → 6, id 2 → 33, id 3 → 29.
    assert_eq!(p.retain_min_frames(6), 0);
    assert_eq!(p.retain_min_frames(30), 2);
    assert_eq!(p.len(), 1);
    assert_eq!(p.people()[0].id, 2);
}

#[test]
fn validation_errors_name_the_problem() {
    let check = |r: Result<People, GeomError>, want: &str| {
        let e = r.unwrap_err().to_string();
        assert!(e.contains(want), "expected `{want}` in `{e}`");
    };
    let fig = || figure(5, 0.0, 0.0, 10.0, &[]);
    check(
        People::new(10, 30.0, vec![person(4, 0, fig()), person(4, 5, fig())]),
        "person id 4 appears twice",
    );
    check(
        People::new(10, 30.0, vec![person(1, 6, fig())]),
        "person 1: frames 6..11 run past the video's 10 frames",
    );
    check(
        People::new(10, 30.0, vec![person(1, usize::MAX, fig())]),
        "run past",
    );
    check(People::new(0, 30.0, Vec::new()), "at least 1 frame");
    check(People::new(5, f64::NAN, Vec::new()), "fps");
    check(
        People::new(10, 25.0, vec![person(1, 0, fig())]),
        "person 1: track at 30 fps, the video at 25 fps",
    );
    let generic = Track::new(
        Array3::zeros((5, 17, 2)),
        None,
        30.0,
        Units::Pixels,
        Skeleton::generic(17),
    )
    .unwrap();
    check(
        People::new(10, 30.0, vec![person(1, 0, fig()), person(2, 0, generic)]),
        "person 2 has skeleton `generic`",
    );
    let metres = Track::new(
        Array3::zeros((5, 17, 2)),
        None,
        30.0,
        Units::Metres,
        Skeleton::coco17(),
    )
    .unwrap();
    check(
        People::new(10, 30.0, vec![person(1, 0, fig()), person(2, 0, metres)]),
        "person 2 has units `m`",
    );
    let three_d = Track::new(
        Array3::zeros((5, 17, 3)),
        None,
        30.0,
        Units::Pixels,
        Skeleton::coco17(),
    )
    .unwrap();
    check(
        People::new(10, 30.0, vec![person(1, 0, fig()), person(2, 0, three_d)]),
        "person 2 has 3 dimensions",
    );
    let empty_track = figure(0, 0.0, 0.0, 1.0, &[]);
    check(
        People::new(10, 30.0, vec![person(1, 0, empty_track.clone())]),
        "person 1: the track has no frames",
    );
    check(People::from_track(empty_track), "at least 1 frame");
    // A video longer than a whole-video track may hold (what a corrupt or
    // hostile file would ask for: the readers build through People::new).
    check(
        People::new(usize::MAX, 30.0, vec![person(1, 0, fig())]),
        "values a whole-video track may hold",
    );
    let mut json: serde_json::Value =
        serde_json::from_str(&people_to_json_string(&crowd()).unwrap()).unwrap();
    json["n_frames"] = serde_json::json!(u64::MAX);
    check(
        people_from_json_str(&json.to_string(), std::path::Path::new("people.json")),
        "values a whole-video track may hold",
    );
}

#[test]
fn every_format_round_trips_exactly() {
    let dir = tempfile::tempdir().unwrap();
    for (i, p) in samples().into_iter().enumerate() {
        for ext in ["npz", "json", "mpt", "NPZ"] {
            let path = dir.path().join(format!("p{i}.{ext}"));
            write_people(&path, &p).unwrap();
            assert_eq!(read_people(&path).unwrap(), p, "sample {i} as .{ext}");
        }
        let z = Npz::from_bytes(people_to_npz_bytes(&p).unwrap(), "mem.npz").unwrap();
        assert_eq!(people_from_npz(&z).unwrap(), p);
        let json = people_to_json_string(&p).unwrap();
        assert_eq!(people_from_json_str(&json, "mem.json".as_ref()).unwrap(), p);
        let bytes = people_to_bincode(&p).unwrap();
        assert!(bytes.starts_with(BINARY_MAGIC));
        assert_eq!(people_from_bincode(&bytes).unwrap(), p);
    }
    let e = write_people(dir.path().join("p.csv"), &crowd()).unwrap_err();
    assert!(
        e.to_string().contains("cannot write people as `csv`"),
        "{e}"
    );
}

#[test]
fn the_json_layout_is_as_documented() {
    let json = people_to_json_string(&crowd()).unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["format"], "mp-people");
    assert_eq!(v["version"], 1);
    assert_eq!(v["n_frames"], 40);
    assert_eq!(v["fps"], 30.0);
    assert_eq!(v["people"][1]["id"], 2);
    assert_eq!(v["people"][1]["first_frame"], 3);
    assert_eq!(v["people"][1]["track"]["format"], "mp-track");
    assert_eq!(
        v["people"][1]["track"]["positions"]
            .as_array()
            .unwrap()
            .len(),
        35
    );
}

#[test]
fn the_npz_layout_is_as_documented() {
    let p = crowd();
    let z = Npz::from_bytes(people_to_npz_bytes(&p).unwrap(), "mem.npz").unwrap();
    let shape = |n: &str| z.array(n).unwrap().shape;
    // Each person's frames once: 6 + 35 + 30 rows.
    assert_eq!(shape("people_positions"), vec![71, 17, 2]);
    assert_eq!(shape("people_confidence"), vec![71, 17]);
    assert_eq!(shape("positions"), vec![40, 17, 2]);
    assert_eq!(
        z.array_i64("people_ids")
            .unwrap()
            .iter()
            .copied()
            .collect::<Vec<_>>(),
        vec![1, 2, 3]
    );
    assert_eq!(
        z.array_i64("people_first_frame")
            .unwrap()
            .iter()
            .copied()
            .collect::<Vec<_>>(),
        vec![0, 3, 10]
    );
    assert_eq!(
        z.array_i64("people_frames")
            .unwrap()
            .iter()
            .copied()
            .collect::<Vec<_>>(),
        vec![6, 35, 30]
    );
    assert_eq!(z.scalar_f64("mp_people_version").unwrap(), 2.0);
    assert_eq!(z.scalar_f64("people_n_frames").unwrap(), 40.0);
    // Person 2's rows are 6..41, person 3's 41..71.
    let pos = z.array_f64("people_positions").unwrap();
    let conf = z.array_f64("people_confidence").unwrap();
    let two = &p.people()[1].track;
    let three = &p.people()[2].track;
    assert_eq!(pos.slice(ndarray::s![6..41, .., ..]), two.positions());
    assert_eq!(conf.slice(ndarray::s![41..71, ..]), three.confidence());

    // Nobody in the video.
    let empty = People::new(12, 25.0, Vec::new()).unwrap();
    let z = Npz::from_bytes(people_to_npz_bytes(&empty).unwrap(), "mem.npz").unwrap();
    assert!(!z.contains("positions"));
    assert_eq!(shape_of(&z, "people_positions"), vec![0, 0, 0]);
    assert_eq!(shape_of(&z, "people_confidence"), vec![0, 0]);
    assert_eq!(shape_of(&z, "people_ids"), vec![0]);
    assert_eq!(z.scalar_f64("fps").unwrap(), 25.0);
}

#[test]
fn a_version_1_npz_with_everyone_over_the_whole_video_still_reads() {
    // Version 1 laid every person over the whole video, 0 outside their span.
    let p = crowd();
    let (t, j, d) = (40, 17, 2);
    let mut pos = ndarray::Array4::<f64>::zeros((3, t, j, d));
    let mut conf = ndarray::Array3::<f64>::zeros((3, t, j));
    for (i, person) in p.people().iter().enumerate() {
        let span = person.first_frame..person.first_frame + person.track.n_frames();
        pos.slice_mut(ndarray::s![i, span.clone(), .., ..])
            .assign(&person.track.positions());
        conf.slice_mut(ndarray::s![i, span, ..])
            .assign(&person.track.confidence());
    }
    // The arrays besides the people's positions and confidence, at `version`.
    let archive = |version: i64| {
        let mut out = crate::io::npz::NpzOut::new(true);
        crate::io::native::add_track_arrays(&mut out, &p.main_track().unwrap()).unwrap();
        let ints = |v: Vec<i64>| ndarray::Array1::from(v);
        out.add("people_n_frames", &ndarray::arr0(t as i64))
            .unwrap();
        out.add("people_ids", &ints(vec![1, 2, 3])).unwrap();
        out.add("people_first_frame", &ints(vec![0, 3, 10]))
            .unwrap();
        out.add("people_frames", &ints(vec![6, 35, 30])).unwrap();
        out.add("mp_people_version", &ndarray::arr0(version))
            .unwrap();
        out
    };
    let mut out = archive(1);
    out.add("people_positions", &pos).unwrap();
    out.add("people_confidence", &conf).unwrap();
    let z = Npz::from_bytes(out.finish().unwrap(), "v1.npz").unwrap();
    let back = crate::io::people::people_from_npz(&z).unwrap();
    assert_eq!(back.len(), 3);
    for (a, b) in back.people().iter().zip(p.people()) {
        assert_eq!((a.id, a.first_frame), (b.id, b.first_frame));
        assert_eq!(a.track.positions(), b.track.positions());
        assert_eq!(a.track.confidence(), b.track.confidence());
    }
    // A version-2 file whose rows do not add up is refused, naming the array.
    let mut out = archive(2);
    out.add(
        "people_positions",
        &ndarray::Array3::<f64>::zeros((70, j, d)),
    )
    .unwrap();
    out.add("people_confidence", &ndarray::Array2::<f64>::zeros((70, j)))
        .unwrap();
    let z = Npz::from_bytes(out.finish().unwrap(), "short.npz").unwrap();
    let e = crate::io::people::people_from_npz(&z)
        .unwrap_err()
        .to_string();
    assert!(e.contains("people_positions"), "{e}");
}

fn shape_of(z: &Npz, n: &str) -> Vec<usize> {
    z.array(n).unwrap().shape
}

#[test]
fn read_track_gets_the_main_person() {
    let dir = tempfile::tempdir().unwrap();
    let p = crowd();
    let main = p.main_track().unwrap();
    for ext in ["npz", "json", "mpt"] {
        let path = dir.path().join(format!("people.{ext}"));
        write_people(&path, &p).unwrap();
        assert_eq!(read_track(&path).unwrap(), main, ".{ext}");
    }
    let empty = People::new(12, 25.0, Vec::new()).unwrap();
    for ext in ["npz", "json", "mpt"] {
        let path = dir.path().join(format!("nobody.{ext}"));
        write_people(&path, &empty).unwrap();
        let e = read_track(&path).unwrap_err();
        assert!(matches!(e, GeomError::Format { .. }), "{e}");
        let msg = e.to_string();
        assert!(
            msg.contains("no person in this file") && msg.contains(&format!("nobody.{ext}")),
            "{msg}"
        );
    }
}

#[test]
fn single_track_files_read_as_one_person() {
    let dir = tempfile::tempdir().unwrap();
    let tr = figure(8, 100.0, 50.0, 30.0, &[3]);
    for ext in ["npz", "json", "mpt", "csv"] {
        let path = dir.path().join(format!("one.{ext}"));
        write_track(&path, &tr).unwrap();
        let p = read_people(&path).unwrap();
        assert_eq!((p.len(), p.n_frames(), p.fps()), (1, 8, 30.0), ".{ext}");
        let only = &p.people()[0];
        assert_eq!((only.id, only.first_frame), (1, 0));
        if ext != "csv" {
            assert_eq!(only.track, tr, ".{ext}");
        }
        assert_eq!(p.main_person().unwrap().id, 1);
    }
    let e = read_people(dir.path().join("missing.npz")).unwrap_err();
    assert!(matches!(e, GeomError::Io { .. }), "{e}");
}

#[test]
fn inconsistent_npz_arrays_are_errors() {
    use crate::io::npz::NpzOut;
    let p = crowd();
    let good = Npz::from_bytes(people_to_npz_bytes(&p).unwrap(), "mem.npz").unwrap();
    // Rebuild the archive with one array replaced.
    let with = |name: &str, value: ndarray::ArrayD<i64>| {
        let mut out = NpzOut::new(false);
        for n in good.names() {
            if n == name {
                out.add(n, &value).unwrap();
            } else if let Ok(a) = good.array_i64(n) {
                out.add(n, &a).unwrap();
            } else if let Ok(a) = good.array_f64(n) {
                out.add(n, &a).unwrap();
            } else {
                let a = good.array(n).unwrap();
                out.add_strings(n, &a.to_strings().unwrap(), &a.shape)
                    .unwrap();
            }
        }
        let z = Npz::from_bytes(out.finish().unwrap(), "bad.npz").unwrap();
        people_from_npz(&z).unwrap_err().to_string()
    };
    let v = |x: Vec<i64>| ndarray::ArrayD::from_shape_vec(vec![x.len()], x).unwrap();
    let s = |x: i64| ndarray::ArrayD::from_elem(vec![], x);
    let e = with("people_ids", v(vec![1, 2, 2]));
    assert!(
        e.contains("bad.npz") && e.contains("person id 2 appears twice"),
        "{e}"
    );
    let e = with("people_ids", v(vec![1, 2, -3]));
    assert!(e.contains("person id -3"), "{e}");
    let e = with("people_frames", v(vec![6, 38, 30]));
    assert!(e.contains("do not lie within the video's 40 frames"), "{e}");
    let e = with("people_frames", v(vec![6, 0, 30]));
    assert!(e.contains("person 2"), "{e}");
    let e = with("people_first_frame", v(vec![0, 3]));
    assert!(e.contains("people_first_frame"), "{e}");
    let e = with("people_n_frames", s(41));
    assert!(e.contains("`positions` has 40 frames"), "{e}");
    let e = with("people_n_frames", s(0));
    assert!(e.contains("at least 1 frame"), "{e}");
    let e = with("mp_people_version", s(3));
    assert!(e.contains("version 3 is not supported"), "{e}");
    // Spans that ask for more rows than the arrays hold.
    let e = with("people_frames", v(vec![6, 35, 29]));
    assert!(e.contains("people_positions"), "{e}");
}

#[test]
fn json_errors_name_the_person() {
    let json = people_to_json_string(&crowd()).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&json).unwrap();
    v["people"][2]["track"]["confidence"] = serde_json::json!([[1.0]]);
    let e = people_from_json_str(&v.to_string(), "x.json".as_ref())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("x.json: person 3: confidence has 1 frames"),
        "{e}"
    );
    let mut v: serde_json::Value = serde_json::from_str(&json).unwrap();
    v["version"] = 2.into();
    let e = people_from_json_str(&v.to_string(), "x.json".as_ref())
        .unwrap_err()
        .to_string();
    assert!(e.contains("version 2 is not supported"), "{e}");
    let mut v: serde_json::Value = serde_json::from_str(&json).unwrap();
    v["n_frames"] = 20.into();
    let e = people_from_json_str(&v.to_string(), "x.json".as_ref())
        .unwrap_err()
        .to_string();
    assert!(e.contains("run past the video's 20 frames"), "{e}");
}

#[test]
fn every_binary_truncation_is_an_error() {
    for p in samples() {
        let bytes = people_to_bincode(&p).unwrap();
        for n in 0..bytes.len() {
            let e = people_from_bincode(&bytes[..n]).unwrap_err();
            assert!(matches!(e, GeomError::Format { .. }), "{n}: {e}");
            let msg = e.to_string();
            assert!(
                msg.contains("truncated") || msg.contains("does not start with"),
                "cut at {n} of {}: {msg}",
                bytes.len()
            );
        }
        let mut long = bytes.clone();
        long.push(0);
        assert!(people_from_bincode(&long)
            .unwrap_err()
            .to_string()
            .contains("1 bytes after the end"));
    }
    // A track file is not a people file, nor the other way round.
    let tr = crate::track_to_bincode(&figure(2, 0.0, 0.0, 1.0, &[])).unwrap();
    let e = people_from_bincode(&tr).unwrap_err().to_string();
    assert!(e.contains("not an mp-people binary"), "{e}");
    let pb = people_to_bincode(&crowd()).unwrap();
    let e = crate::track_from_bincode(&pb).unwrap_err().to_string();
    assert!(e.contains("not an mp-track binary"), "{e}");
    let mut newer = pb.clone();
    let at = BINARY_MAGIC.len();
    newer[at..at + 4].copy_from_slice(&(BINARY_VERSION + 1).to_le_bytes());
    let e = people_from_bincode(&newer).unwrap_err().to_string();
    assert!(e.contains("version 2 is not supported"), "{e}");
}

#[test]
fn corrupt_binary_bytes_never_panic() {
    let bytes = people_to_bincode(&samples()[2]).unwrap();
    for i in 0..bytes.len() {
        for flip in [0x01u8, 0x80, 0xff] {
            let mut b = bytes.clone();
            b[i] ^= flip;
            // Either an error or people that passed every check.
            if let Ok(p) = people_from_bincode(&b) {
                assert!(p.n_frames() >= 1 && p.fps().is_finite() && p.fps() > 0.0);
                for q in p.people() {
                    assert!(q.track.positions().iter().all(|v| v.is_finite()));
                    assert!(q.first_frame + q.track.n_frames() <= p.n_frames());
                }
            }
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let header: Vec<u8> = BINARY_MAGIC
        .iter()
        .copied()
        .chain(BINARY_VERSION.to_le_bytes())
        .collect();
    for i in 0..2000 {
        let n = rng.random_range(0..400);
        let mut b: Vec<u8> = (0..n).map(|_| rng.random()).collect();
        assert!(people_from_bincode(&b).is_err());
        b.splice(0..0, header.iter().copied());
        let _ = people_from_bincode(&b);
        if i % 2 == 0 {
            // Behind a valid header and a plausible start.
            let mut start = header.clone();
            start.push(10);
            start.extend_from_slice(&30.0f64.to_le_bytes());
            start.push(rng.random_range(0..3));
            b.splice(0..header.len(), start);
            let _ = people_from_bincode(&b);
        }
    }
}

#[test]
fn corrupt_npz_and_json_never_panic() {
    let p = samples()[2].clone();
    let npz = people_to_npz_bytes(&p).unwrap();
    let json = people_to_json_string(&p).unwrap().into_bytes();
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for _ in 0..300 {
        let mut a = npz.clone();
        for _ in 0..rng.random_range(1..4) {
            let i = rng.random_range(0..a.len());
            a[i] ^= 1 << rng.random_range(0..8);
        }
        if let Ok(z) = Npz::from_bytes(a, "fuzz.npz") {
            let _ = people_from_npz(&z);
        }
        let mut b = json.clone();
        let i = rng.random_range(0..b.len());
        b[i] = b"0123456789-.,[]{}\"e"[rng.random_range(0..19)];
        if let Ok(s) = std::str::from_utf8(&b) {
            let _ = people_from_json_str(s, "fuzz.json".as_ref());
        }
    }
}
