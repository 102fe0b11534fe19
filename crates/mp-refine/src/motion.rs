//! The canonical motion representation the refinement networks see.
//!
//! Every network of this crate reads and writes clips of the MSR Action3D
//! 20-joint skeleton ([`mp_geom::Skeleton::msr20`]) in one canonical frame:
//!
//! * **time**: the clip is resampled (linear interpolation over its whole
//!   duration) to [`NET_FRAMES`] = 60 frames, as fixed-length motion
//!   generators do;
//! * **position**: the hip centre of the first frame is the origin;
//! * **heading**: the clip is rotated about the vertical axis (+y) so that the
//!   first frame's hip vector (left hip − right hip), projected on the ground
//!   plane, points along +x;
//! * **units**: metres (no scale normalisation: body size is part of the pose).
//!
//! [`canonicalize`] returns the canonical clip and the [`CanonicalFrame`]
//! needed by [`decanonicalize`] to put a (refined) canonical clip back where
//! the input was, at the input's frame count. [`bvh_to_msr20`] maps a CMU BVH
//! hierarchy's world positions onto the same 20 joints so mocap can be used
//! next to MSR Action3D.

use mp_geom::Bvh;
use mp_geom::{Skeleton, Track, Units};
use ndarray::{Array2, Array3, ArrayView3};
use serde::{Deserialize, Serialize};

use crate::error::{RefineError, Result};

/// Frames of every clip the networks read or write.
pub const NET_FRAMES: usize = 60;
/// Joints of the MSR Action3D skeleton.
pub const MSR_JOINTS: usize = 20;
/// Features per frame (`MSR_JOINTS × 3`).
pub const FRAME_FEATURES: usize = MSR_JOINTS * 3;
/// Index of the right hip in the MSR order.
pub(crate) const R_HIP: usize = 4;
/// Index of the left hip in the MSR order.
pub(crate) const L_HIP: usize = 5;
/// Index of the hip centre (root) in the MSR order.
pub const HIP_CENTRE: usize = 6;

/// Where a canonical clip came from: enough to undo [`canonicalize`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CanonicalFrame {
    /// Hip centre of the input's first frame (input units).
    pub origin: [f64; 3],
    /// Rotation about +y applied to the input, radians.
    pub yaw_rad: f64,
    /// Frames of the input.
    pub source_frames: usize,
    /// Frame rate of the input.
    pub source_fps: f64,
}

/// Output frame `f` of `n` frames spread evenly over `t ≥ 1` input frames:
/// the two input frames around it and the weight of the second.
pub(crate) fn resample_bracket(f: usize, n: usize, t: usize) -> (usize, usize, f64) {
    let u = if n <= 1 || t <= 1 {
        0.0
    } else {
        f as f64 * (t - 1) as f64 / (n - 1) as f64
    };
    let i0 = (u.floor() as usize).min(t.saturating_sub(1));
    let i1 = (i0 + 1).min(t.saturating_sub(1));
    (i0, i1, u - i0 as f64)
}

/// Resamples `x` (`T × J × D`) to `n` frames by linear interpolation over
/// the whole duration (frame 0 ↦ 0, frame `T−1` ↦ `n−1`).
pub fn resample(x: ArrayView3<'_, f64>, n: usize) -> Result<Array3<f64>> {
    let (t, j, d) = x.dim();
    if t == 0 {
        return Err(RefineError::TooShort {
            what: "resampling".into(),
            needed: 1,
            got: 0,
        });
    }
    if n == 0 {
        return Err(RefineError::param("frames", "must be ≥ 1"));
    }
    let mut out = Array3::<f64>::zeros((n, j, d));
    for f in 0..n {
        let (i0, i1, w) = resample_bracket(f, n, t);
        for a in 0..j {
            for k in 0..d {
                out[[f, a, k]] = (1.0 - w) * x[[i0, a, k]] + w * x[[i1, a, k]];
            }
        }
    }
    Ok(out)
}

