//! DSL, JSON and the binary form: lossless round trips, the paper's notation,
//! and errors with positions.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::dsl::{self, parse, print, print_pretty};
use crate::{ConcreteError, Program, Segment};
use mp_geom::{Primitive, Units};
use proptest::prelude::*;

fn num() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => (-100_000i64..100_000).prop_map(|v| v as f64 / 100.0),
        2 => -1e3..1e3f64,
        1 => prop::num::f64::POSITIVE | prop::num::f64::NEGATIVE | prop::num::f64::NORMAL
            | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO,
        1 => Just(-0.0),
    ]
}

fn vecn(d: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(num(), d)
}

fn primitive(d: usize) -> impl Strategy<Value = Primitive> {
    let axes = if d == 3 {
        prop_oneof![
            Just(Vec::new()),
            (vecn(3), vecn(3)).prop_map(|(u, v)| vec![u, v])
        ]
        .boxed()
    } else {
        Just(Vec::new()).boxed()
    };
    prop_oneof![
        vecn(d).prop_map(|point| Primitive::Stationary { point }),
        (vecn(d), vecn(d)).prop_map(|(start, velocity)| Primitive::Line { start, velocity }),
        (
            vecn(d),
            num(),
            num(),
            num(),
            prop_oneof![Just(0.0), num()],
            axes
        )
            .prop_map(|(center, r, angle_start, angle_vel, angle_acc, axes)| {
                Primitive::Circle {
                    center,
                    radius: r.abs(),
                    angle_start,
                    angle_vel,
                    angle_acc,
                    axes,
                }
            }),
        prop::collection::vec(
            (num(), num(), num(), num()).prop_map(|(a, b, c, e)| [a, b, c, e]),
            d
        )
        .prop_map(|coeffs| Primitive::Spline { coeffs }),
    ]
}

