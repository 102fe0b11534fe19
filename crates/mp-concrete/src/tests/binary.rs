//! The binary program form (`.mpb`): exact round trips of synthesised and
//! hand-written programs, validation on decode, and corrupt, truncated or
//! random bytes rejected with an error, never a panic.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::program::{BINARY_MAGIC, BINARY_VERSION};
use crate::synthetic::synthetic_track;
use crate::{ConcreteError, Program, Segment, SynthParams};
use mp_geom::{GeomError, Primitive, Units};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn all_kinds_3d() -> Program {
    Program {
        fps: 120.0,
        units: Units::Metres,
        dims: 3,
        skeleton: "bvh".into(),
        joints: vec!["hip".into(), "lHand".into()],
        continuity: crate::Continuity::C0,
        segments: vec![
            Segment {
                duration_frames: 12,
                primitives: vec![
                    Primitive::Stationary {
                        point: vec![0.0, -0.0, 1.25],
                    },
                    Primitive::Circle {
                        center: vec![0.1, 1.2, 0.3],
                        radius: 0.4,
                        angle_start: -90.0,
                        angle_vel: 6.5,
                        angle_acc: -0.125,
                        axes: vec![vec![1.0, 0.0, 0.0], vec![0.0, 0.0, 1.0]],
                    },
                ],
            },
            Segment {
                duration_frames: 1,
                primitives: vec![
                    Primitive::Line {
                        start: vec![5e-324, f64::MAX, -1e-300],
                        velocity: vec![0.01, 0.0, -0.02],
                    },
                    Primitive::Spline {
                        coeffs: vec![[1.0, 2.0, 3.0, 4.0], [0.0; 4], [-1e-9, 0.5, 0.25, 9.0]],
                    },
                ],
            },
        ],
    }
}

fn synthesised() -> Program {
    let track = synthetic_track(90, 3).unwrap();
    Program::synthesize(&track, &SynthParams::paper()).unwrap()
}

#[test]
fn round_trips_exactly() {
    for p in [all_kinds_3d(), synthesised()] {
        let bytes = p.to_bincode().unwrap();
        assert!(bytes.starts_with(BINARY_MAGIC));
        let q = Program::from_bincode(&bytes).unwrap();
        assert_eq!(q.to_dsl(), p.to_dsl());
        assert_eq!(q, p);
        // Smaller than the JSON form.
        assert!(bytes.len() < p.to_json().unwrap().len());
    }
}

#[test]
fn every_truncation_is_an_error() {
    let bytes = all_kinds_3d().to_bincode().unwrap();
    for n in 0..bytes.len() {
        let e = Program::from_bincode(&bytes[..n]).unwrap_err();
        assert!(
            matches!(e, ConcreteError::Geom(GeomError::Format { .. })),
            "cut at {n}: {e}"
        );
        let msg = e.to_string();
        assert!(
            msg.contains("truncated") || msg.contains("does not start with"),
            "cut at {n}: {msg}"
        );
    }
}

#[test]
fn random_and_flipped_bytes_are_errors_not_panics() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let header: Vec<u8> = BINARY_MAGIC
        .iter()
        .copied()
        .chain(BINARY_VERSION.to_le_bytes())
        .collect();
    for i in 0..2000 {
        let n = rng.random_range(0..300);
        let mut b: Vec<u8> = (0..n).map(|_| rng.random()).collect();
        assert!(Program::from_bincode(&b).is_err());
        b.splice(0..0, header.iter().copied());
        assert!(Program::from_bincode(&b).is_err(), "case {i}");
    }
    let bytes = all_kinds_3d().to_bincode().unwrap();
    for i in 0..bytes.len() {
        for flip in [0x01u8, 0x40, 0xff] {
            let mut b = bytes.clone();
            b[i] ^= flip;
            // Either an error or a program that passes validation.
            if let Ok(p) = Program::from_bincode(&b) {
                p.validate().unwrap();
            }
        }
    }
}

#[test]
fn decoded_programs_are_validated() {
    let bytes = all_kinds_3d().to_bincode().unwrap();
    // The record starts with fps (8 bytes) right after magic and version.
    let at = BINARY_MAGIC.len() + 4;
    for fps in [f64::NAN, f64::INFINITY, 0.0, -30.0] {
        let mut b = bytes.clone();
        b[at..at + 8].copy_from_slice(&fps.to_le_bytes());
        let e = Program::from_bincode(&b).unwrap_err();
        assert!(matches!(e, ConcreteError::Program(_)), "{e}");
        assert!(e.to_string().contains("fps must be finite and > 0"), "{e}");
    }
    // Rename joint `lHand` in place: to `hip_2` (valid), then to `hip`
    // (shorter, length prefix adjusted), which duplicates joint 0.
    let k = bytes.windows(5).position(|w| w == b"lHand").unwrap();
    let mut b = bytes.clone();
    b[k..k + 5].copy_from_slice(b"hip_2");
    assert_eq!(Program::from_bincode(&b).unwrap().joints[1], "hip_2");
    let mut b = bytes.clone();
    b.splice(k..k + 5, *b"hip");
    b[k - 1] = 3;
    let e = Program::from_bincode(&b).unwrap_err();
    assert!(matches!(e, ConcreteError::Program(_)), "{e}");
    assert!(
        e.to_string().contains("joint name `hip` appears twice"),
        "{e}"
    );
}

#[test]
fn encoding_refuses_invalid_programs_and_decoding_applies_the_same_rules() {
    let mut p = all_kinds_3d();
    p.segments[1].primitives[0] = Primitive::Line {
        start: vec![0.0; 3],
        velocity: vec![0.0; 2],
    };
    let msg = p.to_bincode().unwrap_err().to_string();
    assert!(msg.contains("line velocity has 2 values, start 3"), "{msg}");
    let msg = p
        .write("/nonexistent-folder/p.mpb")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("line velocity"), "{msg}");
}

#[test]
fn read_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.mpb");
    let bytes = synthesised().to_bincode().unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let msg = Program::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("cut.mpb: truncated mp-program binary"),
        "{msg}"
    );
    // A track is not a program.
    let track = synthetic_track(10, 1).unwrap();
    std::fs::write(&path, mp_geom::track_to_bincode(&track).unwrap()).unwrap();
    let msg = Program::read(&path).unwrap_err().to_string();
    assert!(msg.contains("not an mp-program binary"), "{msg}");
}
