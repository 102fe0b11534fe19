//! Metrics: hand-computed values, invariances and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::metrics::{
    dtw, dtw_align, kd, kd_per_frame, max_adjacent_jump, mpjpe, mpjpe_per_frame, nanmean, pa_mpjpe,
    pa_mpjpe_per_frame, pck, pck_per_frame, pck_per_frame_sized, pck_with, procrustes, DtwCost,
    PckParams, Poses,
};
use crate::{GeomError, Skeleton, Track, Units};
use ndarray::{array, s, Array2, Array3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn random_poses(t: usize, j: usize, d: usize, seed: u64) -> Array3<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    Array3::from_shape_fn((t, j, d), |_| rng.random_range(-100.0..100.0))
}

/// Applies `x ↦ s·R·x + τ` (R given as rows) to every joint.
fn transform(p: &Array3<f64>, sc: f64, r: &[Vec<f64>], tr: &[f64]) -> Array3<f64> {
    let (t, j, d) = p.dim();
    Array3::from_shape_fn((t, j, d), |(ti, ji, a)| {
        tr[a] + sc * (0..d).map(|b| r[a][b] * p[[ti, ji, b]]).sum::<f64>()
    })
}

fn rot3(ax: f64, ay: f64, az: f64) -> Vec<Vec<f64>> {
    let (sx, cx) = ax.sin_cos();
    let (sy, cy) = ay.sin_cos();
    let (sz, cz) = az.sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]];
    let ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
    let rz = [[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]];
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for k in 0..3 {
                c[i][k] = (0..3).map(|m| a[i][m] * b[m][k]).sum();
            }
        }
        c
    };
    mul(rz, mul(ry, rx)).iter().map(|r| r.to_vec()).collect()
}

#[test]
fn kd_hand_computed() {
    // 2 frames × 2 joints × 2D
    let a = array![[[0.0, 0.0], [1.0, 1.0]], [[2.0, 2.0], [5.0, 5.0]]];
    let b = array![[[3.0, 4.0], [1.0, 1.0]], [[2.0, 2.0], [5.0, 17.0]]];
    // distances 5, 0, 0, 12
    assert!((kd(&a, &b).unwrap() - 17.0 / 4.0).abs() < 1e-12);
    assert_eq!(kd_per_frame(&a, &b).unwrap(), vec![2.5, 6.0]);
    // mask: joint 1 of frame 1 missing in b → pairs 5, 0, 0 over 3 (pooled, not a mean of frame means)
    let conf = array![[1.0, 1.0], [1.0, 0.0]];
    let bp = Poses::new(b.view(), Some(conf.view())).unwrap();
    assert!((kd(&a, bp).unwrap() - 5.0 / 3.0).abs() < 1e-12);
    assert_eq!(kd_per_frame(&a, bp).unwrap(), vec![2.5, 0.0]);
    // a frame with nothing in common is NaN per frame
    let conf = array![[1.0, 1.0], [0.0, 0.0]];
    let bp = Poses::new(b.view(), Some(conf.view())).unwrap();
    let pf = kd_per_frame(&a, bp).unwrap();
    assert_eq!(pf[0], 2.5);
    assert!(pf[1].is_nan());
    assert_eq!(nanmean(&pf), 2.5);
}

#[test]
fn kd_on_tracks() {
    let p = random_poses(5, 3, 2, 1);
    let tr = Track::new(p.clone(), None, 30.0, Units::Pixels, Skeleton::generic(3)).unwrap();
    let shifted = p.mapv(|v| v + 1.0);
    let tr2 = Track::new(shifted, None, 30.0, Units::Pixels, Skeleton::generic(3)).unwrap();
    assert_eq!(kd(&tr, &tr).unwrap(), 0.0);
    assert!((kd(&tr, &tr2).unwrap() - 2f64.sqrt()).abs() < 1e-12);
}

