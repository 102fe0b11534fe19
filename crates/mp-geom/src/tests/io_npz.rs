//! npy/npz reading: every dtype of the shared data, hand-made headers for
//! the rarer layouts, and typed errors for broken input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::io::npz::{read_npy, DType, NpyArray, Npz, NpzOut};
use crate::GeomError;
use ndarray::{arr0, array, Array2};

/// The shared data file `rel`, or the test records its skip and returns.
macro_rules! data {
    ($rel:expr) => {
        crate::data_or_return!($rel)
    };
}

/// A version-1.0 `.npy` with the given header dict and raw data.
fn npy_bytes(dict: &str, data: &[u8]) -> Vec<u8> {
    let unpadded = 10 + dict.len() + 1;
    let pad = (64 - unpadded % 64) % 64;
    let mut v = b"\x93NUMPY\x01\x00".to_vec();
    v.extend_from_slice(&((dict.len() + pad + 1) as u16).to_le_bytes());
    v.extend_from_slice(dict.as_bytes());
    v.extend(std::iter::repeat_n(b' ', pad));
    v.push(b'\n');
    v.extend_from_slice(data);
    v
}

#[test]
fn penn_npz_every_dtype() {
    let z = Npz::open(data!("penn_action/penn_action_train.npz")).unwrap();
    let names = z.names().to_vec();
    for k in [
        "action",
        "bbox",
        "clip_id",
        "dimensions",
        "keypoints",
        "offsets",
        "train",
        "view",
        "visibility",
    ] {
        assert!(names.contains(&k.to_string()), "{k} missing from {names:?}");
    }
    // <U15
    let action = z.array("action").unwrap();
    assert_eq!(action.dtype, DType::Unicode(15));
    let action = action.to_strings().unwrap();
    assert_eq!(action.len(), 1258);
    assert_eq!(action[0], "baseball_pitch");
    assert_eq!(
        z.strings("clip_id").unwrap()[..2],
        ["0002".to_string(), "0003".to_string()]
    );
    // f4
    let kp = z.array_f64("keypoints").unwrap();
    assert_eq!(kp.shape(), &[87543, 13, 2]);
    assert_eq!((kp[[0, 0, 0]], kp[[0, 0, 1]]), (48.0, 52.0));
    // u1 visibility, i1 train, i4 dimensions, i8 offsets
    let vis = z.array_i64("visibility").unwrap();
    assert_eq!(vis.slice(ndarray::s![0, 0..4]).to_vec(), vec![1, 1, 0, 1]);
    assert!(z.array_i64("train").unwrap().iter().all(|&v| v == 1));
    let dims = z.array_i64("dimensions").unwrap();
    assert_eq!(dims.slice(ndarray::s![0, ..]).to_vec(), vec![270, 480, 80]);
    let off = z.array_i64("offsets").unwrap();
    assert_eq!(off.len(), 1259);
    assert_eq!(off[[1258]], 87543);
    // floats are refused as integers, strings as numbers
    assert!(matches!(z.array_i64("bbox"), Err(GeomError::Format { .. })));
    assert!(z.array_f64("action").is_err());
}

#[test]
fn msr_i2_and_reference_bool_scalars() {
    let m = Npz::open(data!("msr_action3d/msr_action3d_odd_subjects.npz")).unwrap();
    let a = m.array("action").unwrap();
    assert_eq!(a.dtype, DType::Int(2));
    assert_eq!(a.to_i64().unwrap().len(), 292);
    let r = Npz::open(data!("reference_keypoints/golf_swing.npz")).unwrap();
    assert_eq!(r.array("found").unwrap().dtype, DType::Bool);
    assert!(r.array_f64("found").unwrap().iter().all(|&v| v == 1.0));
    assert!((r.scalar_f64("fps").unwrap() - 29.97).abs() < 1e-12);
    assert_eq!(r.scalar_f64("width").unwrap(), 354.0);
    assert_eq!(r.array("height").unwrap().dtype, DType::Int(4));
    assert!(r.scalar_f64("found").is_err(), "not a scalar");
}

#[test]
fn big_endian_and_fortran_order() {
    // >f8, shape (2, 3), Fortran order: memory holds columns.
    let vals = [1.0f64, 4.0, 2.0, 5.0, 3.0, 6.0];
    let mut data = Vec::new();
    for v in vals {
        data.extend_from_slice(&v.to_be_bytes());
    }
    let b = npy_bytes(
        "{'descr': '>f8', 'fortran_order': True, 'shape': (2, 3), }",
        &data,
    );
    let a = NpyArray::from_bytes(&b, "mem").unwrap();
    let f = a.to_f64().unwrap();
    assert_eq!(f, array![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]].into_dyn());
    // <u2 and >i4
    let b = npy_bytes(
        "{'descr': '<u2', 'fortran_order': False, 'shape': (2,), }",
        &[1, 1, 255, 255],
    );
    assert_eq!(
        NpyArray::from_bytes(&b, "m")
            .unwrap()
            .to_i64()
            .unwrap()
            .into_raw_vec_and_offset()
            .0,
        vec![257, 65535]
    );
    let b = npy_bytes(
        "{'descr': '>i4', 'fortran_order': False, 'shape': (1,), }",
        &(-7i32).to_be_bytes(),
    );
    assert_eq!(
        NpyArray::from_bytes(&b, "m").unwrap().scalar_f64().unwrap(),
        -7.0
    );
    // |S bytes strings
    let b = npy_bytes(
        "{'descr': '|S3', 'fortran_order': False, 'shape': (2,), }",
        b"ab\0xyz",
    );
    assert_eq!(
        NpyArray::from_bytes(&b, "m").unwrap().to_strings().unwrap(),
        vec!["ab", "xyz"]
    );
}

