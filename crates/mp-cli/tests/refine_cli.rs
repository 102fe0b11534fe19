//! `mp refine` through the built binary on a real MSR Action3D clip with an
//! injected jump: the flaw detector finds and refills it, and the refined
//! track is closer to the clean one than the flawed input was.

use std::process::Command;

use mp_geom::io::datasets::MsrAction3D;
use mp_geom::io::{read_track, write_track};
use mp_refine::baseline::full_confidence;
use mp_refine::flaws::{inject, Flaw};
use mp_refine::mpjpe_abs;

#[test]
fn refine_repairs_an_injected_jump_and_rejects_a_useless_flag_set() {
    let data = MsrAction3D::open_default()
        .expect("shared data: msr_action3d/msr_action3d_odd_subjects.npz (set MP_DATA_DIR)");
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
    let out = Command::new(env!("CARGO_BIN_EXE_mp"))
        .args(["refine", input.to_str().unwrap(), "-o"])
        .arg(&output)
        .arg("--report")
        .arg(&report)
        .output()
        .expect("running mp");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "mp refine failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
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