#[test]
fn pck_scaled_shifted_copy_is_100() {
    let gt = random_poses(10, 13, 2, 2);
    let pred = gt.mapv(|v| 0.37 * v) + &array![55.0, -12.0];
    let v = pck(&pred, &gt, 0.05).unwrap();
    assert!((v - 100.0).abs() < 1e-12, "{v}");
    // the fit is not a rotation: a rotated copy is not 100
    let r = vec![vec![0.0, -1.0], vec![1.0, 0.0]];
    let rot = transform(&gt, 1.0, &r, &[0.0, 0.0]);
    assert!(pck(&rot, &gt, 0.05).unwrap() < 50.0);
}

#[test]
fn pck_hand_computed() {
    // 6 joints on a 100 × 50 box: size = 100, threshold 5 at α = 0.05
    let g = array![[
        [0.0, 0.0],
        [100.0, 0.0],
        [100.0, 50.0],
        [0.0, 50.0],
        [50.0, 25.0],
        [20.0, 10.0]
    ]];
    let mut p = g.clone();
    p[[0, 5, 0]] += 30.0; // one joint 30 px off: the LS fit spreads that error
    let pf = pck_per_frame(&p, &g, &PckParams::default()).unwrap();
    // the fit: s and τ from the closed form; check joint by joint by hand
    let (n, d) = (6usize, 2usize);
    let pm: Vec<f64> = (0..d)
        .map(|k| (0..n).map(|j| p[[0, j, k]]).sum::<f64>() / n as f64)
        .collect();
    let gm: Vec<f64> = (0..d)
        .map(|k| (0..n).map(|j| g[[0, j, k]]).sum::<f64>() / n as f64)
        .collect();
    let (mut pg, mut pp) = (0.0, 0.0);
    for j in 0..n {
        for k in 0..d {
            pg += (p[[0, j, k]] - pm[k]) * (g[[0, j, k]] - gm[k]);
            pp += (p[[0, j, k]] - pm[k]).powi(2);
        }
    }
    let sc = pg / pp;
    let correct = (0..n)
        .filter(|&j| {
            let e: f64 = (0..d)
                .map(|k| (sc * (p[[0, j, k]] - pm[k]) + gm[k] - g[[0, j, k]]).powi(2))
                .sum();
            e.sqrt() <= 5.0
        })
        .count();
    assert!(correct < 6 && correct > 0);
    assert!((pf[0] - 100.0 * correct as f64 / 6.0).abs() < 1e-12);
    // with α = 1 every joint is within 100 px
    assert_eq!(pck(&p, &g, 1.0).unwrap(), 100.0);
    // fewer than 6 visible joints → frame skipped → no frame left
    let conf = array![[1.0, 1.0, 1.0, 1.0, 1.0, 0.0]];
    let gp = Poses::new(g.view(), Some(conf.view())).unwrap();
    assert!(pck_per_frame(&p, gp, &PckParams::default()).unwrap()[0].is_nan());
    assert!(matches!(pck(&p, gp, 0.05), Err(GeomError::NoData(_))));
    let five = PckParams {
        min_visible: 5,
        ..PckParams::default()
    };
    assert_eq!(pck_with(&p, gp, &five).unwrap(), 100.0);
}

