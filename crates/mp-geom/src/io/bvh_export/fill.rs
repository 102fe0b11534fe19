//! The geometry of the export: missing joints placed, rest offsets, and
//! the rotations that fit bones.

use glam::{DQuat, DVec3};
use nalgebra::Matrix3;

use super::tree::Tree;
use super::MIN_LENGTH;
use crate::stats::median;
use crate::track::Track;

pub(super) fn point(track: &Track, t: usize, j: usize) -> DVec3 {
    let p = track.point(t, j);
    DVec3::new(p[0], p[1], p[2])
}

/// The rigid motion (rotation, then translation) that best takes the
/// points `from` onto `to`: Kabsch about the centroids for three points or
/// more that are not in line, the smallest turn of the one direction for
/// two, a translation for one.
fn rigid_fit(from: &[DVec3], to: &[DVec3]) -> (DQuat, DVec3) {
    let n = from.len().max(1) as f64;
    let ca = from.iter().copied().sum::<DVec3>() / n;
    let cb = to.iter().copied().sum::<DVec3>() / n;
    let a: Vec<DVec3> = from.iter().map(|p| *p - ca).collect();
    let b: Vec<DVec3> = to.iter().map(|p| *p - cb).collect();
    let w: Vec<f64> = vec![1.0; a.len()];
    let q = if a.len() >= 3 {
        best_rotation(&a, &b, &w)
    } else {
        None
    };
    let q = q.unwrap_or_else(|| {
        // The longest arm that both frames have.
        match (0..a.len()).max_by(|&i, &k| a[i].length().total_cmp(&a[k].length())) {
            Some(i) if a[i].length() > MIN_LENGTH && b[i].length() > MIN_LENGTH => {
                DQuat::from_rotation_arc(a[i].normalize(), b[i].normalize())
            }
            _ => DQuat::IDENTITY,
        }
    });
    (q, cb - q * ca)
}

/// Most frames [`nearest`] tries.
const NEAREST_TRIES: usize = 2000;

/// The nearest frame to `f` in the sorted list `seen` for which `ok` holds
/// (among the [`NEAREST_TRIES`] nearest).
fn nearest(seen: &[usize], f: usize, ok: impl Fn(usize) -> bool) -> Option<usize> {
    let at = seen.partition_point(|&g| g < f);
    let (mut lo, mut hi) = (at, at);
    for _ in 0..NEAREST_TRIES {
        let g = match (lo.checked_sub(1).map(|i| seen[i]), seen.get(hi).copied()) {
            (Some(b), Some(a)) if f - b <= a - f => {
                lo -= 1;
                b
            }
            (_, Some(a)) => {
                hi += 1;
                a
            }
            (Some(b), None) => {
                lo -= 1;
                b
            }
            (None, None) => return None,
        };
        if ok(g) {
            return Some(g);
        }
    }
    None
}

/// The track with every joint placed, confidence 1 everywhere. A joint
/// missing in a frame moves rigidly with its neighbours along the bones:
/// first with those found in that frame, from the nearest frame where it
/// was found with them; then (where none was found) with all its
/// neighbours as placed so far, from the nearest frame where it was found.
/// A joint never found sits at the mean of its neighbours (those placed
/// first, then outwards).
pub(super) fn completed(track: &Track, nb: &[Vec<usize>]) -> Track {
    let (t_n, j_n) = (track.n_frames(), track.n_joints());
    let found = |f: usize, j: usize| track.is_valid(f, j, 0.0);
    let mut t = track.clone();
    // Interpolation in time first: what is left where nothing better applies.
    t.fill_missing();
    let mut pos = t.positions().to_owned();
    let at = |pos: &ndarray::Array3<f64>, f: usize, j: usize| {
        DVec3::new(pos[[f, j, 0]], pos[[f, j, 1]], pos[[f, j, 2]])
    };
    let seen: Vec<Vec<usize>> = (0..j_n)
        .map(|j| (0..t_n).filter(|&f| found(f, j)).collect())
        .collect();
    let mut placed = ndarray::Array2::from_shape_fn((t_n, j_n), |(f, j)| found(f, j));
    for pass in 0..2 {
        for j in 0..j_n {
            if seen[j].is_empty() {
                continue;
            }
            for f in 0..t_n {
                if placed[[f, j]] {
                    continue;
                }
                let with: Vec<usize> = if pass == 0 {
                    nb[j].iter().copied().filter(|&k| found(f, k)).collect()
                } else {
                    nb[j].clone()
                };
                if with.is_empty() {
                    continue;
                }
                let ok = |g: usize| pass == 1 || with.iter().all(|&k| found(g, k));
                let Some(g) = nearest(&seen[j], f, ok) else {
                    continue;
                };
                let from: Vec<DVec3> = with.iter().map(|&k| at(&pos, g, k)).collect();
                let to: Vec<DVec3> = with.iter().map(|&k| at(&pos, f, k)).collect();
                let (q, shift) = rigid_fit(&from, &to);
                let p = q * at(&pos, g, j) + shift;
                for k in 0..3 {
                    pos[[f, j, k]] = p[k];
                }
                placed[[f, j]] = true;
            }
        }
    }
    let mut known: Vec<bool> = seen.iter().map(|s| !s.is_empty()).collect();
    loop {
        let now: Vec<(usize, Vec<usize>)> = (0..j_n)
            .filter(|&j| !known[j])
            .filter_map(|j| {
                let from: Vec<usize> = nb[j].iter().copied().filter(|&k| known[k]).collect();
                (!from.is_empty()).then_some((j, from))
            })
            .collect();
        if now.is_empty() {
            break;
        }
        for (j, from) in &now {
            for f in 0..t_n {
                for k in 0..3 {
                    let m = from.iter().map(|&n| pos[[f, n, k]]).sum::<f64>() / from.len() as f64;
                    pos[[f, *j, k]] = m;
                }
            }
        }
        for (j, _) in now {
            known[j] = true;
        }
    }
    t.positions_mut().assign(&pos);
    t.confidence_mut().fill(1.0);
    t
}