fn program() -> impl Strategy<Value = Program> {
    (2usize..=3, 1usize..4, 1usize..5)
        .prop_flat_map(|(d, j, s)| {
            let seg = (1usize..60, prop::collection::vec(primitive(d), j)).prop_map(
                |(duration_frames, primitives)| Segment {
                    duration_frames,
                    primitives,
                },
            );
            (
                Just(d),
                prop::collection::vec("[a-z_\"\\\\ é#]{1,6}", j),
                prop::collection::vec(seg, s),
                prop_oneof![Just(30.0), Just(29.97), 0.5..240.0f64],
                prop_oneof![
                    Just(Units::Pixels),
                    Just(Units::Metres),
                    Just(Units::Unitless)
                ],
                "[a-z0-9\"]{0,8}",
            )
        })
        .prop_map(|(dims, names, segments, fps, units, skeleton)| Program {
            fps,
            units,
            dims,
            skeleton,
            joints: names
                .into_iter()
                .enumerate()
                .map(|(i, n)| format!("{n}{i}"))
                .collect(),
            // Both values print and parse (C0 is a header field).
            continuity: if fps > 30.0 {
                crate::Continuity::C0
            } else {
                crate::Continuity::None
            },
            segments,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn parse_print_roundtrip(p in program()) {
        let text = print(&p);
        let q = parse(&text).map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        prop_assert_eq!(&q, &p);
        // Bit-exact numbers (== treats -0 and 0 alike; the printer keeps the sign).
        prop_assert_eq!(print(&q), text);
    }

    #[test]
    fn json_roundtrip(p in program()) {
        let q = Program::from_json(&p.to_json().unwrap()).unwrap();
        prop_assert_eq!(q, p);
    }

    #[test]
    fn bincode_roundtrip(p in program()) {
        let q = Program::from_bincode(&p.to_bincode().unwrap()).unwrap();
        // Bit-exact numbers, signed zeros included.
        prop_assert_eq!(print(&q), print(&p));
        prop_assert_eq!(q, p);
    }

    #[test]
    fn pretty_parses_and_is_close(p in program()) {
        // Pretty text with many decimals is valid DSL too.
        let q = parse(&print_pretty(&p, 3)).unwrap();
        prop_assert_eq!(q.boundaries(), p.boundaries());
        prop_assert_eq!(q.joints, p.joints);
    }
}

fn paper_program() -> Program {
    Program {
        fps: 30.0,
        units: Units::Pixels,
        dims: 2,
        skeleton: "penn13".into(),
        joints: vec!["right_wrist".into()],
        continuity: crate::Continuity::None,
        segments: vec![
            Segment {
                duration_frames: 7,
                primitives: vec![Primitive::Circle {
                    center: vec![220.56, 175.67],
                    radius: 108.23,
                    angle_start: 79.99,
                    angle_vel: 3.17,
                    angle_acc: 0.0,
                    axes: vec![],
                }],
            },
            Segment {
                duration_frames: 4,
                primitives: vec![Primitive::Stationary {
                    point: vec![129.25, 121.59],
                }],
            },
            Segment {
                duration_frames: 4,
                primitives: vec![Primitive::Circle {
                    center: vec![249.49, 169.97],
                    radius: 107.97,
                    angle_start: -156.79,
                    angle_vel: -6.6,
                    angle_acc: 0.0,
                    axes: vec![],
                }],
            },
            Segment {
                duration_frames: 13,
                primitives: vec![Primitive::Line {
                    start: vec![261.61, 122.32],
                    velocity: vec![-0.48, 5.13],
                }],
            },
        ],
    }
}

#[test]
fn pretty_matches_the_paper_notation() {
    let p = paper_program();
    let text = print_pretty(&p, 2);
    let expected = "program(fps=30.00, units=px, dims=2, skeleton=\"penn13\")\n\n\
joint \"right_wrist\" {\n    \
circular_motion(center=(220.56, 175.67), radius=108.23, angle=3.17*t + 79.99, duration=7)\n    \
stationary(x=129.25, y=121.59, duration=4)\n    \
circular_motion(center=(249.49, 169.97), radius=107.97, angle=-6.60*t - 156.79, duration=4)\n    \
linear_motion(x=-0.48*t + 261.61, y=5.13*t + 122.32, duration=13)\n}\n";
    assert_eq!(text, expected);
    // The paper's numbers are exact decimals here, so pretty text parses back to the same program.
    assert_eq!(parse(&text).unwrap(), p);
}

#[test]
fn spline_and_3d_forms() {
    let s = Primitive::Spline {
        coeffs: vec![[1.0, -2.0, 3.5, 4.0], [0.0, 0.0, 1.0, -1.0]],
    };
    assert_eq!(
        dsl::statement(&s, 5, dsl::NumberFormat::Exact),
        "spline_motion(x=1*t^3 - 2*t^2 + 3.5*t + 4, y=0*t^3 + 0*t^2 + 1*t - 1, duration=5)"
    );
    let c = Primitive::Circle {
        center: vec![0.1, 0.2, 0.3],
        radius: 0.5,
        angle_start: 10.0,
        angle_vel: 2.0,
        angle_acc: 0.25,
        axes: vec![vec![1.0, 0.0, 0.0], vec![0.0, 0.0, 1.0]],
    };
    let text = dsl::statement(&c, 9, dsl::NumberFormat::Exact);
    assert_eq!(
        text,
        "circular_motion(center=(0.1, 0.2, 0.3), radius=0.5, angle=0.25*t^2 + 2*t + 10, u=(1, 0, 0), v=(0, 0, 1), duration=9)"
    );
    assert_eq!(dsl::parse_statement(&text, 3).unwrap(), (c, 9));
    let st = Primitive::Stationary {
        point: vec![1.0, 2.0, 3.0],
    };
    assert_eq!(
        dsl::statement(&st, 2, dsl::NumberFormat::Fixed(2)),
        "stationary(x=1.00, y=2.00, z=3.00, duration=2)"
    );
}

#[test]
fn parser_accepts_flexible_spelling() {
    // Comments, `;`, `a*t - b`, terms in any order, exponents, signs.
    let text = "# a comment\nprogram(units=px, dims=2, fps=25);\njoint \"a\" {\n  linear_motion(x=30 + 1.2*t, y=-0.5*t - 12, duration=8);\n  stationary(y=+5, x=1.5e1, duration=3) # trailing\n}\n";
    let p = parse(text).unwrap();
    assert_eq!(p.skeleton, "generic");
    assert_eq!(
        p.segments[0].primitives[0],
        Primitive::Line {
            start: vec![30.0, -12.0],
            velocity: vec![1.2, -0.5]
        }
    );
    assert_eq!(
        p.segments[1].primitives[0],
        Primitive::Stationary {
            point: vec![15.0, 5.0]
        }
    );
}

fn err_at(text: &str) -> (usize, usize, String) {
    match parse(text) {
        Err(ConcreteError::Parse { err, .. }) => (err.line, err.column, err.expected),
        other => panic!("expected a parse error, got {other:?}"),
    }
}

const HEAD: &str = "program(fps=30, units=px, dims=2)\n";

#[test]
fn malformed_text_reports_line_and_column() {
    // Missing `=` after `x`.
    let (l, c, e) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n    stationary(x 1, y=2, duration=3)\n}}\n"
    ));
    assert_eq!((l, c), (3, 18));
    assert!(e.contains('='), "{e}");
    // Unknown primitive.
    let (l, c, e) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n  spiral(x=1, y=2, duration=3)\n}}\n"
    ));
    assert_eq!((l, c), (3, 3));
    assert!(e.contains("stationary"), "{e}");
    // Missing key: reported at the closing parenthesis.
    let (l, c, e) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n  stationary(x=1, duration=3)\n}}\n"
    ));
    assert_eq!((l, c), (3, 29));
    assert!(e.contains("`y=`"), "{e}");
    // A power too high for a line.
    let (l, c, _) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n  linear_motion(x=1*t^2 + 3, y=1*t + 0, duration=3)\n}}\n"
    ));
    assert_eq!((l, c), (3, 19));
    // Fractional duration.
    let (l, c, e) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n  stationary(x=1, y=2, duration=2.5)\n}}\n"
    ));
    assert_eq!((l, c), (3, 33));
    assert!(e.contains("duration"), "{e}");
    // Durations differ between joints (shared segmentation).
    let (l, c, e) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n  stationary(x=1, y=2, duration=3)\n}}\njoint \"b\" {{\n  stationary(x=1, y=2, duration=4)\n}}\n"
    ));
    assert_eq!((l, c), (6, 33));
    assert!(e.contains("duration=3"), "{e}");
    // Unterminated block.
    let (l, c, _) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n  stationary(x=1, y=2, duration=3)\n"
    ));
    assert_eq!((l, c), (4, 1));
    // Bad character.
    let (l, c, _) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n  stationary(x=1, y=@2, duration=3)\n}}\n"
    ));
    assert_eq!((l, c), (3, 21));
    // Out-of-range number.
    let (l, c, e) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n  stationary(x=1e999, y=2, duration=3)\n}}\n"
    ));
    assert_eq!((l, c), (3, 16));
    assert!(e.contains("finite"), "{e}");
    // Missing header field.
    let (l, c, e) =
        err_at("program(fps=30, dims=2)\njoint \"a\" { stationary(x=1, y=2, duration=3) }");
    assert_eq!((l, c), (1, 23));
    assert!(e.contains("units"), "{e}");
    // Wrong tuple size for a 2D circle.
    let (l, c, _) = err_at(&format!(
        "{HEAD}joint \"a\" {{\n  circular_motion(center=(1, 2, 3), radius=2, angle=1*t + 0, duration=3)\n}}\n"
    ));
    assert_eq!((l, c), (3, 26));
    // Empty input.
    let (l, c, e) = err_at("");
    assert_eq!((l, c), (1, 1));
    assert!(e.contains("program"), "{e}");
    // Display carries the position.
    let msg = parse("program(fps=30)").unwrap_err().to_string();
    assert!(msg.starts_with("line 1, column 15: expected"), "{msg}");
}

