//! `mp grammar` end to end through the built binary: symbols → learn →
//! synth (BVH and track output, FSM baseline, regeneration) on 15 s of a
//! real salsa take at 30 fps, and learn-strings on the paper's six strings.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::Path;
use std::process::Command;

use mp_geom::io::bvh::Bvh;

fn mp(args: &[&str]) -> (String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_mp"))
        .args(args)
        .output()
        .expect("running mp");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        out.status.success(),
        "mp {args:?} failed\nstdout:\n{stdout}\nstderr:\n{stderr}"
    );
    (stdout, stderr)
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

#[test]
fn symbols_learn_synth_round_trip() {
    let src = mp_geom::data_or_return!("cmu_salsa_bvh/60_02_scaled.bvh");
    let dir = tempfile::tempdir().unwrap();
    // A 1,800-frame slice (15 s at 120 fps) as the input.
    let slice = dir.path().join("slice.bvh");
    let full = Bvh::read(&src).unwrap();
    full.slice_frames(0, 1800)
        .unwrap()
        .write_bvh(&slice)
        .unwrap();

    let sym = dir.path().join("sym.json");
    let (stdout, _) = mp(&[
        "grammar",
        "symbols",
        p(&slice),
        "--k",
        "5",
        "--frame-step",
        "4",
        "--population",
        "16",
        "--generations",
        "10",
        "--sa-iterations",
        "100",
        "--seed",
        "2",
        "-o",
        p(&sym),
    ]);
    let string: Vec<&str> = stdout.split_whitespace().collect();
    assert!(string.len() >= 5, "{stdout}");
    let js: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&sym).unwrap()).unwrap();
    assert_eq!(js["format"], "mp-grammar-symbols/1");
    assert_eq!(js["source"]["n_frames"], 450);
    assert_eq!(js["source"]["kind"], "bvh");
    let segs = js["symbols"]["segments"].as_array().unwrap();
    assert_eq!(segs.len(), string.len());
    assert_eq!(segs[0]["start"], 0);
    assert_eq!(segs.last().unwrap()["end"], 450);

    let gram = dir.path().join("grammar.json");
    let (rules, _) = mp(&[
        "grammar",
        "learn",
        p(&sym),
        "-o",
        p(&gram),
        "--candidates",
        "20",
    ]);
    assert!(rules.contains("S -> "), "{rules}");
    assert!(rules.contains("nonterminals"), "{rules}");

    // BVH output with the input's hierarchy, seeded.
    let out1 = dir.path().join("a.bvh");
    let out2 = dir.path().join("b.bvh");
    mp(&[
        "grammar",
        "synth",
        p(&gram),
        "--seed",
        "4",
        "--segments",
        "8",
        "-o",
        p(&out1),
    ]);
    mp(&[
        "grammar",
        "synth",
        p(&gram),
        "--seed",
        "4",
        "--segments",
        "8",
        "-o",
        p(&out2),
    ]);
    let a = std::fs::read_to_string(&out1).unwrap();
    assert_eq!(a, std::fs::read_to_string(&out2).unwrap());
    let b = Bvh::parse(&a, &out1).unwrap();
    assert_eq!(b.joints(), full.joints());
    assert!(b.n_frames() > 0);
    assert!((b.fps() - 30.0).abs() < 0.01);

    // Track output, the FSM baseline, regeneration and an explicit source.
    let npz = dir.path().join("fsm.npz");
    let (fsm, _) = mp(&[
        "grammar",
        "synth",
        p(&gram),
        "--fsm",
        "--segments",
        "8",
        "-o",
        p(&npz),
        "--source",
        p(&slice),
    ]);
    assert_eq!(
        fsm.lines().next().unwrap().split_whitespace().count(),
        9,
        "{fsm}"
    );
    let t = mp_geom::io::read_track(&npz).unwrap();
    assert_eq!(t.n_joints(), full.joints().len());
    let regen = dir.path().join("regen.bvh");
    let (out, err) = mp(&[
        "grammar",
        "synth",
        p(&gram),
        "--seed",
        "4",
        "--segments",
        "8",
        "--regenerate",
        "1",
        "-o",
        p(&regen),
    ]);
    assert!(out.contains("regenerated:"), "{out}");
    assert!(err.contains("regenerated "), "{err}");
    Bvh::read(&regen).unwrap();
}

#[test]
fn learn_strings_on_the_paper_example() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("basketball.txt");
    std::fs::write(
        &f,
        "r f d p m\nr f d s m\nr d f s m\nr d p m\nr d s m\nr p m\n",
    )
    .unwrap();
    let json = dir.path().join("g.json");
    let (out, _) = mp(&["grammar", "learn-strings", p(&f), "-o", p(&json)]);
    assert!(out.contains("S -> "), "{out}");
    assert!(out.contains("DL = "), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rules = v["n_rules"].as_u64().unwrap();
    let nts = v["n_nonterminals"].as_u64().unwrap();
    // The paper: 5 nonterminals and 11 rules with the reference ABL.
    assert!((2..=8).contains(&nts) && (5..=20).contains(&rules), "{out}");
    assert!(out.contains(&format!("{nts} nonterminals, {rules} rules")));
    // A bad file is a clear error.
    let empty = dir.path().join("empty.txt");
    std::fs::write(&empty, "\n\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mp"))
        .args(["grammar", "learn-strings", p(&empty)])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("empty.txt"));
}
