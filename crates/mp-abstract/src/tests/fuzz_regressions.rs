//! Inputs found by fuzzing (`crates/mp-fuzz`, targets `abstract_json` and
//! `abstract_dsl`): abstract programs that read from JSON but could not be
//! written as text and read back (units and joint names the text form
//! cannot hold), and duration counts whose total overflowed. Each is now
//! rejected with a typed error, or reads back unchanged.

use crate::{dsl, AbstractError, AbstractProgram};
use std::path::Path;

/// A joint called `right\x7fwrist` (DEL inside the name).
const CONTROL_CHAR_IN_JOINT: &[u8] = b"{
  \"fps\": 30.0,
  \"units\": \"px\",
  \"dims\": 2,
  \"unit_scale\": 1.0,
  \"joints\": [
    \"right\x7fwrist\",
    \"neck\"
  ],
  \"stmts\": [
    {
      \"kind\": \"prim\",
      \"duration\": 7,
      \"points\": [
        [
          10.825317547305485,
          7.249999999999999,
          9.067179637653595,
          9.604432196171924,
          6.807987937687838,
          11.4833820993178
        ],
        [
          20.825317547305485,
          17.25,
          19.067179637653595,
          19.604432196171924,
          16.807987937687837,
          21.4833820993178
        ]
      ]
    },
    {
      \"kind\": \"prim\",
      \"duration\": 4,
      \"points\": [
        [
          0.5,
          1.5,
          0.5,
          1.5,
          0.5,
          1.5
        ],
        [
          10.5,
          11.5,
          10.5,
          11.5,
          10.5,
          11.5
        ]
      ]
    },
    {
      \"kind\": \"prim\",
      \"duration\": 5,
      \"points\": [
        [
          1.0,
          2.0,
          0.0,
          1.5,
          -1.0,
          1.0
        ],
        [
          11.0,
          12.0,
          10.0,
          11.5,
          9.0,
          11.0
        ]
      ]
    }
  ]
}";

/// `"units": "x"`.
const UNKNOWN_UNITS: &[u8] = b"{
  \"fps\": 71.1,
  \"units\": \"x\",
  \"dims\":\x093,
  \"unit_scale\": 1.1,
  \"joints\": [ \"d\"
  ],
  \"stmts\": [
    {   \"kind\": \"prim\",
      \"duration\": 4,
      \"points\": [
    [
  0.069,   0.052,
      0.046,
          0.248,
          1.922,
          7.584,
  1.588,
  9.945,
  17.885 ]
  ]
    },
    {
      \"kind\": \"prim\",
      \"duration\": 9,
      \"points\": [     [
  0.6,
          1.5,
          9.9,
          0.89,
          1.952,
          7.9,
          0.0,
          1.64,
          3.2 ]
      ]
    }
  ]
}";

/// `"units": "m  "` (printed as `units=m  `, read back as `m`).
const UNITS_WITH_SPACES: &[u8] = b"{
  \"fps\": 30.0,
  \"units\": \"m  \",
  \"dims\": 3,
  \"unit_scale\": 1.0,
  \"joints\": [ \"a\"
  ],
  \"stmts\": [
    {   \"kind\": \"prim\",
      \"duration\": 3,
      \"points\": [
    [
  0.169,   0.055,
  0.045,
          0.348,
          1.925,
          2.284,
  1.595,
  9.625,
  17.625 ]
  ]
    },
    {
      \"kind\": \"prim\",
      \"duration\": 2,
      \"points\": [     [
  0.5,
  1.5,
          2.5,
          0.89,
          1.905485,
       2.5,
          0.0,
          1.64,
          2.5 ]
      ]
    }
  ]
}";

/// A duration of 2222222222222222222 frames (printed, then refused by the
/// text form's integers).
const HUGE_DURATION: &[u8] = b"{
  \"fps\": 30.0,
  \"units\": \"m\",
  \"dims\": 3,
  \"unit_scale\": 1.0,
  \"joints\": [ \"_\"
  ],
  \"stmts\": [
    {   \"kind\": \"prim\",
      \"duration\":83,
      \"points\": [
    [
  0.169,   0.055,
  0.045,
          0.348,
          1.925,
          2.284,
  1.595,
  9.625,
  17.625 ]
  ]
    },
    {
      \"kind\": \"prim\",
      \"duration\": 2222222222222222222,
      \"points\": [     [
  0.5,
          1.5,
          2.5,
          0.89,
          1.955,
             1112.5,
          0.0,
          1.64,
          2.5 ]
      ] }
  ]
}";

