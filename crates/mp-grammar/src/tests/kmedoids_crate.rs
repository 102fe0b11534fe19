//! Cross-checks of the project's PAM / FasterPAM against the `kmedoids`
//! crate (Schubert & Lenssen), used here only as a test-time reference.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::kmedoids::{first_k, FasterPam, LowerTriangle, MedoidSwap, Pam};
use ndarray::Array2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The crate's own 5-point example: loss 4, medoids [0, 3], assignment [0,0,0,1,1].
#[test]
fn crate_reference_example_both() {
    let data = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 1.0];
    let ours = FasterPam::default()
        .fit(&LowerTriangle::new(5, data.clone()).unwrap(), &[0, 1])
        .unwrap();
    let lt = kmedoids::arrayadapter::LowerTriangle { n: 5, data };
    let mut meds = vec![0, 1];
    let (loss, assi, iters, swaps): (f64, Vec<usize>, usize, usize) =
        kmedoids::fasterpam(&lt, &mut meds, 10);
    assert_eq!(loss, 4.0);
    assert_eq!(ours.loss, loss);
    assert_eq!(ours.medoids, meds);
    assert_eq!(ours.medoids, vec![0, 3]);
    assert_eq!(ours.assignment, assi);
    assert_eq!(ours.assignment, vec![0, 0, 0, 1, 1]);
    assert_eq!(ours.swaps, swaps);
    assert_eq!(ours.iterations, iters);
}

fn random_matrix(rng: &mut ChaCha8Rng, n: usize, dim: usize) -> Array2<f64> {
    let pts: Vec<Vec<f64>> = (0..n)
        .map(|_| (0..dim).map(|_| rng.random::<f64>()).collect())
        .collect();
    Array2::from_shape_fn((n, n), |(i, j)| {
        pts[i]
            .iter()
            .zip(&pts[j])
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt()
    })
}

#[test]
fn fasterpam_matches_crate_on_random_data() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for trial in 0..40 {
        let n = rng.random_range(5..120);
        let k = rng.random_range(1..=n.min(25));
        let dim = rng.random_range(1..6);
        let m = random_matrix(&mut rng, n, dim);
        let ours = FasterPam { max_iter: 100 }.fit(&m, &first_k(k)).unwrap();
        let mut meds = first_k(k);
        let (loss, assi, _iters, swaps): (f64, Vec<usize>, usize, usize) =
            kmedoids::fasterpam(&m, &mut meds, 100);
        assert!(
            (ours.loss - loss).abs() <= 1e-9 * loss.max(1.0),
            "trial {trial}: n={n} k={k}: ours {} crate {loss}",
            ours.loss
        );
        assert_eq!(ours.medoids, meds, "trial {trial}");
        assert_eq!(ours.assignment, assi, "trial {trial}");
        assert_eq!(ours.swaps, swaps, "trial {trial}");
    }
}

#[test]
fn pam_matches_crate_pam_swap_on_random_data() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut same_medoids = 0;
    for trial in 0..25 {
        let n = rng.random_range(5..60);
        let k = rng.random_range(1..=n.min(10));
        let m = random_matrix(&mut rng, n, 3);
        let ours = Pam { max_iter: 1000 }.fit(&m, &first_k(k)).unwrap();
        let mut meds = first_k(k);
        let (loss, assi, _iters, swaps): (f64, Vec<usize>, usize, usize) =
            kmedoids::pam_swap(&m, &mut meds, 1000);
        assert!(
            (ours.loss - loss).abs() <= 1e-9 * loss.max(1.0),
            "trial {trial}: ours {} crate {loss}",
            ours.loss
        );
        // Medoids may differ where two members of a cluster are equivalent
        // medoids and rounding noise decides between them; the partition and
        // the loss may not.
        assert_eq!(ours.assignment, assi, "trial {trial}");
        if ours.medoids == meds {
            assert_eq!(ours.swaps, swaps, "trial {trial}");
            same_medoids += 1;
        }
    }
    assert!(
        same_medoids >= 20,
        "only {same_medoids}/25 runs had identical medoids"
    );
}
