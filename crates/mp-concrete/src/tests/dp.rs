//! The DP segmentation equals exhaustive search.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::dp::{segment_brute_force, segment_table, CostTable, Segmentation};
use crate::ConcreteError;
use proptest::prelude::*;

/// Random segment costs for T ≤ 10 frames, with a penalty λ.
fn costs() -> impl Strategy<Value = (usize, usize, f64, Vec<f64>)> {
    (1usize..=10, 1usize..=10, 0.0..50.0f64).prop_flat_map(|(t, w, lambda)| {
        (
            Just(t),
            Just(w),
            Just(lambda),
            prop::collection::vec(0.0..100.0f64, t * t),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn dp_equals_brute_force((t, w, lambda, c) in costs()) {
        let cost = |k: usize, n: usize| c[k * t + (n - 1)] + lambda;
        let dp = Segmentation::dp(t, w, cost).unwrap();
        let bf = segment_brute_force(t, w, cost).unwrap();
        prop_assert!((dp.cost - bf.cost).abs() <= 1e-9 * (1.0 + bf.cost.abs()), "dp {} bf {}", dp.cost, bf.cost);
        // The DP's segmentation really has the cost it claims, and respects W.
        let recomputed: f64 = dp.boundaries.windows(2).map(|s| cost(s[0], s[1])).sum();
        prop_assert!((recomputed - dp.cost).abs() <= 1e-9 * (1.0 + dp.cost.abs()));
        prop_assert!(dp.durations().iter().all(|&d| d >= 1 && d <= w));
        prop_assert_eq!(dp.boundaries.first().copied(), Some(0));
        prop_assert_eq!(dp.boundaries.last().copied(), Some(t));
        // Random real costs have a unique optimum: the same boundaries.
        prop_assert_eq!(&dp.boundaries, &bf.boundaries);
        // The table version agrees.
        let table = CostTable::from_fn(t, w, cost);
        prop_assert_eq!(segment_table(&table).unwrap(), dp.clone());
        // So does the table filled in parallel, cell for cell.
        let par = CostTable::try_from_fn_parallel(t, w, |k, n| Ok::<f64, ()>(cost(k, n))).unwrap();
        for n in 1..=t {
            for k in 0..n {
                prop_assert_eq!(par.get(k, n).to_bits(), table.get(k, n).to_bits());
            }
        }
        prop_assert_eq!(segment_table(&par).unwrap(), dp);
    }
}

#[test]
fn a_failing_cost_stops_the_parallel_fill() {
    let r = CostTable::try_from_fn_parallel(50, 8, |k, n| {
        if (k, n) == (30, 33) {
            Err(format!("segment {k}..{n} cannot be fitted"))
        } else {
            Ok(1.0)
        }
    });
    assert_eq!(r.unwrap_err(), "segment 30..33 cannot be fitted");
}

#[test]
fn lambda_controls_granularity() {
    // Cost of a segment = its squared length deviation from 3 frames: λ = 0
    // gives single frames when single frames are free.
    let free = |k: usize, n: usize| if n - k == 1 { 0.0 } else { 1.0 };
    let s = Segmentation::dp(6, 6, free).unwrap();
    assert_eq!(s.n_segments(), 6);
    // A large λ gives one segment when a segment costs the same at any length.
    let s = Segmentation::dp(6, 6, |_, _| 1000.0).unwrap();
    assert_eq!(s.boundaries, vec![0, 6]);
    // …unless the window forbids it.
    let s = Segmentation::dp(6, 4, |_, _| 1000.0).unwrap();
    assert_eq!(s.n_segments(), 2);
}

#[test]
fn bad_inputs_are_typed_errors() {
    assert!(matches!(
        Segmentation::dp(0, 5, |_, _| 0.0),
        Err(ConcreteError::Track(_))
    ));
    assert!(matches!(
        Segmentation::dp(5, 0, |_, _| 0.0),
        Err(ConcreteError::InvalidParam {
            name: "max_segment_frames",
            ..
        })
    ));
    assert!(matches!(
        Segmentation::dp(3, 3, |_, _| f64::NAN),
        Err(ConcreteError::Track(_))
    ));
    assert!(matches!(
        Segmentation::dp(3, 3, |_, _| f64::INFINITY),
        Err(ConcreteError::Track(_))
    ));
    assert!(segment_brute_force(21, 3, |_, _| 0.0).is_err());
}

mod on_real_costs {
    use crate::dp::segment_brute_force;
    use crate::synth::segment_costs;
    use crate::{Lambda, Program, Scale, SynthParams};
    use mp_geom::{Skeleton, Track, Units};
    use ndarray::Array3;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Synthesis (fit costs from mp-geom + λ) finds the same optimum as
        /// exhaustive search over the same costs, on small random tracks.
        #[test]
        fn synthesis_equals_brute_force(
            t in 2usize..=9,
            w in 1usize..=9,
            lambda in 0.0..400.0f64,
            coords in prop::collection::vec(0.0..200.0f64, 9 * 2 * 2),
        ) {
            let mut pos = Array3::zeros((t, 2, 2));
            for ti in 0..t {
                for j in 0..2 {
                    for k in 0..2 {
                        pos[[ti, j, k]] = coords[(ti * 2 + j) * 2 + k];
                    }
                }
            }
            let track = Track::new(pos, None, 30.0, Units::Pixels, Skeleton::generic(2)).unwrap();
            let params = SynthParams {
                lambda: Lambda::fixed(lambda),
                max_segment_frames: w,
                scale: Scale::UnitScale { unit_scale: 1.0 },
                ..SynthParams::paper()
            };
            let table = segment_costs(&track, &params).unwrap();
            let bf = segment_brute_force(t, w, |k, n| table.get(k, n)).unwrap();
            let syn = Program::synthesize_detailed(&track, &params).unwrap();
            prop_assert!((syn.segmentation.cost - bf.cost).abs() <= 1e-9 * (1.0 + bf.cost));
            prop_assert_eq!(syn.program.boundaries(), syn.segmentation.boundaries.clone());
        }
    }
}
