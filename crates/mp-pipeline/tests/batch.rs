//! `mp_pipeline::batch` on folders and lists of procedural-performer tracks:
//! one output folder per input equal to what `run` writes, a corrupt input
//! that fails alone, resume, several jobs at once, cancellation, and one real
//! video when the shared data is present.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use mp_geom::{perform, CancelToken, Move, PerformerParams};
use mp_pipeline::{
    analyse_input, batch, batch_items, run, BatchObserver, BatchParams, Input, ItemReport,
    ItemStatus, OutputParams, Params, SharedModel, Silent, Stage,
};

/// A short routine of the procedural performer (2D, pixels).
fn write_performer(path: &Path, seed: u64, squats: usize) {
    let perf = perform(&PerformerParams {
        moves: vec![(Move::JumpingJack, 4), (Move::Squat, squats)],
        seed,
        ..PerformerParams::default()
    })
    .unwrap();
    mp_geom::write_track(path, &perf.track_2d).unwrap();
}

/// Programs and counts only: the batch logic does not depend on the pictures.
fn quick_params() -> BatchParams {
    BatchParams {
        params: Params {
            output: OutputParams {
                report: false,
                overlay_video: false,
                ..OutputParams::default()
            },
            ..Params::default()
        },
        ..BatchParams::default()
    }
}

/// `a.npz`, `b.json` and a corrupt `c.npz`, plus files a batch must not list.
fn track_folder(dir: &Path) -> PathBuf {
    let input = dir.join("tracks");
    std::fs::create_dir_all(input.join("sub")).unwrap();
    write_performer(&input.join("a.npz"), 1, 3);
    write_performer(&input.join("b.json"), 2, 4);
    std::fs::write(input.join("c.npz"), b"this is not a zip archive").unwrap();
    std::fs::write(input.join(".hidden.npz"), b"x").unwrap();
    std::fs::write(input.join("notes.txt"), b"not an input").unwrap();
    write_performer(&input.join("sub/d.npz"), 3, 2);
    input
}

fn total_of(loops_json: &Path) -> usize {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(loops_json).unwrap()).unwrap();
    v["repetitions"]["total"].as_u64().unwrap() as usize
}

fn by_name<'a>(items: &'a [ItemReport], name: &str) -> &'a ItemReport {
    items
        .iter()
        .find(|i| i.input.file_name().unwrap() == name)
        .unwrap_or_else(|| panic!("no item {name} in {items:?}"))
}

fn statuses(items: &[ItemReport]) -> Vec<(String, ItemStatus)> {
    items
        .iter()
        .map(|i| {
            (
                i.input.file_name().unwrap().to_string_lossy().into_owned(),
                i.status,
            )
        })
        .collect()
}

#[derive(Default)]
struct Recorder {
    started: AtomicUsize,
    finished: Mutex<Vec<(usize, ItemStatus)>>,
    stages: Mutex<BTreeSet<(usize, &'static str)>>,
    batch: Mutex<Option<(usize, usize)>>,
}

impl BatchObserver for Recorder {
    fn batch_started(&self, items: usize, to_run: usize) {
        *self.batch.lock().unwrap() = Some((items, to_run));
    }
    fn item_started(&self, _index: usize, _input: &Path) {
        self.started.fetch_add(1, Ordering::SeqCst);
    }
    fn item_finished(&self, index: usize, report: &ItemReport) {
        self.finished.lock().unwrap().push((index, report.status));
    }
    fn stage_finished(&self, index: usize, time: &mp_pipeline::StageTime) {
        self.stages
            .lock()
            .unwrap()
            .insert((index, time.stage.name()));
    }
}

#[test]
fn a_folder_runs_fails_alone_and_resumes() {
    let tmp = tempfile::tempdir().unwrap();
    let input = track_folder(tmp.path());
    // The output folder inside the input folder is not an input.
    let out = input.join("out");
    let items = batch_items(&input).unwrap();
    let names: Vec<_> = items
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["a.npz", "b.json", "c.npz"]);