fn check_msr(track: &Track, what: &str) -> Result<()> {
    if track.n_joints() != MSR_JOINTS {
        return Err(RefineError::JointCount {
            what: what.into(),
            expected: MSR_JOINTS,
            got: track.n_joints(),
        });
    }
    if track.dims() != 3 {
        return Err(RefineError::Dims {
            what: what.into(),
            expected: 3,
            got: track.dims(),
        });
    }
    if track.n_frames() < 2 {
        return Err(RefineError::TooShort {
            what: what.into(),
            needed: 2,
            got: track.n_frames(),
        });
    }
    Ok(())
}

/// Rotates points about +y by `yaw` (x' = c·x + s·z, z' = −s·x + c·z).
fn rotate_y(x: f64, z: f64, yaw: f64) -> (f64, f64) {
    let (s, c) = yaw.sin_cos();
    (c * x + s * z, -s * x + c * z)
}

/// Puts a 20-joint 3D track in the canonical frame at [`NET_FRAMES`] frames.
///
/// Missing joints (confidence 0) are used as stored; callers that care fill
/// them first ([`Track::fill_missing`]).
pub fn canonicalize(track: &Track) -> Result<(Array3<f64>, CanonicalFrame)> {
    check_msr(track, "canonical motion")?;
    let p = track.positions();
    if p.iter().any(|v| !v.is_finite()) {
        return Err(RefineError::NonFinite(
            "canonical motion: the track has a non-finite coordinate".into(),
        ));
    }
    let origin = [
        p[[0, HIP_CENTRE, 0]],
        p[[0, HIP_CENTRE, 1]],
        p[[0, HIP_CENTRE, 2]],
    ];
    let hx = p[[0, L_HIP, 0]] - p[[0, R_HIP, 0]];
    let hz = p[[0, L_HIP, 2]] - p[[0, R_HIP, 2]];
    // Rotate the hip vector onto +x: after rotation z' = −s·hx + c·hz = 0.
    let yaw = if hx.abs() + hz.abs() > 1e-9 {
        hz.atan2(hx)
    } else {
        0.0
    };
    let mut x = resample(p, NET_FRAMES)?;
    for mut frame in x.outer_iter_mut() {
        for mut joint in frame.outer_iter_mut() {
            let (a, b) = rotate_y(joint[0] - origin[0], joint[2] - origin[2], yaw);
            joint[0] = a;
            joint[1] -= origin[1];
            joint[2] = b;
        }
    }
    Ok((
        x,
        CanonicalFrame {
            origin,
            yaw_rad: yaw,
            source_frames: track.n_frames(),
            source_fps: track.fps(),
        },
    ))
}

/// Undoes [`canonicalize`]: rotates and translates a canonical clip back and
/// resamples it to the source's frame count. Confidence is 1 everywhere.
pub fn decanonicalize(x: ArrayView3<'_, f64>, frame: &CanonicalFrame) -> Result<Track> {
    let (_, j, d) = x.dim();
    if j != MSR_JOINTS || d != 3 {
        return Err(RefineError::Shape(format!(
            "decanonicalize: expected (frames, {MSR_JOINTS}, 3), got {:?}",
            x.dim()
        )));
    }
    if x.iter().any(|v| !v.is_finite()) {
        return Err(RefineError::NonFinite(
            "decanonicalize: the clip has a non-finite coordinate".into(),
        ));
    }
    let mut out = resample(x, frame.source_frames)?;
    for mut f in out.outer_iter_mut() {
        for mut joint in f.outer_iter_mut() {
            let (a, b) = rotate_y(joint[0], joint[2], -frame.yaw_rad);
            joint[0] = a + frame.origin[0];
            joint[1] += frame.origin[1];
            joint[2] = b + frame.origin[2];
        }
    }
    let t = out.dim().0;
    Ok(Track::new(
        out,
        Some(Array2::ones((t, MSR_JOINTS))),
        frame.source_fps,
        Units::Metres,
        Skeleton::msr20(),
    )?)
}

/// Flattens a canonical clip (`T × 20 × 3`) to `T × 60` `f32` features
/// (joint-major: x, y, z of joint 0, then joint 1, …), the layout of every
/// network input and output.
pub fn to_features(x: ArrayView3<'_, f64>) -> Array2<f32> {
    let (t, j, d) = x.dim();
    let mut out = Array2::<f32>::zeros((t, j * d));
    for f in 0..t {
        for a in 0..j {
            for k in 0..d {
                out[[f, a * d + k]] = x[[f, a, k]] as f32;
            }
        }
    }
    out
}

