//! The binary track form (`.mpt`): exact round trips, and corrupt,
//! truncated or random bytes rejected with an error, never a panic.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::io::native::{BINARY_MAGIC, BINARY_VERSION};
use crate::io::{read_track, write_track};
use crate::{track_from_bincode, track_to_bincode};
use crate::{GeomError, Skeleton, Track, Units};
use ndarray::{Array2, Array3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

fn msr_like(t: usize) -> Track {
    let p = Array3::from_shape_fn((t, 20, 3), |(f, j, k)| {
        (f as f64 * 0.1).sin() * (j + 1) as f64 / 7.0 + k as f64 / 3.0
    });
    let mut c = Array2::from_elem((t, 20), 0.5);
    if t > 1 {
        c[[1, 3]] = 0.0;
    }
    Track::new(p, Some(c), 15.0, Units::Metres, Skeleton::msr20()).unwrap()
}

fn coco_2d(t: usize) -> Track {
    let p = Array3::from_shape_fn((t, 17, 2), |(f, j, k)| {
        100.0 + f as f64 * 1.5 - j as f64 * 3.25 + k as f64 * 1e-300
    });
    Track::new(p, None, 29.97, Units::Pixels, Skeleton::coco17()).unwrap()
}

fn custom(t: usize) -> Track {
    let sk = Skeleton::custom(
        "bvh",
        vec!["hip".into(), "knee".into(), "ünïcode joint".into()],
        vec![(0, 1), (1, 2)],
        Some(0),
    );
    let p = Array3::from_shape_fn((t, 3, 3), |(f, j, k)| (f * 9 + j * 3 + k) as f64 * -0.25);
    Track::new(p, None, 120.0, Units::Unitless, sk).unwrap()
}

fn samples() -> Vec<Track> {
    vec![msr_like(9), coco_2d(4), custom(5), custom(0), msr_like(1)]
}

#[test]
fn round_trips_exactly_in_memory_and_through_mpt_files() {
    let dir = tempfile::tempdir().unwrap();
    for tr in samples() {
        let bytes = track_to_bincode(&tr).unwrap();
        assert!(bytes.starts_with(BINARY_MAGIC));
        assert_eq!(track_from_bincode(&bytes).unwrap(), tr);
        let p = dir.path().join("t.mpt");
        write_track(&p, &tr).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), bytes);
        assert_eq!(read_track(&p).unwrap(), tr, "{}", tr.skeleton().name);
    }
    // The upper-case extension dispatches too, and only the final file remains.
    let tr = msr_like(3);
    let p = dir.path().join("T.MPT");
    write_track(&p, &tr).unwrap();
    assert_eq!(read_track(&p).unwrap(), tr);
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, vec!["T.MPT", "t.mpt"]);
}

#[test]
fn binary_is_compact() {
    // 9 frames × 20 joints × 3 values plus confidence: 8 bytes per number
    // and a small header (skeleton names included).
    let tr = msr_like(9);
    let bytes = track_to_bincode(&tr).unwrap();
    let numbers = 9 * 20 * 3 + 9 * 20;
    assert!(bytes.len() >= numbers * 8);
    assert!(bytes.len() < numbers * 8 + 600, "{} bytes", bytes.len());
    let json = crate::io::native::track_to_json_string(&tr).unwrap();
    assert!(bytes.len() < json.len());
}

#[test]
fn every_truncation_is_an_error() {
    for tr in samples() {
        let bytes = track_to_bincode(&tr).unwrap();
        for n in 0..bytes.len() {
            let e = track_from_bincode(&bytes[..n]).unwrap_err();
            assert!(matches!(e, GeomError::Format { .. }), "{n}: {e}");
            let msg = e.to_string();
            assert!(
                msg.contains("truncated") || msg.contains("does not start with"),
                "cut at {n} of {}: {msg}",
                bytes.len()
            );
        }
    }
}

#[test]
fn trailing_bytes_wrong_magic_and_newer_versions_are_refused() {
    let bytes = track_to_bincode(&coco_2d(2)).unwrap();
    let mut long = bytes.clone();
    long.extend_from_slice(&[0, 0, 0]);
    let e = track_from_bincode(&long).unwrap_err().to_string();
    assert!(e.contains("3 bytes after the end"), "{e}");

    let mut other = bytes.clone();
    other[0] = b'M';
    let e = track_from_bincode(&other).unwrap_err().to_string();
    assert!(e.contains("not an mp-track binary"), "{e}");

    let mut newer = bytes.clone();
    let at = BINARY_MAGIC.len();
    newer[at..at + 4].copy_from_slice(&(BINARY_VERSION + 1).to_le_bytes());
    let e = track_from_bincode(&newer).unwrap_err().to_string();
    assert!(e.contains("version 2 is not supported"), "{e}");

    // A program file is not a track.
    let e = track_from_bincode(b"mp-program\x01\0\0\0")
        .unwrap_err()
        .to_string();
    assert!(e.contains("not an mp-track binary"), "{e}");
}

