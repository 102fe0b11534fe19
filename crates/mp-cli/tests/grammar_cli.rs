//! `mp grammar` end to end through the built binary: symbols → learn →
//! synth (BVH and track output, FSM baseline, regeneration) on 15 s of a
//! real salsa take at 30 fps, the learned symbols on another slice and its
//! score (grammar, FSM, unigram), and learn-strings on the paper's six
//! strings.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::path::Path;
use std::process::Command;

use mp_geom::Bvh;

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

    // The learned symbols on frames the model has not seen, then its score.
    let other_src = mp_geom::data_or_return!("cmu_salsa_bvh/60_09_scaled.bvh");
    let other = dir.path().join("other.bvh");
    Bvh::read(&other_src)
        .unwrap()
        .slice_frames(0, 1200)
        .unwrap()
        .write_bvh(&other)
        .unwrap();
    let held = dir.path().join("held.json");
    let (held_text, _) = mp(&[
        "grammar",
        "symbols",
        p(&other),
        "--model",
        p(&gram),
        "-o",
        p(&held),
    ]);
    let hv: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&held).unwrap()).unwrap();
    assert_eq!(hv["source"]["n_frames"], 300, "the model's frame step (4)");
    assert_eq!(hv["symbols"]["k"], 5);
    let held_syms: Vec<&str> = held_text.split_whitespace().collect();
    assert!(held_syms.len() >= 2, "{held_text}");
    assert!(held_syms
        .iter()
        .all(|s| ["a", "b", "c", "d", "e"].contains(s)));
    let score_json = dir.path().join("score.json");
    let (score, _) = mp(&["grammar", "score", p(&gram), p(&held), "-o", p(&score_json)]);
    assert!(score.contains("bits per symbol: grammar"), "{score}");
    let sv: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&score_json).unwrap()).unwrap();
    for m in ["grammar", "fsm", "unigram"] {
        let b = sv["score"][m]["bits_per_symbol"].as_f64().unwrap();
        assert!(b.is_finite() && b > 0.0, "{m}: {b}");
        assert_eq!(sv["score"][m]["symbols"], held_syms.len());
    }
    // A text string scores the same as the JSON it came from.
    let txt = dir.path().join("held.txt");
    std::fs::write(&txt, &held_text).unwrap();
    let (score_txt, _) = mp(&["grammar", "score", p(&gram), p(&txt)]);
    assert_eq!(score_txt, score);
    // Unknown symbols and bad model files are errors naming the file.
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, "a b zz\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mp"))
        .args(["grammar", "score", p(&gram), p(&bad)])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("bad.txt") && err.contains("line 1, symbol 3"),
        "{err}"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_mp"))
        .args(["grammar", "score", p(&sym), p(&txt)])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("sym.json"));

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
    let t = mp_geom::read_track(&npz).unwrap();
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
    assert!((2..=5).contains(&nts) && (5..=11).contains(&rules), "{out}");
    assert!(out.contains(&format!("{nts} nonterminals, {rules} rules")));
    // The previous clustering, for comparison.
    let (first, _) = mp(&[
        "grammar",
        "learn-strings",
        p(&f),
        "--clustering",
        "first-mapping",
    ]);
    assert!(first.contains("8 nonterminals, 18 rules"), "{first}");
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