#[test]
fn pck_with_given_reference_sizes() {
    // 6 joints spanning 100 px; one joint 12 px off after the fit cannot pass at size 100
    // (threshold 5) but passes at a reference size of 400 (threshold 20)
    let g = array![[
        [0.0, 0.0],
        [100.0, 0.0],
        [100.0, 50.0],
        [0.0, 50.0],
        [50.0, 25.0],
        [20.0, 10.0]
    ]];
    let mut p = g.clone();
    p[[0, 4, 1]] += 12.0;
    let params = PckParams::default();
    let own = pck_per_frame(&p, &g, &params).unwrap()[0];
    let same = pck_per_frame_sized(&p, &g, Some(&[100.0]), &params).unwrap()[0];
    assert_eq!(own, same);
    assert!(own < 100.0);
    assert_eq!(
        pck_per_frame_sized(&p, &g, Some(&[400.0]), &params).unwrap()[0],
        100.0
    );
    // a missing size (NaN, 0) falls back to the joints' extent
    assert_eq!(
        pck_per_frame_sized(&p, &g, Some(&[f64::NAN]), &params).unwrap()[0],
        own
    );
    assert_eq!(
        pck_per_frame_sized(&p, &g, Some(&[0.0]), &params).unwrap()[0],
        own
    );
    // one size per ground-truth frame
    assert!(matches!(
        pck_per_frame_sized(&p, &g, Some(&[1.0, 2.0]), &params),
        Err(GeomError::Shape(_))
    ));
}

#[test]
fn pck_nanmean_over_frames() {
    let gt = random_poses(3, 8, 2, 3);
    let mut pred = gt.clone();
    // frame 1: every joint of the prediction scrambled
    for j in 0..8 {
        pred[[1, j, 0]] = gt[[1, (j + 3) % 8, 0]];
        pred[[1, j, 1]] = gt[[1, (j + 5) % 8, 1]];
    }
    let mut conf = Array2::ones((3, 8));
    conf.slice_mut(s![2, ..]).fill(0.0); // frame 2 unscored
    let gp = Poses::new(gt.view(), Some(conf.view())).unwrap();
    let pf = pck_per_frame(&pred, gp, &PckParams::default()).unwrap();
    assert_eq!(pf[0], 100.0);
    assert!(pf[1] < 100.0);
    assert!(pf[2].is_nan());
    assert!((pck(&pred, gp, 0.05).unwrap() - (100.0 + pf[1]) / 2.0).abs() < 1e-12);
}

#[test]
fn mpjpe_hand_computed() {
    // 1 frame, 3 joints, 2D
    let g = array![[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]];
    let p = array![[[10.0, 10.0], [11.0, 10.0], [10.0, 13.0]]];
    // root 0: (0,0), (0,0), (0,2) → mean 2/3
    assert!((mpjpe(&p, &g, Some(0)).unwrap() - 2.0 / 3.0).abs() < 1e-12);
    // mean root: centroids differ by (10, 10 + 2/3); residuals (0,−2/3), (0,−2/3), (0,4/3) → 8/9
    assert!((mpjpe(&p, &g, None).unwrap() - 8.0 / 9.0).abs() < 1e-12);
    // invalid root → NaN frame → no data
    let conf = array![[0.0, 1.0, 1.0]];
    let pp = Poses::new(p.view(), Some(conf.view())).unwrap();
    assert!(mpjpe_per_frame(pp, &g, Some(0)).unwrap()[0].is_nan());
    assert!(matches!(mpjpe(pp, &g, Some(0)), Err(GeomError::NoData(_))));
    assert!(matches!(
        mpjpe(&p, &g, Some(3)),
        Err(GeomError::InvalidParam { name: "root", .. })
    ));
}

#[test]
fn pa_mpjpe_undoes_similarity() {
    for (d, seed) in [(3usize, 4u64), (2, 5)] {
        let gt = random_poses(6, 17, d, seed);
        let (r, tr) = if d == 3 {
            (rot3(0.3, -1.1, 2.5), vec![40.0, -7.0, 3.0])
        } else {
            let (s, c) = 2.2f64.sin_cos();
            (vec![vec![c, -s], vec![s, c]], vec![40.0, -7.0])
        };
        let pred = transform(&gt, 2.7, &r, &tr);
        let v = pa_mpjpe(&pred, &gt).unwrap();
        assert!(v < 1e-9, "d={d}: {v}");
        // plain MPJPE sees the transform
        assert!(mpjpe(&pred, &gt, None).unwrap() > 10.0);
    }
}

