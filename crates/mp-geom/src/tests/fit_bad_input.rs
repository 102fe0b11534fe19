//! Bad input to the fits gives typed errors, never a panic or NaN.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::fit::{fit_best, fit_circle, fit_kind, prefix::PrefixFits, FitParams};
use crate::{GeomError, PrimitiveKind};
use ndarray::{array, Array2};

#[test]
fn empty_points() {
    let p = FitParams::default();
    let e = Array2::<f64>::zeros((0, 2));
    for k in PrimitiveKind::ALL {
        assert!(matches!(
            fit_kind(k, e.view(), None, &p),
            Err(GeomError::TooShort { got: 0, .. })
        ));
    }
    assert!(matches!(
        fit_best(e.view(), None, &p),
        Err(GeomError::TooShort { .. })
    ));
    let nod = Array2::<f64>::zeros((4, 0));
    assert!(matches!(
        fit_best(nod.view(), None, &p),
        Err(GeomError::Shape(_))
    ));
}

#[test]
fn one_point() {
    let p = FitParams::default();
    let one = array![[3.0, 4.0]];
    for k in [
        PrimitiveKind::Stationary,
        PrimitiveKind::Line,
        PrimitiveKind::Spline,
    ] {
        let f = fit_kind(k, one.view(), None, &p).unwrap();
        assert_eq!(f.primitive.eval(0.0), vec![3.0, 4.0]);
        assert_eq!(f.error, 0.0);
    }
    assert!(matches!(
        fit_circle(one.view(), None, &p),
        Err(GeomError::TooShort {
            needed: 3,
            got: 1,
            ..
        })
    ));
    // best of only-circle on one point: the circle's error
    let only_circle = FitParams {
        kinds: vec![PrimitiveKind::Circle],
        ..FitParams::default()
    };
    assert!(fit_best(one.view(), None, &only_circle).is_err());
    // default kinds: stationary
    assert_eq!(
        fit_best(one.view(), None, &p).unwrap().primitive.kind(),
        PrimitiveKind::Stationary
    );
}

#[test]
fn nan_names_the_frame() {
    let p = FitParams::default();
    let pts = array![[0.0, 0.0], [1.0, 1.0], [2.0, f64::NAN], [3.0, 3.0]];
    for k in PrimitiveKind::ALL {
        match fit_kind(k, pts.view(), None, &p) {
            Err(GeomError::NonFinite(m)) => assert!(m.contains("frame 2"), "{m}"),
            other => panic!("{k:?}: {other:?}"),
        }
    }
    match fit_best(pts.view(), None, &p) {
        Err(GeomError::NonFinite(m)) => assert!(m.contains("frame 2"), "{m}"),
        other => panic!("{other:?}"),
    }
    // the same frame with weight 0 is simply missing
    let w = [1.0, 1.0, 0.0, 1.0];
    assert!(fit_best(pts.view(), Some(&w), &p).is_ok());
    // infinities too
    let inf = array![[0.0, f64::INFINITY]];
    assert!(matches!(
        fit_best(inf.view(), None, &p),
        Err(GeomError::NonFinite(_))
    ));
}

