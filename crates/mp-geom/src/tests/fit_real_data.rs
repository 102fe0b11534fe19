//! Fitting and metrics on real Penn Action clips (hand-labelled 2D joints).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::fit::{fit_best, FitParams};
use crate::io::datasets::PennAction;
use crate::metrics::{kd, max_adjacent_jump, pck, Poses};
use crate::{GeomError, PrimitiveKind};
use ndarray::{s, Array2, Array3};

/// Encodes every joint of a clip with the best primitive on fixed windows
/// and returns the executed positions and the kinds chosen.
fn encode(
    track: &crate::Track,
    window: usize,
    params: &FitParams,
) -> (Array3<f64>, Vec<PrimitiveKind>) {
    let (t, j, d) = track.positions().dim();
    let mut out = Array3::zeros((t, j, d));
    let mut kinds = Vec::new();
    for ji in 0..j {
        let traj = track.joint(ji);
        let conf = track.confidence();
        let mut a = 0;
        while a < t {
            let b = (a + window).min(t);
            let w: Vec<f64> = conf.slice(s![a..b, ji]).to_vec();
            match fit_best(traj.slice(s![a..b, ..]), Some(&w), params) {
                Ok(f) => {
                    assert!(f.error.is_finite() && f.primitive.is_finite());
                    kinds.push(f.primitive.kind());
                    for i in a..b {
                        let p = f.primitive.eval((i - a) as f64);
                        for k in 0..d {
                            out[[i, ji, k]] = p[k];
                        }
                    }
                }
                Err(GeomError::NoData(_)) => assert!(w.iter().all(|&v| v == 0.0)),
                Err(e) => panic!("joint {ji}, frames {a}..{b}: {e}"),
            }
            a = b;
        }
    }
    (out, kinds)
}

#[test]
fn penn_action_windows() {
    crate::data_or_return!(PennAction::TRAIN_FILE);
    let penn = PennAction::open_default()
        .expect("Penn Action npz in the shared data (MP_DATA_DIR or ../shared/data)");
    let mut kds = Vec::new();
    let mut all_kinds = Vec::new();
    // a few clips of different actions
    for action in [
        "baseball_pitch",
        "golf_swing",
        "jumping_jacks",
        "squat",
        "tennis_serve",
    ] {
        let clips = penn.clips_of_action(action);
        assert!(!clips.is_empty(), "{action}");
        let i = clips[0];
        let info = penn.clip_info(i).unwrap().clone();
        let track = penn.clip(i).unwrap();
        let params = FitParams {
            unit_scale: info.width_px.max(info.height_px) as f64 / 512.0,
            ..FitParams::default()
        };
        let (enc, kinds) = encode(&track, 12, &params);
        all_kinds.extend(kinds);
        let conf: Array2<f64> = track.confidence().to_owned();
        let encoded = Poses::new(enc.view(), Some(conf.view())).unwrap();
        let k = kd(encoded, &track).unwrap();
        // relative to the frame size: program-encoded poses stay close to the labels
        let rel = k / info.width_px.max(info.height_px) as f64;
        assert!(rel < 0.03, "{action}: KD {k:.2} px ({rel:.4} of the frame)");
        kds.push(k);
        // metric sanity on real data
        assert!(max_adjacent_jump(&track).unwrap() > 0.0);
        if let Ok(p) = pck(&track, &track, 0.05) {
            assert_eq!(p, 100.0);
        }
    }
    eprintln!("KD per clip (px): {kds:.2?}");
    // every primitive kind of the default set occurs on real motion
    for kind in [
        PrimitiveKind::Stationary,
        PrimitiveKind::Line,
        PrimitiveKind::Circle,
    ] {
        assert!(all_kinds.contains(&kind), "{kind:?} never chosen: {kds:?}");
    }
}