    let params = quick_params();
    let rec = Recorder::default();
    let s = batch(&items, &out, &params, &rec, &CancelToken::new()).unwrap();
    assert_eq!(
        (s.ok(), s.failed(), s.skipped()),
        (2, 1, 0),
        "{:?}",
        s.items
    );
    assert!(!s.cancelled);
    assert_eq!(*rec.batch.lock().unwrap(), Some((3, 3)));
    assert_eq!(rec.started.load(Ordering::SeqCst), 3);
    assert_eq!(rec.finished.lock().unwrap().len(), 3);
    let stages = rec.stages.lock().unwrap().clone();
    assert!(stages.contains(&(0, Stage::Concrete.name())), "{stages:?}");
    assert!(stages.contains(&(1, Stage::Count.name())), "{stages:?}");

    // The corrupt file fails with a message that names it and says why.
    let c = by_name(&s.items, "c.npz");
    assert_eq!(c.status, ItemStatus::Failed);
    let msg = c.error.as_deref().unwrap();
    assert!(
        msg.contains("c.npz") && msg.contains("keypoint track"),
        "{msg}"
    );
    assert!(c.total_repetitions.is_none());

    // Each ok folder holds the counts that analyse_input finds.
    for (name, folder) in [("a.npz", "a"), ("b.json", "b")] {
        let r = by_name(&s.items, name);
        assert_eq!(r.status, ItemStatus::Ok);
        assert_eq!(r.output, out.join(folder));
        let expected = analyse_input(
            Input::open(input.join(name), None).unwrap(),
            &params.params,
            &Silent,
            &CancelToken::new(),
        )
        .unwrap();
        let total = total_of(&out.join(folder).join("loops.json"));
        assert_eq!(total, expected.counts.total, "{name}");
        assert_eq!(r.total_repetitions, Some(total));
        assert_eq!(r.frames, Some(expected.keypoints.track.n_frames()));
        assert_eq!(
            r.counts,
            expected
                .counts
                .intervals
                .iter()
                .map(|i| i.count)
                .collect::<Vec<_>>()
        );
        assert!(r.seconds.unwrap() > 0.0);
        assert!(total > 0, "{name}: the performer repeats");
    }

    // The manifest: one parsable line per item, as the summary says.
    let text = std::fs::read_to_string(out.join(ItemReport::MANIFEST)).unwrap();
    let lines: Vec<ItemReport> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3);
    for l in &lines {
        let v: serde_json::Value = serde_json::from_str(
            text.lines()
                .find(|t| t.contains(&*l.input.to_string_lossy()))
                .unwrap(),
        )
        .unwrap();
        for key in [
            "input",
            "output",
            "status",
            "error",
            "frames",
            "seconds",
            "total_repetitions",
            "counts",
            "signal",
            "method",
        ] {
            assert!(v.get(key).is_some(), "{key} missing in {v}");
        }
        let r = by_name(&s.items, &l.input.file_name().unwrap().to_string_lossy());
        assert_eq!(
            (&r.input, &r.output, r.status, &r.error, r.frames),
            (&l.input, &l.output, l.status, &l.error, l.frames)
        );
        assert_eq!(
            (r.total_repetitions, &r.counts, &r.signal, &r.method),
            (l.total_repetitions, &l.counts, &l.signal, &l.method)
        );
    }

    // The output folder inside the input folder is not listed.
    assert_eq!(batch_items(&input).unwrap(), items);

    // Again: the complete ones are skipped with their counts, the corrupt one fails again.
    let again = batch(&items, &out, &params, &Silent, &CancelToken::new()).unwrap();
    assert_eq!(
        statuses(&again.items),
        [
            ("a.npz".to_string(), ItemStatus::Skipped),
            ("b.json".to_string(), ItemStatus::Skipped),
            ("c.npz".to_string(), ItemStatus::Failed),
        ]
    );
    for name in ["a.npz", "b.json"] {
        assert_eq!(
            by_name(&again.items, name).total_repetitions,
            by_name(&s.items, name).total_repetitions
        );
        assert_eq!(
            by_name(&again.items, name).counts,
            by_name(&s.items, name).counts
        );
    }
    assert_eq!(again.frames(), 0, "nothing was run");
    assert_eq!(
        ItemReport::read_manifest(&out.join(ItemReport::MANIFEST))
            .unwrap()
            .len(),
        3
    );

    // A line cut short by a crash, and one folder deleted: only that one runs again.
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(out.join(ItemReport::MANIFEST))
        .unwrap();
    std::io::Write::write_all(&mut f, b"{\"input\": \"tracks/a.n").unwrap();
    drop(f);
    std::fs::remove_dir_all(out.join("a")).unwrap();
    let rec = Recorder::default();
    let third = batch(&items, &out, &params, &rec, &CancelToken::new()).unwrap();
    assert_eq!(
        statuses(&third.items),
        [
            ("a.npz".to_string(), ItemStatus::Ok),
            ("b.json".to_string(), ItemStatus::Skipped),
            ("c.npz".to_string(), ItemStatus::Failed),
        ]
    );
    assert_eq!(*rec.batch.lock().unwrap(), Some((3, 2)));
    assert_eq!(
        by_name(&third.items, "a.npz").total_repetitions,
        by_name(&s.items, "a.npz").total_repetitions
    );
    let manifest = ItemReport::read_manifest(&out.join(ItemReport::MANIFEST)).unwrap();
    assert_eq!(manifest.len(), 3);
    assert!(std::fs::read_to_string(out.join(ItemReport::MANIFEST))
        .unwrap()
        .lines()
        .all(|l| serde_json::from_str::<serde_json::Value>(l).is_ok()));
}