#[test]
fn unsupported_dtype_and_truncated_data() {
    let b = npy_bytes(
        "{'descr': '|O', 'fortran_order': False, 'shape': (1,), }",
        &[0; 8],
    );
    let e = NpyArray::from_bytes(&b, "obj.npy").unwrap_err();
    assert!(e.to_string().contains("unsupported dtype `|O`"), "{e}");
    let b = npy_bytes(
        "{'descr': '<f2', 'fortran_order': False, 'shape': (1,), }",
        &[0; 2],
    );
    assert!(NpyArray::from_bytes(&b, "h.npy")
        .unwrap_err()
        .to_string()
        .contains("<f2"));
    let b = npy_bytes(
        "{'descr': '<f8', 'fortran_order': False, 'shape': (4,), }",
        &[0; 16],
    );
    let e = NpyArray::from_bytes(&b, "short.npy").unwrap_err();
    assert!(e.to_string().contains("truncated"), "{e}");
    let e = NpyArray::from_bytes(b"not an npy file at all", "junk.npy").unwrap_err();
    assert!(matches!(e, GeomError::Format { .. }), "{e}");
}

#[test]
fn stored_and_compressed_written_archives_read_back() {
    let a: Array2<f32> = array![[1.5, -2.0], [3.25, 4.0]];
    let names: Vec<String> = vec!["squat".into(), "jumping_jacks".into()];
    for compressed in [false, true] {
        let mut out = NpzOut::new(compressed);
        out.add("a", &a).unwrap();
        out.add("n", &arr0(7i16)).unwrap();
        out.add("flags", &array![true, false, true]).unwrap();
        out.add_strings("names", &names, &[2]).unwrap();
        let bytes = out.finish().unwrap();
        let z = Npz::from_bytes(bytes, "mem.npz").unwrap();
        assert_eq!(z.names(), &["a", "flags", "n", "names"]);
        assert_eq!(z.array_f64("a").unwrap(), a.mapv(f64::from).into_dyn());
        assert_eq!(z.scalar_f64("n").unwrap(), 7.0);
        assert_eq!(
            z.array_i64("flags").unwrap().into_raw_vec_and_offset().0,
            vec![1, 0, 1]
        );
        assert_eq!(z.strings("names").unwrap(), names);
    }
}

#[test]
fn read_npy_file_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.npy");
    let b = npy_bytes(
        "{'descr': '<i8', 'fortran_order': False, 'shape': (3,), }",
        &{
            let mut d = Vec::new();
            for v in [5i64, -1, 9] {
                d.extend_from_slice(&v.to_le_bytes());
            }
            d
        },
    );
    std::fs::write(&p, b).unwrap();
    assert_eq!(
        read_npy(&p)
            .unwrap()
            .to_i64()
            .unwrap()
            .into_raw_vec_and_offset()
            .0,
        vec![5, -1, 9]
    );
    let e = read_npy(dir.path().join("missing.npy")).unwrap_err();
    assert!(matches!(e, GeomError::Io { .. }));
    assert!(e.to_string().contains("missing.npy"));
}

#[test]
fn npz_errors_are_typed_and_named() {
    let dir = tempfile::tempdir().unwrap();
    // Missing file.
    let e = Npz::open(dir.path().join("nope.npz")).unwrap_err();
    assert!(matches!(e, GeomError::Io { .. }), "{e}");
    assert!(e.to_string().contains("nope.npz"));
    // Random bytes.
    let junk = dir.path().join("junk.npz");
    let bytes: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    std::fs::write(&junk, &bytes).unwrap();
    let e = Npz::open(&junk).unwrap_err();
    assert!(matches!(e, GeomError::Format { .. }), "{e}");
    assert!(e.to_string().contains("not a valid .npz"), "{e}");
    // Truncated real file: either the archive or the member read fails, never a panic.
    let full = std::fs::read(data!("cmu_mocap6_exercise/13_29_features10fps.npz")).unwrap();
    for cut in [full.len() / 2, full.len() - 30, 100] {
        let r = Npz::from_bytes(full[..cut].to_vec(), "cut.npz").and_then(|z| z.array_f64("X"));
        assert!(r.is_err(), "cut at {cut} read fine");
    }
    // Corrupted compressed payload (header intact): the member read fails.
    let mut bad = full.clone();
    for b in bad.iter_mut().skip(200).take(2000) {
        *b ^= 0x5a;
    }
    if let Ok(z) = Npz::from_bytes(bad, "flipped.npz") {
        assert!(z.array_f64("X").is_err() || z.array_f64("labels").is_err());
    }
    // Wrong key: names the key and lists the available ones.
    let z = Npz::open(data!("cmu_mocap6_exercise/13_29_features10fps.npz")).unwrap();
    let e = z.array_f64("Y").unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("`Y`") && msg.contains("X, action_names, labels"),
        "{msg}"
    );
    // Wrong shape.
    let e = z.array_f64_shaped("X", &[None, Some(13)]).unwrap_err();
    assert!(
        e.to_string().contains("(382, 12)") || e.to_string().contains("[382, 12]"),
        "{e}"
    );
}