/// The rest offset of every joint from its parent (zero for the root),
/// with the bones' directions in frame `rest`.
pub(super) fn rest_offsets(track: &Track, tree: &Tree, rest: usize) -> Vec<DVec3> {
    let (t_n, j_n) = (track.n_frames(), track.n_joints());
    let valid = |t: usize, j: usize| track.is_valid(t, j, 0.0);
    (0..j_n)
        .map(|j| {
            let Some(p) = tree.parent[j] else {
                return DVec3::ZERO;
            };
            let mut lengths: Vec<f64> = (0..t_n)
                .filter(|&t| valid(t, j) && valid(t, p))
                .map(|t| (point(track, t, j) - point(track, t, p)).length())
                .collect();
            let len = median(&mut lengths).unwrap_or(0.0);
            let dir = std::iter::once(rest)
                .chain(0..t_n)
                .filter(|&t| t < t_n && valid(t, j) && valid(t, p))
                .map(|t| point(track, t, j) - point(track, t, p))
                .find(|d| d.length() > MIN_LENGTH)
                .map_or(DVec3::ZERO, DVec3::normalize);
            dir * len
        })
        .collect()
}

/// Turns the rest directions of the children of each joint with several
/// into their mean configuration: the frames' child directions, each set
/// turned onto the current mean (Kabsch), averaged (twice, from the rest
/// frame's). Fitting one rotation to children whose angles change then
/// leaves the smallest misfit on average. Frames where the joint and all
/// those children were found in `source` are used, else every frame.
pub(super) fn mean_configurations(
    track: &Track,
    source: &Track,
    tree: &Tree,
    offsets: &mut [DVec3],
) {
    for j in 0..track.n_joints() {
        let kids: Vec<usize> = tree.children[j]
            .iter()
            .copied()
            .filter(|&c| offsets[c].length() > MIN_LENGTH)
            .collect();
        if kids.len() < 2 {
            continue;
        }
        let dirs = |t: usize| -> Option<Vec<DVec3>> {
            kids.iter()
                .map(|&c| {
                    let d = point(track, t, c) - point(track, t, j);
                    (d.length() > MIN_LENGTH).then(|| d.normalize())
                })
                .collect()
        };
        let all_found = |t: usize| {
            source.is_valid(t, j, 0.0) && kids.iter().all(|&c| source.is_valid(t, c, 0.0))
        };
        let mut frames: Vec<usize> = (0..track.n_frames()).filter(|&t| all_found(t)).collect();
        if frames.is_empty() {
            frames = (0..track.n_frames()).collect();
        }
        let sets: Vec<Vec<DVec3>> = frames.iter().filter_map(|&t| dirs(t)).collect();
        let w: Vec<f64> = kids.iter().map(|&c| offsets[c].length()).collect();
        let mut mean: Vec<DVec3> = kids.iter().map(|&c| offsets[c].normalize()).collect();
        for _ in 0..2 {
            let mut sum = vec![DVec3::ZERO; kids.len()];
            for set in &sets {
                if let Some(q) = best_rotation(set, &mean, &w) {
                    for (s, d) in sum.iter_mut().zip(set) {
                        *s += q * *d;
                    }
                }
            }
            if sum.iter().all(|s| s.length() > MIN_LENGTH) {
                mean = sum.iter().map(|s| s.normalize()).collect();
            }
        }
        for (k, &c) in kids.iter().enumerate() {
            offsets[c] = mean[k] * offsets[c].length();
        }
    }
}

/// The rotation that best turns the unit vectors `from` onto `to` (weights
/// `w`): Kabsch through the SVD of the cross-covariance. `None` when the
/// directions do not fix a rotation (fewer than two that are not parallel).
pub(super) fn best_rotation(from: &[DVec3], to: &[DVec3], w: &[f64]) -> Option<DQuat> {
    let mut h = Matrix3::<f64>::zeros();
    for ((a, b), &wi) in from.iter().zip(to).zip(w) {
        for r in 0..3 {
            for c in 0..3 {
                h[(r, c)] += wi * a[r] * b[c];
            }
        }
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let mut s: Vec<f64> = svd.singular_values.iter().copied().collect();
    s.sort_by(|a, b| b.total_cmp(a));
    if !(s[0] > 0.0 && s[1] > 1e-6 * s[0]) {
        return None;
    }
    let v = v_t.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, d)) * u.transpose();
    let m = glam::DMat3::from_cols_array(&[
        r[(0, 0)],
        r[(1, 0)],
        r[(2, 0)],
        r[(0, 1)],
        r[(1, 1)],
        r[(2, 1)],
        r[(0, 2)],
        r[(1, 2)],
        r[(2, 2)],
    ]);
    let q = DQuat::from_mat3(&m).normalize();
    q.is_finite().then_some(q)
}