#[test]
fn a_folder_holds_what_run_writes() {
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("a.npz");
    write_performer(&input, 5, 2);
    let params = BatchParams::default();
    let s = batch(
        std::slice::from_ref(&input),
        &tmp.path().join("batch"),
        &params,
        &Silent,
        &CancelToken::new(),
    )
    .unwrap();
    assert_eq!(s.ok(), 1, "{:?}", s.items);
    let single = run(
        Input::open(&input, None).unwrap(),
        &tmp.path().join("single"),
        &params.params,
        &Silent,
        &CancelToken::new(),
    )
    .unwrap();
    let files = |dir: &Path| -> BTreeSet<String> {
        let mut out = BTreeSet::new();
        let mut stack = vec![dir.to_path_buf()];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap().flatten() {
                if e.path().is_dir() {
                    stack.push(e.path());
                } else {
                    let rel = e.path().strip_prefix(dir).unwrap().to_path_buf();
                    out.insert(rel.to_string_lossy().into_owned());
                }
            }
        }
        out
    };
    let batch_files = files(&tmp.path().join("batch/a"));
    assert_eq!(batch_files, files(&tmp.path().join("single")));
    assert_eq!(
        batch_files,
        single.files.iter().cloned().collect::<BTreeSet<_>>()
    );
    for f in ["loops.json", "program.txt", "abstract.txt"] {
        assert_eq!(
            std::fs::read(tmp.path().join("batch/a").join(f)).unwrap(),
            std::fs::read(tmp.path().join("single").join(f)).unwrap(),
            "{f}"
        );
    }
}

