//! Inputs found by fuzzing (`crates/mp-fuzz`) that made a reader of
//! concrete programs panic or stall; each must now be a quick, typed error.

use crate::{ConcreteError, Program};

/// `dims=2222222222222222222`: every statement listed that many axis names
/// (capacity overflow).
const HUGE_DIMS_CRASH: &[u8] = b"#\x1fAnmgent.
program(fps=30, units=px, dims=2222222222222222222, skeleton=\"pe ann13\")

joint \"ri -0.25*t + 0.125, z=2*t^3 + 0ght_wrist\" {
    circular_motion(center=(220.56, 175.67), radius=108.23, angle=3.1777777777777777777*t + 79.99, duration=7) stationary(x=129.25, y=121.59, duration=4);#spl3*t + 4, duration=2)
}
";

/// `dims=22222222`: the same, slow enough to stall the parser.
const HUGE_DIMS_HANG: &[u8] = b"#3 + -1*t^2 + 2*t +  Anng after '#' is a comment.
program(fps=30, units=px, dims=22222222, skeleton=\"pdnn13\")

joint \"rig.25, ht_writt\" {
circular_motion(center=(220.56, 175.67), radius=108.23, angle=3.17*t + 7777777777777777799, duration=444444444444444444);
   #splix=129.25, y=121.59, duration=4);
   #spmine(x=0.5*t^3 + -1*t^2 + 2*t + 3, y=1e-3*t@+ 4, duration=2)
}
";

fn dsl(bytes: &[u8]) -> crate::error::Result<Program> {
    Program::from_dsl(&String::from_utf8_lossy(bytes))
}

#[test]
fn huge_dims_is_a_parse_error() {
    for input in [HUGE_DIMS_CRASH, HUGE_DIMS_HANG] {
        let start = std::time::Instant::now();
        let e = dsl(input).unwrap_err();
        assert!(matches!(e, ConcreteError::Parse { .. }), "{e}");
        assert!(
            start.elapsed().as_secs_f64() < 1.0,
            "took {:?}",
            start.elapsed()
        );
    }
    let e = dsl(HUGE_DIMS_CRASH).unwrap_err().to_string();
    assert!(e.contains("a point of 2222222222222222222 numbers"), "{e}");
}

#[test]
fn axis_names_of_many_dimensions() {
    let ok = "program(fps=30, units=unitless, dims=4)\n\
              joint \"a\" { stationary(x0=1, x1=2, x2=3, x3=4, duration=2) }";
    assert_eq!(Program::from_dsl(ok).unwrap().dims, 4);
    for (bad, key) in [("x4", "x4"), ("x01", "x01"), ("y", "y")] {
        let text = ok.replace("x3=4", &format!("{bad}=4"));
        let e = Program::from_dsl(&text).unwrap_err().to_string();
        assert!(e.contains(&format!("`{key}`")), "{e}");
        assert!(e.contains("`x0`, `x1`, `x2`, `x3`, `duration`"), "{e}");
    }
    let big = "program(fps=30, units=unitless, dims=100000000000)\n\
               joint \"a\" { stationary(x0=1, q=2, duration=2) }";
    let e = Program::from_dsl(big).unwrap_err().to_string();
    assert!(e.contains("`x0` … `x99999999999`, `duration`"), "{e}");
}
