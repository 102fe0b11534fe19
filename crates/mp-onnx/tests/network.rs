//! A real model of the repository through [`Network`]: the refinement
//! evaluator (`models/refine/evaluator.onnx`, input `motion [B, 60, 60]`,
//! outputs `logits [B, 20]` and `features [B, F]`).
//!
//! Needs ONNX Runtime (`cargo xtask setup`) and the committed model.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::sync::OnceLock;

use mp_onnx::{ModelDirs, Network, OnnxError, SessionParams, TensorInput};

const FRAMES: usize = 60;
const FEATURES: usize = 60;
const ACTIONS: usize = 20;

fn evaluator() -> &'static Network {
    static NET: OnceLock<Network> = OnceLock::new();
    NET.get_or_init(|| {
        let path = ModelDirs::standard("MP_REFINE_MODELS", "models/refine")
            .require_file("evaluator.onnx")
            .unwrap_or_else(|e| panic!("models/refine is part of the repository: {e}"));
        Network::open(&path, &SessionParams::default())
            .unwrap_or_else(|e| panic!("{e} (ONNX Runtime: run `cargo xtask setup`)"))
    })
}

/// A smooth batch of clips, different per item.
fn motion(batch: usize) -> Vec<f32> {
    (0..batch * FRAMES * FEATURES)
        .map(|i| (i as f32 * 0.013).sin() * 0.3)
        .collect()
}

#[test]
fn the_graph_is_described() {
    let net = evaluator();
    assert!(net.name().ends_with("evaluator.onnx"), "{}", net.name());
    let motion = net.input("motion").expect("input `motion`");
    assert_eq!(motion.dtype, "f32");
    assert_eq!(motion.shape.len(), 3);
    assert_eq!(&motion.shape[1..], &[FRAMES as i64, FEATURES as i64]);
    assert!(net.output("logits").is_some() && net.output("features").is_some());
    net.expect_input("motion", "f32", &[-1, FRAMES as i64, FEATURES as i64])
        .unwrap();
    net.expect_output("logits", "f32", &[-1, ACTIONS as i64])
        .unwrap();
    let e = net
        .expect_input("motion", "f32", &[-1, 61, 60])
        .unwrap_err();
    assert!(matches!(e, OnnxError::Contract { .. }), "{e}");
}

#[test]
fn the_right_shape_runs_and_gives_finite_outputs() {
    let net = evaluator();
    for batch in [1, 3] {
        let data = motion(batch);
        let shape = [batch, FRAMES, FEATURES];
        let out = net
            .run(
                &[TensorInput::new("motion", &shape, &data)],
                &["logits", "features"],
            )
            .unwrap();
        assert_eq!(out.len(), 2);
        assert_eq!(out[0].name, "logits");
        assert_eq!(out[0].shape, vec![batch, ACTIONS]);
        assert_eq!(out[0].data.len(), batch * ACTIONS);
        assert_eq!(out[1].name, "features");
        assert_eq!(out[1].shape.len(), 2);
        assert_eq!(out[1].shape[0], batch);
        assert_eq!(out[1].data.len(), out[1].shape.iter().product::<usize>());
        for o in &out {
            assert!(
                o.data.iter().all(|v| v.is_finite()),
                "{}: non-finite",
                o.name
            );
        }
    }
}

#[test]
fn a_wrong_shape_is_a_typed_error_naming_the_input() {
    let net = evaluator();
    let data = motion(1);
    // 59 frames instead of 60 (same number of values as a different shape would need).
    let bad = [1usize, FRAMES - 1, FEATURES];
    let e = net
        .run(
            &[TensorInput::new(
                "motion",
                &bad,
                &data[..(FRAMES - 1) * FEATURES],
            )],
            &["logits"],
        )
        .unwrap_err();
    match &e {
        OnnxError::InputShape {
            model,
            input,
            expected,
            got,
        } => {
            assert!(model.ends_with("evaluator.onnx"), "{model}");
            assert_eq!(input, "motion");
            assert_eq!(&expected[1..], &[FRAMES as i64, FEATURES as i64]);
            assert_eq!(got, &bad.to_vec());
        }
        other => panic!("expected InputShape, got {other:?}"),
    }
    assert!(e.is_shape_mismatch());
    let msg = e.to_string();
    assert!(
        msg.contains("`motion`") && msg.contains("evaluator.onnx") && msg.contains("[1, 59, 60]"),
        "{msg}"
    );

    // A missing batch dimension.
    let e = net
        .run(
            &[TensorInput::new("motion", &[FRAMES, FEATURES], &data)],
            &["logits"],
        )
        .unwrap_err();
    assert!(matches!(e, OnnxError::InputShape { .. }), "{e}");

    // The right shape with too few values.
    let e = net
        .run(
            &[TensorInput::new(
                "motion",
                &[1, FRAMES, FEATURES],
                &data[1..],
            )],
            &["logits"],
        )
        .unwrap_err();
    assert!(
        matches!(&e, OnnxError::InputLength { input, needed: 3600, len: 3599, .. } if input == "motion"),
        "{e}"
    );
}

#[test]
fn wrong_names_are_typed_errors() {
    let net = evaluator();
    let data = motion(1);
    let shape = [1, FRAMES, FEATURES];
    let e = net
        .run(&[TensorInput::new("frames", &shape, &data)], &["logits"])
        .unwrap_err();
    assert!(
        matches!(&e, OnnxError::UnknownInput { input, known, .. } if input == "frames" && known.contains("motion")),
        "{e}"
    );
    let e = net.run(&[], &["logits"]).unwrap_err();
    assert!(
        matches!(&e, OnnxError::MissingInput { input, .. } if input == "motion"),
        "{e}"
    );
    let e = net
        .run(&[TensorInput::new("motion", &shape, &data)], &["scores"])
        .unwrap_err();
    assert!(
        matches!(&e, OnnxError::MissingOutput { output, .. } if output == "scores"),
        "{e}"
    );
    let twice = [
        TensorInput::new("motion", &shape, &data),
        TensorInput::new("motion", &shape, &data),
    ];
    let e = net.run(&twice, &["logits"]).unwrap_err();
    assert!(matches!(e, OnnxError::Contract { .. }), "{e}");
}