/// Inverse of [`to_features`].
pub fn from_features(x: ndarray::ArrayView2<'_, f32>) -> Result<Array3<f64>> {
    let (t, n) = x.dim();
    if n != FRAME_FEATURES {
        return Err(RefineError::Shape(format!(
            "from_features: expected {FRAME_FEATURES} features per frame, got {n}"
        )));
    }
    let mut out = Array3::<f64>::zeros((t, MSR_JOINTS, 3));
    for f in 0..t {
        for a in 0..MSR_JOINTS {
            for k in 0..3 {
                out[[f, a, k]] = x[[f, a * 3 + k]] as f64;
            }
        }
    }
    Ok(out)
}

/// BVH joint (CMU naming) that stands for each MSR joint, in MSR order.
/// `*_end` is the end site of the named joint.
pub(crate) const CMU_BVH_TO_MSR20: [&str; MSR_JOINTS] = [
    "rShldr",    // R shoulder
    "lShldr",    // L shoulder
    "neck",      // neck
    "abdomen",   // spine
    "rThigh",    // R hip
    "lThigh",    // L hip
    "hip",       // hip centre
    "rForeArm",  // R elbow
    "lForeArm",  // L elbow
    "rHand",     // R wrist
    "lHand",     // L wrist
    "rMid1",     // R hand
    "lMid1",     // L hand
    "rShin",     // R knee
    "lShin",     // L knee
    "rFoot",     // R ankle
    "lFoot",     // L ankle
    "rFoot_end", // R foot
    "lFoot_end", // L foot
    "head",      // head
];

/// BVH length unit → metres of [`bvh_to_msr20`] when none is given: 1 (the
/// CMU salsa files are in metres).
pub const DEFAULT_BVH_LENGTH_SCALE: f64 = 1.0;

/// World positions of a CMU-style BVH mapped onto the 20 MSR joints,
/// resampled to `fps` (linear interpolation), in metres after `length_scale`.
pub fn bvh_to_msr20(bvh: &Bvh, length_scale: f64, fps: f64) -> Result<Track> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(RefineError::param(
            "fps",
            format!("must be finite and > 0, got {fps}"),
        ));
    }
    let pos = bvh.world_positions(length_scale, true)?;
    let sk = bvh.skeleton(true);
    let mut idx = Vec::with_capacity(MSR_JOINTS);
    for name in CMU_BVH_TO_MSR20 {
        let i = sk.joints.iter().position(|n| n == name).ok_or_else(|| {
            RefineError::Shape(format!(
                "BVH to MSR joints: the hierarchy has no joint `{name}` (CMU naming expected)"
            ))
        })?;
        idx.push(i);
    }
    let t = pos.dim().0;
    if t < 2 {
        return Err(RefineError::TooShort {
            what: "BVH to MSR joints".into(),
            needed: 2,
            got: t,
        });
    }
    let mut sel = Array3::<f64>::zeros((t, MSR_JOINTS, 3));
    for f in 0..t {
        for (a, &i) in idx.iter().enumerate() {
            for k in 0..3 {
                sel[[f, a, k]] = pos[[f, i, k]];
            }
        }
    }
    let src_fps = bvh.fps();
    let n = (((t - 1) as f64) * fps / src_fps).round() as usize + 1;
    let out = resample(sel.view(), n.max(2))?;
    let n = out.dim().0;
    Ok(Track::new(
        out,
        Some(Array2::ones((n, MSR_JOINTS))),
        fps,
        Units::Metres,
        Skeleton::msr20(),
    )?)
}

/// Per canonical frame and joint: whether a source frame in the frame's
/// support (the one or two source frames it interpolates, with non-zero
/// weight) is flagged in `src` (`T × J`).
pub fn canonical_mask(src: &Array2<bool>, n: usize) -> Array2<bool> {
    let (t, j) = src.dim();
    let mut out = Array2::from_elem((n, j), false);
    if t == 0 {
        return out;
    }
    for f in 0..n {
        let (i0, i1, w) = resample_bracket(f, n, t);
        for a in 0..j {
            out[[f, a]] = (w < 1.0 - 1e-9 && src[[i0, a]]) || (w > 1e-9 && src[[i1, a]]);
        }
    }
    out
}