#[test]
fn bad_weights() {
    let p = FitParams::default();
    let pts = array![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
    for k in PrimitiveKind::ALL {
        assert!(matches!(
            fit_kind(k, pts.view(), Some(&[0.0; 3]), &p),
            Err(GeomError::NoData(_))
        ));
    }
    assert!(matches!(
        fit_best(pts.view(), Some(&[0.0; 3]), &p),
        Err(GeomError::NoData(_))
    ));
    assert!(matches!(
        fit_best(pts.view(), Some(&[1.0; 2]), &p),
        Err(GeomError::Shape(_))
    ));
    assert!(matches!(
        fit_best(pts.view(), Some(&[1.0, -1.0, 1.0]), &p),
        Err(GeomError::InvalidParam {
            name: "weights",
            ..
        })
    ));
    match fit_best(pts.view(), Some(&[1.0, f64::NAN, 1.0]), &p) {
        Err(GeomError::NonFinite(m)) => assert!(m.contains("frame 1"), "{m}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_params() {
    let pts = array![[0.0, 0.0], [10.0, 1.0], [20.0, 2.0]];
    let cases: Vec<(&str, FitParams)> = vec![
        (
            "kinds",
            FitParams {
                kinds: vec![],
                ..Default::default()
            },
        ),
        (
            "unit_scale",
            FitParams {
                unit_scale: 0.0,
                ..Default::default()
            },
        ),
        (
            "unit_scale",
            FitParams {
                unit_scale: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "stationary_bbox_px",
            FitParams {
                stationary_bbox_px: -1.0,
                ..Default::default()
            },
        ),
        (
            "stationary_mean_residual_px",
            FitParams {
                stationary_mean_residual_px: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "min_span_px",
            FitParams {
                min_span_px: -0.1,
                ..Default::default()
            },
        ),
        (
            "max_radius_px",
            FitParams {
                max_radius_px: f64::INFINITY,
                ..Default::default()
            },
        ),
        (
            "min_radius_px",
            FitParams {
                min_radius_px: -3.0,
                ..Default::default()
            },
        ),
        (
            "radius_penalty",
            FitParams {
                radius_penalty: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "max_angle_acc_deg",
            FitParams {
                max_angle_acc_deg: -0.4,
                ..Default::default()
            },
        ),
    ];
    for (field, params) in cases {
        assert!(params.validate().is_err());
        for k in PrimitiveKind::ALL {
            match fit_kind(k, pts.view(), None, &params) {
                Err(GeomError::InvalidParam { name, .. }) => assert_eq!(name, field),
                other => panic!("{field}: {other:?}"),
            }
        }
        assert!(matches!(
            fit_best(pts.view(), None, &params),
            Err(GeomError::InvalidParam { .. })
        ));
    }
}

#[test]
fn degenerate_circles() {
    let p = FitParams::default();
    // collinear (2D and 3D), coincident
    let line2 = Array2::from_shape_fn((10, 2), |(i, k)| i as f64 * (k as f64 + 1.0));
    let line3 = Array2::from_shape_fn((10, 3), |(i, k)| 1.0 + i as f64 * (k as f64 - 0.5));
    let same = Array2::from_elem((10, 3), 2.5);
    for pts in [line2, line3, same] {
        match fit_circle(pts.view(), None, &p) {
            Err(GeomError::NoData(m)) => assert!(m.contains("collinear"), "{m}"),
            other => panic!("{other:?}"),
        }
        // fit_best falls back to the other kinds
        let b = fit_best(pts.view(), None, &p).unwrap();
        assert!(b.error.is_finite());
    }
    // wrong dimension
    let d4 = Array2::from_shape_fn((10, 4), |(i, k)| (i * k) as f64);
    assert!(matches!(
        fit_circle(d4.view(), None, &p),
        Err(GeomError::Shape(_))
    ));
    let d1 = Array2::from_shape_fn((10, 1), |(i, _)| i as f64);
    assert!(matches!(
        fit_circle(d1.view(), None, &p),
        Err(GeomError::Shape(_))
    ));
}

#[test]
fn prefix_bad_input() {
    let e = Array2::<f64>::zeros((0, 2));
    assert!(PrefixFits::new(e.view(), None).is_err());
    let pts = array![[0.0, 0.0], [1.0, f64::NAN]];
    assert!(matches!(
        PrefixFits::new(pts.view(), None),
        Err(GeomError::NonFinite(_))
    ));
    let pf = PrefixFits::new(pts.view(), Some(&[1.0, 0.0])).unwrap();
    assert!(pf.line(1, 1).is_err());
    assert!(pf.line(0, 3).is_err());
    assert!(matches!(pf.line(1, 2), Err(GeomError::NoData(_))));
    assert!(pf.line(0, 2).is_ok());
}
