//! Inputs found by fuzzing (`crates/mp-fuzz`, targets `npy`, `csv` and
//! `people`, and one written after a `csv` input the fuzzer reported as slow)
//! that made a track reader abort or stall; each must now be a quick,
//! typed error or a quick read.

use std::path::Path;
use std::time::{Duration, Instant};

use crate::io::csv::{track_from_csv_str, track_to_csv_string, CsvLayout};
use crate::io::native::track_from_npy_bytes;
use crate::io::npz::NpyArray;
use crate::io::ReadOptions;
use crate::GeomError;

/// Shape `(8, 99999999999, 0)`: no data, yet a generic skeleton of 10^11
/// joints was built for it (allocation failure).
const NPY_EMPTY_HUGE_JOINTS: &[u8] = b"\x93NUMPY\x01\x00\x80\x00{'descr': '<f4', 'fortran_order': False, 'shape': (8, 99999999999,\x090)}                                                         
";

/// A header opening 41 `{`: the header parser took exponential time.
const NPY_NESTED_HEADER: &[u8] = b"\x93NUMPY\x01\x00\x94\x00{{{{{{{{{{{{{{{{{{{{{{{{{{{{{{{'descr': '<fT', 'fortran_order': False, 'shape': (2, 3, 2)}                                                         
";

/// A long CSV whose joint index 8880 makes a track of 8881 joints; writing
/// it as wide CSV and reading that back was quadratic in the joints.
const CSV_MANY_JOINTS: &[u8] = b"# a ent
frame,joint,x,y,z,score
0,08880,3,888888888888,1,2";

fn quick(start: Instant) {
    assert!(
        start.elapsed() < Duration::from_secs(2),
        "took {:?}",
        start.elapsed()
    );
}

#[test]
fn npy_without_values_is_an_error() {
    let start = Instant::now();
    let e = track_from_npy_bytes(
        NPY_EMPTY_HUGE_JOINTS,
        Path::new("f.npy"),
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, GeomError::Format { .. }), "{e}");
    assert!(e.to_string().contains("hold no values"), "{e}");
    quick(start);
}

#[test]
fn deeply_nested_npy_header_is_an_error() {
    let start = Instant::now();
    let e = NpyArray::from_bytes(NPY_NESTED_HEADER, "f.npy").unwrap_err();
    assert!(e.to_string().contains("nest deeper"), "{e}");
    quick(start);
}

#[test]
fn wide_csv_of_many_joints_reads_back_quickly() {
    let start = Instant::now();
    let path = Path::new("f.csv");
    let opts = ReadOptions::default();
    let t = track_from_csv_str(&String::from_utf8_lossy(CSV_MANY_JOINTS), path, &opts).unwrap();
    assert_eq!(t.n_joints(), 8881);
    let wide = track_to_csv_string(&t, CsvLayout::Wide).unwrap();
    let u = track_from_csv_str(&wide, path, &opts).unwrap();
    assert_eq!(u.positions().dim(), t.positions().dim());
    quick(start);
}

/// Two rows, one naming frame 100 000 and one joint 100 000: each index alone
/// was within the reader's guard, together they asked for 10^10 cells (the
/// process aborted on the allocation).
const CSV_HUGE_FRAME_AND_JOINT: &str = "frame,joint,x,y,score
100000,0,1,2,1
0,100000,3,4,1
";

#[test]
fn sparse_csv_implying_too_many_cells_is_an_error() {
    let e = track_from_csv_str(
        CSV_HUGE_FRAME_AND_JOINT,
        Path::new("f.csv"),
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, GeomError::Format { .. }), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("f.csv") && msg.contains("100000") && msg.contains("10000000"),
        "{msg}"
    );
    // A sparse file within the limit still reads: frame 99 999 of joint 0.
    let ok = "frame,joint,x,y,score\n99999,0,1,2,1\n0,0,3,4,1\n";
    let t = track_from_csv_str(ok, Path::new("g.csv"), &ReadOptions::default()).unwrap();
    assert_eq!((t.n_frames(), t.n_joints()), (100_000, 1));
}

/// A coordinate of 10^300 is finite, so it used to be kept; every fit then
/// squared it to infinity ("segment cost … is NaN") and counting found
/// nothing. It is now an error naming the value, the joint and the frame.
#[test]
fn coordinates_beyond_the_limit_are_an_error() {
    let csv = "frame,joint,x,y,score\n0,0,1,2,1\n1,0,1e300,2,1\n";
    let e = track_from_csv_str(csv, Path::new("f.csv"), &ReadOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("1e300") && msg.contains("frame 1") && msg.contains("1e100"),
        "{msg}"
    );
    let ok = "frame,joint,x,y,score\n0,0,1,2,1\n1,0,1e99,2,1\n";
    assert!(track_from_csv_str(ok, Path::new("g.csv"), &ReadOptions::default()).is_ok());
}

/// A people file (JSON) of 2⁶⁴ − 1 frames holding a short track: it read,
/// and the main person's whole-video track then overflowed ndarray's shape
/// (a panic; 10¹² frames aborted on the allocation).
#[test]
fn people_file_of_too_many_frames_is_an_error() {
    let text = r#"{"format":"mp-people","version":1,"n_frames":18446744073709551615,"fps":30.0,"people":[{"id":3,"first_frame":0,"track":{"confidence":[[0.9],[0.9]],"format":"mp-track","fps":30.0,"positions":[[[0.0,25.0]],[[6.25,24.25]]],"skeleton":{"bones":[],"coco17":[],"joints":["j0"],"name":"generic","root":null},"units":"pixels","version":1}}]}"#;
    for frames in ["18446744073709551615", "1000000000000"] {
        let text = text.replace("18446744073709551615", frames);
        let start = Instant::now();
        let err = crate::io::people::people_from_json_str(&text, Path::new("p.json"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("whole-video track may hold"), "{err}");
        quick(start);
    }
}
