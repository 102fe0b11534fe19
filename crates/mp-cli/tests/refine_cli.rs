//! `mp refine` through the built binary on a real MSR Action3D clip with an
//! injected jump: the flaw detector finds and refills it, and the refined
//! track is closer to the clean one than the flawed input was.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::Path;
use std::process::Command;

use mp_geom::MsrAction3D;
use mp_geom::{read_track, write_track};
use mp_refine::full_confidence;
use mp_refine::mpjpe_abs;
use mp_refine::{inject, Flaw};

/// Runs `mp refine INPUT -o OUTPUT --report REPORT EXTRA…`, asserts that it
/// succeeds and returns its standard output.
fn run_refine(input: &Path, output: &Path, report: &Path, extra: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_mp"))
        .arg("refine")
        .arg(input)
        .arg("-o")
        .arg(output)
        .arg("--report")
        .arg(report)
        .args(extra)
        .output()
        .expect("running mp");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "mp refine {extra:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

#[test]
fn refine_repairs_an_injected_jump_and_rejects_a_useless_flag_set() {
    let data = MsrAction3D::open(mp_geom::data_or_return!(MsrAction3D::FILE)).unwrap();
    // the first usable clip of held-out subject 9
    let i = (0..data.len())
        .find(|&i| {
            let c = data.clip_info(i).unwrap();
            c.subject == 9 && (30..=120).contains(&c.rows.len())
        })
        .expect("a subject-9 clip of 30–120 frames");
    let clean = full_confidence(&data.clip(i).unwrap()).unwrap();
    let flawed = inject(
        &clean,
        &Flaw::Jump {
            frames: 4,
            skip_frames: 8,
        },
        i as u64,
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("flawed.json");
    let output = dir.path().join("refined.json");
    let report = dir.path().join("report.json");
    write_track(&input, &flawed.track).unwrap();
    let stdout = run_refine(&input, &output, &report, &[]);
    assert!(stdout.contains("flaw detector"), "{stdout}");
    let refined = read_track(&output).unwrap();
    assert_eq!(refined.n_frames(), clean.n_frames());
    let before = mpjpe_abs(&flawed.track, &clean).unwrap();
    let after = mpjpe_abs(&refined, &clean).unwrap();
    assert!(
        after < 0.8 * before,
        "refined {:.1} mm vs flawed {:.1} mm",
        after * 1e3,
        before * 1e3
    );
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert!(!rep["repaired_runs"].as_array().unwrap().is_empty());

    // switching the detector off without another step is refused with a clear message
    let out = Command::new(env!("CARGO_BIN_EXE_mp"))
        .args(["refine", input.to_str().unwrap(), "-o"])
        .arg(&output)
        .arg("--no-detector")
        .output()
        .expect("running mp");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--no-detector"));
}

#[test]
fn refine_generated_moves_flawed_anchors_to_concepts() {
    use mp_geom::{Skeleton, Track, Units};
    use mp_pose::SessionParams;
    use mp_refine::from_features;
    use mp_refine::generate_clips;
    use mp_refine::Concepts;
    use mp_refine::RefineNets;
    use mp_refine::{NetRefineParams, NetRefiner};

    let dir = RefineNets::find_dir().expect("models/refine");
    let nets = RefineNets::load(&dir, &SessionParams::default()).unwrap();
    let concepts =
        Concepts::from_json(&std::fs::read_to_string(dir.join("concepts.json")).unwrap()).unwrap();
    let params = NetRefineParams::for_generated();
    let lib = NetRefiner::new(&nets, &concepts, &params).unwrap();
    // The first generator sample (seed 11) in which the library moves an anchor.
    let (gen, labels) = generate_clips(&nets, 2, 11).unwrap();
    let (track, action, expected) = gen
        .outer_iter()
        .zip(&labels)
        .find_map(|(x, &a)| {
            let pos = from_features(x).unwrap();
            let t = Track::new(pos, None, 15.0, Units::Metres, Skeleton::msr20()).unwrap();
            let r = lib.refine_track(&t, Some(a)).unwrap();
            let moved: Vec<usize> = r
                .report
                .anchors
                .iter()
                .filter(|an| an.repaired)
                .map(|an| an.frame)
                .collect();
            (!moved.is_empty()).then_some((t, a, moved))
        })
        .expect("a generated sample with a flawed anchor");
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("generated.json");
    let output = tmp.path().join("refined.json");
    let report = tmp.path().join("report.json");
    write_track(&input, &track).unwrap();
    let stdout = run_refine(
        &input,
        &output,
        &report,
        &["--generated", "--action", &action.to_string()],
    );
    assert!(stdout.contains("new pose, concept"), "{stdout}");
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let mut moved = Vec::new();
    for a in rep["anchors"].as_array().unwrap() {
        if a["repaired"] == true {
            moved.push(a["frame"].as_u64().unwrap() as usize);
            // Concepts of the action: ids (action − 1)·4 .. (action − 1)·4 + 3.
            let c = a["concept"]
                .as_u64()
                .expect("a moved anchor names its concept") as u32;
            assert_eq!(c / 4 + 1, action, "concept {c} for action {action}");
        }
    }
    assert_eq!(moved, expected);
    let refined = read_track(&output).unwrap();
    assert_eq!(refined.n_frames(), track.n_frames());
    let d = mp_refine::mpjpe_abs(&refined, &track).unwrap();
    assert!(d > 1e-3, "anchors moved but the track changed by {d} m");
}

#[test]
fn concepts_from_a_folder_with_each_clustering_method() {
    let data = MsrAction3D::open(mp_geom::data_or_return!(MsrAction3D::FILE)).unwrap();
    // Six clips of action 5 (forward punch) as track files.
    let tmp = tempfile::tempdir().unwrap();
    let folder = tmp.path().join("punch");
    std::fs::create_dir(&folder).unwrap();
    for (k, &i) in data.clips_of_action(5).iter().take(6).enumerate() {
        let t = full_confidence(&data.clip(i).unwrap()).unwrap();
        write_track(folder.join(format!("clip{k}.json")), &t).unwrap();
    }
    let run = |extra: &[&str]| {
        let out_path = tmp.path().join("concepts.json");
        let out = Command::new(env!("CARGO_BIN_EXE_mp"))
            .arg("concepts")
            .arg(&folder)
            .arg("-o")
            .arg(&out_path)
            .args(["--action", "5"])
            .args(extra)
            .output()
            .expect("running mp");
        let text = std::fs::read_to_string(&out_path).unwrap_or_default();
        let _ = std::fs::remove_file(&out_path);
        (out, text)
    };
    for (extra, expect) in [
        (&["--method", "kmeans", "--clusters", "3"][..], Some(3)),
        (
            &["--method", "hierarchical", "--clusters", "3"][..],
            Some(3),
        ),
        (
            &[
                "--method",
                "hierarchical",
                "--clusters",
                "2",
                "--linkage",
                "average",
            ][..],
            Some(2),
        ),
        (&["--method", "optics", "--min-points", "3"][..], None),
    ] {
        let (out, text) = run(extra);
        assert!(
            out.status.success(),
            "mp concepts {extra:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let c: serde_json::Value = serde_json::from_str(&text).unwrap();
        let a = &c["actions"]["5"];
        let n_cent = a["centroids"].as_array().unwrap().len();
        let labels = a["labels"].as_array().unwrap();
        assert!(labels.len() >= 12, "{extra:?}: {} anchors", labels.len());
        match expect {
            Some(k) => {
                assert_eq!(n_cent, k, "{extra:?}");
                assert!(labels
                    .iter()
                    .all(|l| l.as_u64().is_some_and(|l| l < k as u64)));
            }
            None => {
                // Density clusters: every label names a centroid; some may be noise.
                assert!(n_cent >= 1, "{extra:?}: no cluster");
                assert!(labels
                    .iter()
                    .all(|l| l.is_null() || l.as_u64().is_some_and(|l| l < n_cent as u64)));
            }
        }
        assert!(a["score_threshold"].as_f64().is_some_and(f64::is_finite));
    }
    // An OPTICS cut beyond the ordering's radius is refused, naming the parameter.
    let (out, _) = run(&[
        "--method",
        "optics",
        "--tolerance",
        "2",
        "--optics-radius",
        "1",
    ]);
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("cut"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