/// Joints of `flawed` that differ from `clean` by more than `eps` (`T × J`).
pub fn changed_joints(clean: &Track, flawed: &Track, eps: f64) -> Array2<bool> {
    let (a, b) = (clean.positions(), flawed.positions());
    let (t, j, d) = a.dim();
    let mut out = Array2::from_elem((t, j), false);
    if b.dim() != a.dim() {
        return out;
    }
    for f in 0..t {
        for k in 0..j {
            let mut s = 0.0;
            for x in 0..d {
                let v = b[[f, k, x]] - a[[f, k, x]];
                s += v * v;
            }
            out[[f, k]] = s.sqrt() > eps;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip(t: usize) -> Track {
        let mut p = Array3::<f64>::zeros((t, MSR_JOINTS, 3));
        for f in 0..t {
            for j in 0..MSR_JOINTS {
                p[[f, j, 0]] = 1.0 + 0.1 * j as f64 + 0.01 * f as f64;
                p[[f, j, 1]] = 0.05 * j as f64;
                p[[f, j, 2]] = 3.0 - 0.02 * j as f64 + 0.003 * (f * f) as f64;
            }
        }
        Track::new(p, None, 15.0, Units::Metres, Skeleton::msr20()).unwrap()
    }

    #[test]
    fn canonical_frame_puts_root_at_origin_and_hips_on_x() {
        let (c, _) = canonicalize(&clip(37)).unwrap();
        assert_eq!(c.dim(), (NET_FRAMES, MSR_JOINTS, 3));
        for k in 0..3 {
            assert!(c[[0, HIP_CENTRE, k]].abs() < 1e-12);
        }
        let hz = c[[0, L_HIP, 2]] - c[[0, R_HIP, 2]];
        let hx = c[[0, L_HIP, 0]] - c[[0, R_HIP, 0]];
        assert!(hz.abs() < 1e-12 && hx > 0.0);
    }

    #[test]
    fn decanonicalize_inverts_canonicalize() {
        let t = clip(60);
        let (c, fr) = canonicalize(&t).unwrap();
        let back = decanonicalize(c.view(), &fr).unwrap();
        assert_eq!(back.n_frames(), 60);
        let err = (&back.positions() - &t.positions())
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(err < 1e-9, "{err}");
    }

    #[test]
    fn features_round_trip_and_reject_bad_input() {
        let (c, _) = canonicalize(&clip(20)).unwrap();
        let f = to_features(c.view());
        assert_eq!(f.dim(), (NET_FRAMES, FRAME_FEATURES));
        let back = from_features(f.view()).unwrap();
        assert!((back[[5, 3, 2]] - c[[5, 3, 2]]).abs() < 1e-6);
        let coco = Track::new(
            Array3::zeros((10, 17, 3)),
            None,
            15.0,
            Units::Metres,
            Skeleton::coco17(),
        )
        .unwrap();
        assert!(matches!(
            canonicalize(&coco),
            Err(RefineError::JointCount { got: 17, .. })
        ));
        assert!(matches!(
            canonicalize(&clip(1)),
            Err(RefineError::TooShort { .. })
        ));
    }

    #[test]
    fn cmu_salsa_maps_to_msr_joints() {
        let path = mp_geom::data_or_return!("cmu_salsa_bvh/60_01_scaled.bvh");
        let bvh = Bvh::read(path).unwrap();
        let t = bvh_to_msr20(&bvh, 1.0, 15.0).unwrap();
        assert_eq!(t.n_joints(), MSR_JOINTS);
        let expected = ((bvh.n_frames() - 1) as f64 * 15.0 / bvh.fps()).round() as usize + 1;
        assert_eq!(t.n_frames(), expected);
        // Head above hip centre, hip centre above the ankles, plausible height in metres.
        let p = t.positions();
        let head = p[[0, 19, 1]];
        let hip = p[[0, HIP_CENTRE, 1]];
        let ankle = p[[0, 15, 1]];
        assert!(head > hip && hip > ankle, "{head} {hip} {ankle}");
        assert!((0.8..2.5).contains(&(head - ankle)), "{}", head - ankle);
    }
}