#[test]
fn pa_mpjpe_reflection_fix() {
    // the prediction is a mirror image: a proper rotation cannot undo it
    let gt = random_poses(1, 12, 2, 6);
    let mirror = vec![vec![-1.0, 0.0], vec![0.0, 1.0]];
    let pred = transform(&gt, 1.5, &mirror, &[3.0, 4.0]);
    let v = pa_mpjpe_per_frame(&pred, &gt).unwrap()[0];
    assert!(v > 1.0, "the reflection must not be allowed: {v}");
    // brute force over proper rotations (optimal scale and translation for each angle)
    let x = pred.slice(s![0, .., ..]).to_owned();
    let y = gt.slice(s![0, .., ..]).to_owned();
    let xm = x.mean_axis(ndarray::Axis(0)).unwrap();
    let ym = y.mean_axis(ndarray::Axis(0)).unwrap();
    let xc = &x - &xm;
    let yc = &y - &ym;
    let mut best = f64::INFINITY;
    let mut best_ss = f64::INFINITY;
    let steps = 200_000;
    for k in 0..steps {
        let a = std::f64::consts::TAU * k as f64 / steps as f64;
        let (s, c) = a.sin_cos();
        let rx = Array2::from_shape_fn(xc.dim(), |(i, m)| {
            if m == 0 {
                c * xc[[i, 0]] - s * xc[[i, 1]]
            } else {
                s * xc[[i, 0]] + c * xc[[i, 1]]
            }
        });
        let sc = (&rx * &yc).sum() / (&rx * &rx).sum();
        let res = &rx * sc - &yc;
        let ss = (&res * &res).sum();
        if ss < best_ss {
            best_ss = ss;
            best = (0..12)
                .map(|i| res.row(i).dot(&res.row(i)).sqrt())
                .sum::<f64>()
                / 12.0;
        }
    }
    assert!((v - best).abs() < 1e-3 * best, "{v} vs brute force {best}");
    // the transform found is proper
    let sim = procrustes(x.view(), y.view()).unwrap();
    assert!((sim.rotation.determinant() - 1.0).abs() < 1e-12);
    // and a proper similarity of mirrored data is still undone exactly
    let gt3 = random_poses(2, 10, 3, 7);
    let mirrored_gt = transform(
        &gt3,
        1.0,
        &[
            vec![1.0, 0.0, 0.0],
            vec![0.0, 1.0, 0.0],
            vec![0.0, 0.0, -1.0],
        ],
        &[0.0; 3],
    );
    let pred3 = transform(&mirrored_gt, 0.5, &rot3(1.0, 2.0, 3.0), &[1.0, 2.0, 3.0]);
    assert!(pa_mpjpe(&pred3, &mirrored_gt).unwrap() < 1e-9);
}

fn check_path(path: &[(usize, usize)], na: usize, nb: usize) {
    assert_eq!(path[0], (0, 0));
    assert_eq!(*path.last().unwrap(), (na - 1, nb - 1));
    for w in path.windows(2) {
        let (di, dj) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
        assert!(
            (di, dj) == (1, 0) || (di, dj) == (0, 1) || (di, dj) == (1, 1),
            "{w:?}"
        );
    }
    for i in 0..na {
        assert!(path.iter().any(|p| p.0 == i));
    }
    for j in 0..nb {
        assert!(path.iter().any(|p| p.1 == j));
    }
}

#[test]
fn dtw_time_stretched_copy() {
    let gt = random_poses(12, 7, 2, 8);
    let stretched = Array3::from_shape_fn((24, 7, 2), |(t, j, k)| gt[[t / 2, j, k]]);
    for cost in [
        DtwCost::Euclidean,
        DtwCost::SquaredEuclidean,
        DtwCost::SquaredThenSqrt,
    ] {
        let r = dtw(&stretched, &gt, cost).unwrap();
        assert_eq!(r.distance, 0.0);
        check_path(&r.path, 24, 12);
        assert_eq!(r.path.len(), 24);
    }
    let al = dtw_align(&stretched, &gt, DtwCost::Euclidean).unwrap();
    assert_eq!(al.positions, gt);
    assert!(al.confidence.iter().all(|&c| c == 1.0));
    assert_eq!(pck(al.poses(), &gt, 0.05).unwrap(), 100.0);
    assert_eq!(kd(al.poses(), &gt).unwrap(), 0.0);
    // the other way round: gt shorter than pred's copy
    let al = dtw_align(&gt, &stretched, DtwCost::Euclidean).unwrap();
    assert_eq!(al.positions, stretched);
}