fn json(bytes: &[u8]) -> crate::Result<AbstractProgram> {
    AbstractProgram::read_str(&String::from_utf8_lossy(bytes), Path::new("fuzz.json"))
}

fn text(src: &str) -> crate::Result<AbstractProgram> {
    AbstractProgram::read_str(src, Path::new("fuzz.mpa"))
}

#[test]
fn json_the_text_form_cannot_hold_is_rejected() {
    let e = json(CONTROL_CHAR_IN_JOINT).unwrap_err();
    assert!(
        matches!(&e, AbstractError::InvalidParam { name: "joints", .. }),
        "{e}"
    );
    let e = json(HUGE_DURATION).unwrap_err();
    assert!(
        matches!(
            &e,
            AbstractError::InvalidParam {
                name: "duration",
                ..
            }
        ),
        "{e}"
    );
    for input in [UNKNOWN_UNITS, UNITS_WITH_SPACES] {
        let e = json(input).unwrap_err();
        assert!(
            matches!(&e, AbstractError::InvalidParam { name: "units", .. }),
            "{e}"
        );
    }
}

#[test]
fn names_of_the_text_form() {
    for ok in ["right_wrist", "a", "x-1", "l|r", "j.2", "-a", "é", "for"] {
        assert!(dsl::is_name(ok), "{ok}");
    }
    for bad in [
        "",
        "right wrist",
        "a\u{7f}",
        "1a",
        "-1",
        ".5",
        "a:b",
        "a,b",
        "+a",
        "a#",
    ] {
        assert!(!dsl::is_name(bad), "{bad:?}");
    }
}

const HEADER: &str = "abstract_program(fps=30, units=1, dims=4)\njoints(a)\n";

#[test]
fn unitless_programs_of_more_than_three_dimensions_round_trip() {
    let src = format!(
        "{HEADER}motion(duration=2) {{\n  a: start=(1, 2, 3, 4), mid=(1, 2, 3, 4), end=(0, 0, 0, 0)\n}}\n"
    );
    let p = text(&src).unwrap();
    assert_eq!(p.dims, 4);
    assert_eq!(text(&p.to_dsl()).unwrap(), p);
    let e = text(&src.replace("units=1", "units=px"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("dims must be 1, 2 or 3"), "{e}");
}

#[test]
fn duration_counts_that_overflow_are_an_error() {
    let src = "abstract_program(fps=30, units=px, dims=2)\njoints(a)\n\
         for i in range(2) {\n  motion(duration=sample({3: 2, 4: 1})) {\n\
         a: Gaussian(mean=<(0, 0), (0, 0), (0, 0)>, cov=[1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, \
         0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1])\n  }\n}\n";
    let ok = text(src).unwrap();
    assert_eq!(ok.expected_frames(), 2 * 3);
    // Counts only JSON can hold: their total overflowed in `validate`.
    let mut v: serde_json::Value = serde_json::to_value(&ok).unwrap();
    // Pairs `[value, count]`; a repeated value adds up.
    v["stmts"][0]["body"][0]["duration"] = serde_json::json!([[3, usize::MAX], [4, 1], [4, 1]]);
    let e = json(v.to_string().as_bytes()).unwrap_err().to_string();
    assert!(e.contains("counts overflow"), "{e}");
    // Numbers beyond the text form's integers (read through `f64`, at most
    // 10^12) could be written but not read back.
    v["stmts"][0]["body"][0]["duration"] = serde_json::json!([[3, 2]]);
    v["stmts"][0]["iterations"] = serde_json::json!(dsl::MAX_INTEGER + 1);
    let e = json(v.to_string().as_bytes()).unwrap_err().to_string();
    assert!(e.contains("iterations, at most"), "{e}");
    v["stmts"][0]["iterations"] = serde_json::json!(2);
    v["stmts"][0]["body"][0]["duration"] = serde_json::json!([[2222222222222222222usize, 1]]);
    let e = json(v.to_string().as_bytes()).unwrap_err().to_string();
    assert!(e.contains("value or count above"), "{e}");
}