#[test]
fn a_list_file_with_relative_paths_and_comments() {
    let tmp = tempfile::tempdir().unwrap();
    let input = track_folder(tmp.path());
    let lists = tmp.path().join("lists");
    std::fs::create_dir_all(&lists).unwrap();
    let list = lists.join("inputs.txt");
    std::fs::write(
        &list,
        format!(
            "# two performer tracks\n\n../tracks/a.npz\n   # indented comment\n{}\n../tracks/sub/d.npz\n../tracks/missing.npz\n",
            input.join("b.json").display()
        ),
    )
    .unwrap();
    let items = batch_items(&list).unwrap();
    assert_eq!(
        items,
        vec![
            lists.join("../tracks/a.npz"),
            input.join("b.json"),
            lists.join("../tracks/sub/d.npz"),
            lists.join("../tracks/missing.npz"),
        ]
    );
    let out = tmp.path().join("out");
    let s = batch(&items, &out, &quick_params(), &Silent, &CancelToken::new()).unwrap();
    assert_eq!(
        statuses(&s.items),
        [
            ("a.npz".to_string(), ItemStatus::Ok),
            ("b.json".to_string(), ItemStatus::Ok),
            ("d.npz".to_string(), ItemStatus::Ok),
            ("missing.npz".to_string(), ItemStatus::Failed),
        ]
    );
    let missing = by_name(&s.items, "missing.npz");
    assert!(
        missing.error.as_deref().unwrap().contains("does not exist"),
        "{missing:?}"
    );
    for d in ["a", "b", "d"] {
        assert!(out.join(d).join("loops.json").is_file(), "{d}");
    }
    assert!(!out.join("missing").exists());

    // Empty lists and folders without inputs are errors of the batch as a whole.
    let empty = lists.join("empty.txt");
    std::fs::write(&empty, "# nothing\n\n").unwrap();
    let e = batch_items(&empty).unwrap_err().to_string();
    assert!(e.contains("names no inputs"), "{e}");
    let e = batch_items(lists.join("sub")).unwrap_err().to_string();
    assert!(e.contains("does not exist"), "{e}");
    let e = batch_items(input.join("sub").join("..").join("..").join("lists"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("holds no videos"), "{e}");
}

#[test]
fn two_jobs_give_the_same_results_as_one() {
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("tracks");
    std::fs::create_dir_all(&input).unwrap();
    for (i, name) in ["p.npz", "q.npz", "r.json", "s.csv"].iter().enumerate() {
        write_performer(&input.join(name), 10 + i as u64, 2 + i);
    }
    // Equal stems get told-apart folders.
    write_performer(&input.join("p.json"), 20, 3);
    let items = batch_items(&input).unwrap();
    assert_eq!(items.len(), 5);
    let one = batch(
        &items,
        &tmp.path().join("one"),
        &quick_params(),
        &Silent,
        &CancelToken::new(),
    )
    .unwrap();
    let params = BatchParams {
        jobs: 2,
        ..quick_params()
    };
    let two = batch(
        &items,
        &tmp.path().join("two"),
        &params,
        &Silent,
        &CancelToken::new(),
    )
    .unwrap();
    assert_eq!(one.jobs, 1);
    assert_eq!(two.jobs, 2);
    assert_eq!(two.ok(), 5, "{:?}", two.items);
    let folder = |r: &ItemReport| r.output.file_name().unwrap().to_string_lossy().into_owned();
    assert_eq!(
        one.items.iter().map(folder).collect::<Vec<_>>(),
        ["p-json", "p-npz", "q", "r", "s"]
    );
    for (a, b) in one.items.iter().zip(&two.items) {
        assert_eq!(a.input, b.input);
        assert_eq!(folder(a), folder(b));
        assert_eq!(a.status, b.status);
        assert_eq!(a.frames, b.frames);
        assert_eq!(a.total_repetitions, b.total_repetitions);
        assert_eq!(a.counts, b.counts);
        assert_eq!((&a.signal, &a.method), (&b.signal, &b.method));
        assert_eq!(
            std::fs::read(a.output.join("loops.json")).unwrap(),
            std::fs::read(b.output.join("loops.json")).unwrap(),
            "{}",
            a.input.display()
        );
    }
    assert_eq!(ItemReport::read_manifest(&two.manifest).unwrap().len(), 5);
}

#[test]
fn a_cancelled_batch_starts_nothing_and_writes_no_lines() {
    let tmp = tempfile::tempdir().unwrap();
    let input = track_folder(tmp.path());
    let items = batch_items(&input).unwrap();
    let cancel = CancelToken::new();
    cancel.cancel();
    let out = tmp.path().join("out");
    let s = batch(&items, &out, &quick_params(), &Silent, &cancel).unwrap();
    assert!(s.cancelled);
    assert_eq!(s.cancelled_items(), 3);
    assert!(ItemReport::read_manifest(&out.join(ItemReport::MANIFEST))
        .unwrap()
        .is_empty());
    assert!(!out.join("a").exists());
    // Then the batch runs in full.
    let s = batch(&items, &out, &quick_params(), &Silent, &CancelToken::new()).unwrap();
    assert_eq!((s.ok(), s.failed()), (2, 1));
}

#[test]
fn bad_parameters_stop_the_batch_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let bad = BatchParams {
        jobs: 0,
        ..BatchParams::default()
    };
    let e = batch(&[], &out, &bad, &Silent, &CancelToken::new()).unwrap_err();
    assert!(e.to_string().contains("jobs"), "{e}");
    assert!(!out.exists());
}