#[test]
fn dtw_hand_computed_costs() {
    // J = 1, D = 1: a = [0, 4], b = [0, 1, 2, 4]
    let a = Array3::from_shape_vec((2, 1, 1), vec![0.0, 4.0]).unwrap();
    let b = Array3::from_shape_vec((4, 1, 1), vec![0.0, 1.0, 2.0, 4.0]).unwrap();
    let e = dtw(&a, &b, DtwCost::Euclidean).unwrap();
    assert_eq!(e.distance, 3.0);
    assert_eq!(e.path, vec![(0, 0), (0, 1), (0, 2), (1, 3)]);
    let q = dtw(&a, &b, DtwCost::SquaredEuclidean).unwrap();
    assert_eq!(q.distance, 5.0);
    let r = dtw(&a, &b, DtwCost::SquaredThenSqrt).unwrap();
    assert!((r.distance - 5f64.sqrt()).abs() < 1e-15);
    // two joints: the local cost is the mean over joints; joint 1 adds a constant offset of 2
    let a2 = Array3::from_shape_fn((2, 2, 1), |(t, j, _)| a[[t, 0, 0]] + 2.0 * j as f64);
    let b2 = Array3::from_shape_fn((4, 2, 1), |(t, _, _)| b[[t, 0, 0]]);
    // pair costs (|Δ| + |Δ + 2|)/2: row a=0: 1 1 1 3; row a=4: 5 4 3 1;
    // best path (0,0) (0,1) (0,2) (1,3) = 1 + 1 + 1 + 1
    let e2 = dtw(&a2, &b2, DtwCost::Euclidean).unwrap();
    assert!((e2.distance - 4.0).abs() < 1e-12, "{}", e2.distance);
    assert_eq!(e2.path, vec![(0, 0), (0, 1), (0, 2), (1, 3)]);
}

#[test]
fn dtw_masks() {
    let a = random_poses(4, 3, 2, 9);
    let mut conf = Array2::ones((4, 3));
    conf[[1, 0]] = 0.0;
    conf[[1, 2]] = 0.0;
    let mut a_bad = a.clone();
    a_bad[[1, 0, 0]] = f64::NAN; // invisible: ignored
    let ap = Poses::new(a_bad.view(), Some(conf.view())).unwrap();
    let r = dtw(ap, &a, DtwCost::Euclidean).unwrap();
    assert!(r.distance.abs() < 1e-12);
    // nothing in common at all → no data
    let none = Array2::zeros((4, 3));
    let np = Poses::new(a.view(), Some(none.view())).unwrap();
    assert!(matches!(
        dtw(np, &a, DtwCost::Euclidean),
        Err(GeomError::NoData(_))
    ));
}

#[test]
fn max_jump() {
    let mut p = Array3::zeros((4, 2, 2));
    p[[1, 0, 0]] = 3.0;
    p[[1, 0, 1]] = 4.0; // jump 5 at t = 0→1, back 5 at 1→2
    p[[3, 1, 0]] = 100.0; // joint 1 jumps 100 at 2→3…
    assert_eq!(max_adjacent_jump(&p).unwrap(), 100.0);
    let mut conf = Array2::ones((4, 2));
    conf[[3, 1]] = 0.0; // …unless frame 3 of joint 1 is missing
    assert_eq!(
        max_adjacent_jump(Poses::new(p.view(), Some(conf.view())).unwrap()).unwrap(),
        5.0
    );
    let one = Array3::<f64>::zeros((1, 2, 2));
    assert!(matches!(
        max_adjacent_jump(&one),
        Err(GeomError::TooShort {
            needed: 2,
            got: 1,
            ..
        })
    ));
}

