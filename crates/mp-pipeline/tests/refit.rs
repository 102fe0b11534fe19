//! The concrete program `mp fit` writes, with the C0 refit under the
//! Euclidean norm, on real keypoints with long gaps.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_concrete::RefitNorm;
use mp_pipeline::Params;

/// The hoola-hoop video's reference keypoints: the person is lost for long
/// stretches (the hoop hides the body), so whole segments have no observed
/// frame of some joints and are pinned by the gap-filled track alone. The
/// Euclidean refit must not let such a segment swing away: the program's
/// largest step between adjacent frames stays below the input's, as the
/// least-squares refit's does, and its KD is lower.
#[test]
fn euclidean_refit_keeps_unobserved_segments_in_place() {
    let Some(path) = mp_geom::test_support::data_file_or_skip(
        "reference_keypoints/090_hoolahoop.npz",
        &mp_geom::test_support::current_test_name(),
    ) else {
        return;
    };
    let track = mp_geom::read_track(&path).unwrap();
    let mut params = Params::default();
    assert_eq!(
        params.analysis.synth.refit_norm,
        RefitNorm::Euclidean,
        "the default"
    );
    let eu = mp_pipeline::concrete_program(&track, None, &params).unwrap();
    params.analysis.synth.refit_norm = RefitNorm::Squared;
    let sq = mp_pipeline::concrete_program(&track, None, &params).unwrap();
    assert_eq!(sq.program.boundaries(), eu.program.boundaries());
    let (s, e) = (
        sq.program.stats(&track).unwrap(),
        eu.program.stats(&track).unwrap(),
    );
    eprintln!(
        "max jump raw {:.1}, squared {:.1}, euclidean {:.1}; KD {:.2} → {:.2}; params {} → {}",
        s.max_jump_raw,
        s.max_jump_program,
        e.max_jump_program,
        s.kd,
        e.kd,
        s.params_program,
        e.params_program
    );
    assert!(s.max_jump_program < s.max_jump_raw);
    assert!(
        e.max_jump_program < e.max_jump_raw,
        "Euclidean refit: program jump {} above the input's {}",
        e.max_jump_program,
        e.max_jump_raw
    );
    assert!(e.kd < s.kd, "KD {} vs least squares {}", e.kd, s.kd);
    assert!(e.params_program <= s.params_program);
}