#[test]
fn a_real_video_item() {
    let video = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let tmp = tempfile::tempdir().unwrap();
    let track = tmp.path().join("023_fitness.npz");
    write_performer(&track, 7, 2);
    let mut params = quick_params();
    params.params.pose.max_frames = Some(60);
    params.jobs = 2;
    let items = vec![video, track];
    let out = tmp.path().join("out");
    let s = batch(&items, &out, &params, &Silent, &CancelToken::new()).unwrap();
    assert_eq!(s.ok(), 2, "{:?}", s.items);
    assert_eq!(s.threads_per_item, params.threads_per_item(2));
    let v = &s.items[0];
    assert_eq!(v.output, out.join("023_fitness-mp4"));
    assert_eq!(s.items[1].output, out.join("023_fitness-npz"));
    assert_eq!(v.frames, Some(60));
    assert!(v.output.join("loops.json").is_file());
    assert!(v.output.join("track.npz").is_file());
    assert!(!v.output.join("overlay.mp4").exists());
}

/// Two videos whose jobs share one landmark model give the keypoints of
/// jobs with a model each, and the shared model reports the crops it ran.
#[test]
fn jobs_sharing_one_landmark_model_give_their_own_keypoints() {
    let a = mp_geom::data_or_return!("quva_repetition/videos/023_fitness.mp4");
    let b = mp_geom::data_or_return!("quva_repetition/videos/020_fitness.mp4");
    let tmp = tempfile::tempdir().unwrap();
    let items = vec![a, b];
    let run_with = |shared: SharedModel, out: &str| {
        let mut params = quick_params();
        params.params.pose.max_frames = Some(45);
        params.jobs = 2;
        params.shared_model = shared;
        let out = tmp.path().join(out);
        let s = batch(&items, &out, &params, &Silent, &CancelToken::new()).unwrap();
        assert_eq!(s.ok(), 2, "{:?}", s.items);
        s
    };
    let own = run_with(SharedModel::Never, "own");
    let shared = run_with(SharedModel::Always, "shared");
    assert_eq!(own.shared_model, None);
    let stats = shared.shared_model.expect("the jobs shared a model");
    assert!(stats.crops >= 45, "{stats:?}");
    assert!(
        stats.runs <= stats.crops && stats.requests <= stats.crops,
        "{stats:?}"
    );
    for (x, y) in own.items.iter().zip(&shared.items) {
        let tx = mp_geom::read_track(x.output.join("track.npz")).unwrap();
        let ty = mp_geom::read_track(y.output.join("track.npz")).unwrap();
        assert_eq!(tx.n_frames(), ty.n_frames());
        let (px, py) = (tx.positions(), ty.positions());
        let (cx, cy) = (tx.confidence(), ty.confidence());
        let mut compared = 0;
        for ((f, j), &c) in cx.indexed_iter() {
            if c > 0.0 && cy[[f, j]] > 0.0 {
                let d = (px[[f, j, 0]] - py[[f, j, 0]]).hypot(px[[f, j, 1]] - py[[f, j, 1]]);
                assert!(
                    d < 0.01,
                    "{}: frame {f} joint {j} {d} px apart",
                    x.input.display()
                );
                compared += 1;
            }
        }
        assert!(
            compared > 100,
            "{}: {compared} keypoints",
            x.input.display()
        );
    }
}