#[test]
fn json_rejects_inconsistent_programs() {
    let mut p = paper_program();
    p.segments[1].primitives.clear();
    let json = serde_json::to_string(&p).unwrap();
    assert!(matches!(
        Program::from_json(&json),
        Err(ConcreteError::Program(_))
    ));
    assert!(matches!(
        Program::from_json("{\"fps\": 30"),
        Err(ConcreteError::Json { .. })
    ));
}

#[test]
fn file_round_trip_by_extension() {
    let dir = tempfile::tempdir().unwrap();
    let p = paper_program();
    for name in ["p.txt", "p.json", "p.mp", "p.mpb", "P.MPB"] {
        let path = dir.path().join(name);
        p.write(&path).unwrap();
        assert_eq!(Program::read(&path).unwrap(), p, "{name}");
    }
    assert_eq!(
        std::fs::read(dir.path().join("p.mpb")).unwrap(),
        p.to_bincode().unwrap()
    );
    // Writes are atomic: only the final files remain.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 5);
    let bad = dir.path().join("bad.txt");
    std::fs::write(
        &bad,
        "program(fps=30, units=px, dims=2)\njoint \"a\" { nope }",
    )
    .unwrap();
    let e = Program::read(&bad).unwrap_err();
    assert!(e.to_string().contains("bad.txt: line 2, column 13"), "{e}");
}