#[test]
fn random_bytes_are_errors_not_panics() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let header: Vec<u8> = BINARY_MAGIC
        .iter()
        .copied()
        .chain(BINARY_VERSION.to_le_bytes())
        .collect();
    for i in 0..2000 {
        let n = rng.random_range(0..400);
        let mut b: Vec<u8> = (0..n).map(|_| rng.random()).collect();
        assert!(track_from_bincode(&b).is_err());
        // Behind a valid header the record itself is random.
        if i % 2 == 0 {
            b.splice(0..0, header.iter().copied());
        } else {
            // Plausible start: finite fps, a valid unit, then noise.
            let mut start = header.clone();
            start.extend_from_slice(&30.0f64.to_le_bytes());
            start.push(rng.random_range(0..3));
            b.splice(0..0, start);
        }
        assert!(track_from_bincode(&b).is_err(), "case {i}");
    }
}

#[test]
fn flipped_bytes_never_panic() {
    let bytes = track_to_bincode(&custom(2)).unwrap();
    for i in 0..bytes.len() {
        for flip in [0x01u8, 0x80, 0xff] {
            let mut b = bytes.clone();
            b[i] ^= flip;
            // Either an error or a track that passed every check.
            if let Ok(t) = track_from_bincode(&b) {
                assert!(t.positions().iter().all(|v| v.is_finite()));
                assert!(t.fps().is_finite() && t.fps() > 0.0);
            }
        }
    }
}

/// The documented record layout, to write inconsistent records on purpose.
#[derive(Serialize)]
struct Rec {
    fps: f64,
    units: Units,
    skeleton: Skeleton,
    shape: [u64; 3],
    positions: Vec<f64>,
    confidence: Vec<f64>,
}

fn encode(rec: &Rec) -> Vec<u8> {
    let mut out = BINARY_MAGIC.to_vec();
    out.extend_from_slice(&BINARY_VERSION.to_le_bytes());
    out.extend(bincode::serde::encode_to_vec(rec, bincode::config::standard()).unwrap());
    out
}

fn good_rec() -> Rec {
    let tr = custom(2);
    Rec {
        fps: tr.fps(),
        units: tr.units(),
        skeleton: tr.skeleton().clone(),
        shape: [2, 3, 3],
        positions: tr.positions().iter().copied().collect(),
        confidence: tr.confidence().iter().copied().collect(),
    }
}

#[test]
fn decoded_records_are_validated() {
    assert_eq!(track_from_bincode(&encode(&good_rec())).unwrap(), custom(2));

    let check = |rec: Rec, want: &str| {
        let e = track_from_bincode(&encode(&rec)).unwrap_err().to_string();
        assert!(e.contains(want), "expected `{want}` in `{e}`");
    };
    check(
        Rec {
            shape: [3, 3, 3],
            ..good_rec()
        },
        "positions hold 18 values, shape (3, 3, 3) needs 27",
    );
    check(
        Rec {
            confidence: vec![1.0; 5],
            ..good_rec()
        },
        "confidence holds 5 values, shape (2, 3) needs 6",
    );
    check(
        Rec {
            shape: [u64::MAX, u64::MAX, 2],
            ..good_rec()
        },
        "overflows",
    );
    for fps in [f64::NAN, f64::INFINITY, 0.0, -30.0] {
        check(Rec { fps, ..good_rec() }, "fps");
    }
    let mut rec = good_rec();
    rec.skeleton.bones.push((0, 3));
    check(rec, "refers to a joint outside 0..3");
    let mut rec = good_rec();
    rec.skeleton.root = Some(7);
    check(rec, "refers to a joint outside 0..3");
    let mut rec = good_rec();
    rec.skeleton.coco17 = vec![Some(0); 5];
    check(rec, "COCO-17 mapping has 5 entries");
    let mut rec = good_rec();
    rec.skeleton.joints.pop();
    check(rec, "skeleton `bvh` has 2 joints but positions have 3");
    check(
        Rec {
            shape: [2, 3, 4],
            positions: vec![0.0; 24],
            units: Units::Metres,
            ..good_rec()
        },
        "2 or 3 dimensions",
    );
    // Non-finite positions become missing joints, as in every reader.
    let mut rec = good_rec();
    rec.positions[4] = f64::NAN;
    rec.units = Units::Metres;
    let t = track_from_bincode(&encode(&rec)).unwrap();
    assert_eq!(t.confidence()[[0, 1]], 0.0);
    assert!(t.positions().iter().all(|v| v.is_finite()));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn any_track_round_trips(
        t in 0usize..6,
        j in 1usize..5,
        d in 2usize..4,
        seed in any::<u64>(),
        fps in 0.5f64..500.0,
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let specials = [0.0, -0.0, f64::MIN_POSITIVE, 5e-324, crate::track::MAX_COORDINATE, -1e100];
        let pos = Array3::from_shape_fn((t, j, d), |_| {
            if rng.random_bool(0.2) {
                specials[rng.random_range(0..specials.len())]
            } else {
                rng.random_range(-1e3..1e3)
            }
        });
        let conf = Array2::from_shape_fn((t, j), |_| rng.random_range(0.0..=1.0));
        let tr = Track::new(pos, Some(conf), fps, Units::Metres, Skeleton::generic(j)).unwrap();
        let back = track_from_bincode(&track_to_bincode(&tr).unwrap()).unwrap();
        // Bit-exact, signed zeros included.
        let bits = |t: &Track| t.positions().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        prop_assert_eq!(bits(&back), bits(&tr));
        prop_assert_eq!(back, tr);
    }
}