#[test]
fn bad_input() {
    let good = random_poses(3, 6, 2, 10);
    let empty = Array3::<f64>::zeros((0, 6, 2));
    let nojoint = Array3::<f64>::zeros((3, 0, 2));
    let mut nan = good.clone();
    nan[[2, 4, 1]] = f64::NAN;
    let other = random_poses(4, 6, 2, 11);
    let ctx = |e: GeomError| e.to_string();

    assert!(matches!(
        kd(&empty, &empty),
        Err(GeomError::TooShort { .. })
    ));
    assert!(matches!(kd(&nojoint, &nojoint), Err(GeomError::NoData(_))));
    match kd(&nan, &good) {
        Err(e @ GeomError::NonFinite(_)) => {
            let m = ctx(e);
            assert!(m.contains("frame 2") && m.contains("joint 4"), "{m}")
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(kd(&good, &other), Err(GeomError::Shape(_))));
    assert!(matches!(
        pck(&nan, &good, 0.05),
        Err(GeomError::NonFinite(_))
    ));
    assert!(matches!(
        pck(&good, &good, -0.1),
        Err(GeomError::InvalidParam { name: "alpha", .. })
    ));
    assert!(matches!(
        pck(&good, &good, f64::NAN),
        Err(GeomError::InvalidParam { .. })
    ));
    assert!(matches!(
        pck(&empty, &empty, 0.05),
        Err(GeomError::TooShort { .. })
    ));
    assert!(matches!(
        mpjpe(&good, &nan, None),
        Err(GeomError::NonFinite(_))
    ));
    assert!(matches!(
        mpjpe(&good, &other, None),
        Err(GeomError::Shape(_))
    ));
    assert!(matches!(
        pa_mpjpe(&nan, &good),
        Err(GeomError::NonFinite(_))
    ));
    assert!(matches!(
        pa_mpjpe(&empty, &empty),
        Err(GeomError::TooShort { .. })
    ));
    assert!(matches!(
        dtw(&nan, &good, DtwCost::Euclidean),
        Err(GeomError::NonFinite(_))
    ));
    assert!(matches!(
        dtw(&empty, &good, DtwCost::Euclidean),
        Err(GeomError::TooShort { .. })
    ));
    // different lengths are fine for DTW, not different joints
    assert!(dtw(&good, &other, DtwCost::Euclidean).is_ok());
    let fewer = random_poses(3, 5, 2, 12);
    assert!(matches!(
        dtw(&good, &fewer, DtwCost::Euclidean),
        Err(GeomError::Shape(_))
    ));
    assert!(matches!(
        max_adjacent_jump(&nan),
        Err(GeomError::NonFinite(_))
    ));
    assert!(matches!(
        max_adjacent_jump(&empty),
        Err(GeomError::TooShort { .. })
    ));
    // NaN confidence, wrong confidence shape
    let mut conf = Array2::ones((3, 6));
    conf[[0, 0]] = f64::NAN;
    let p = Poses::new(good.view(), Some(conf.view())).unwrap();
    assert!(matches!(kd(p, &good), Err(GeomError::NonFinite(_))));
    let wrong = Array2::ones((3, 5));
    assert!(matches!(
        Poses::new(good.view(), Some(wrong.view())),
        Err(GeomError::Shape(_))
    ));
    // procrustes
    let x = Array2::<f64>::zeros((0, 2));
    assert!(procrustes(x.view(), x.view()).is_err());
    assert!(nanmean(&[]).is_nan());
    assert!(nanmean(&[f64::NAN]).is_nan());
}
