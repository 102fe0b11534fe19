//! Forecasting tracks of the product's skeletons with models of another.
//!
//! The learned models are trained on Penn Action (13 joints, 2D pixels) and
//! MSR Action3D (20 joints, 3D metres), while `mp extract` and `mp run` write
//! COCO-17 or BlazePose-33 tracks. [`model_dataset`] picks the model for a
//! track, [`map_to_model`] the [`SkeletonMap`] onto the model's joints, and
//! [`MappedForecaster`] runs any [`Forecaster`] of the model's skeleton on
//! the track: the observed frames are mapped onto the model's joints, the
//! model predicts, and the prediction is carried back onto the input's
//! joints ([`SkeletonMap::carry_back`] with [`FramePairing::LastFrame`]):
//!
//! | input | model | mapping | joints the model does not predict |
//! |---|---|---|---|
//! | `coco17`, 2D | `penn_action` | joint selection, the nose as the head | eyes, ears: carried rigidly with the nearest predicted joint (the head) |
//! | `blazepose33`, 2D | `penn_action` | its COCO-17 joints, then as `coco17` | face, hand and foot landmarks: carried rigidly with the nearest predicted joint |
//! | `blazepose33`, 3D world landmarks | `msr_action3d` | y up; hip centre, spine, neck, hands, feet, head derived (`mp_geom::skeleton_map`) | ears with the head, index and pinky with the hand, the rest with the nearest joint |
//! | `penn13` 2D, `msr20` 3D | its own | none | – |
//!
//! "Carried rigidly" means translated: the joint keeps its offset from its
//! carrier in the last observed frame where both were seen.

use mp_geom::{FramePairing, SkeletonMap};
use mp_geom::{Skeleton, Track};

use crate::error::{ForecastError, Result};
use crate::forecaster::Forecaster;

/// The data set whose forecasting models suit a track of `skeleton` with
/// `dims` coordinates per joint (see the module docs); `None` when none does.
pub fn model_dataset(skeleton: &Skeleton, dims: usize) -> Option<&'static str> {
    match (skeleton.name.as_str(), dims) {
        ("penn13" | "coco17", 2) | ("blazepose33", 2) => Some("penn_action"),
        ("msr20", 3) | ("blazepose33", 3) => Some("msr_action3d"),
        _ => None,
    }
}

/// The map from a track's skeleton onto a model's joints (`model_joints`,
/// in the model's order), or `None` when the track already has them (or,
/// for skeletons without a built-in map, as many joints, taken in order).
/// Errors name what the model needs when no built-in map fits.
pub fn map_to_model(
    skeleton: &Skeleton,
    dims: usize,
    model_joints: &[String],
) -> Result<Option<SkeletonMap>> {
    let builtin = ["coco17", "blazepose33", "penn13", "msr20"];
    if skeleton.joints == model_joints
        || (skeleton.len() == model_joints.len() && !builtin.contains(&skeleton.name.as_str()))
    {
        return Ok(None);
    }
    let mismatch = |why: String| {
        ForecastError::mismatch(
            "the forecasting model",
            format!(
                "a track of its {} joints, or one that maps onto them",
                model_joints.len()
            ),
            why,
        )
    };
    let target = [Skeleton::penn13(), Skeleton::msr20()]
        .into_iter()
        .find(|t| t.joints == model_joints)
        .ok_or_else(|| {
            mismatch(format!(
                "skeleton `{}` and the model's joints are no built-in skeleton",
                skeleton.name
            ))
        })?;
    let map = SkeletonMap::builtin(skeleton, &target.name)
        .map_err(|e| mismatch(format!("skeleton `{}` ({dims}D): {e}", skeleton.name)))?;
    if let Some(d) = map.dims().filter(|&d| d != dims) {
        return Err(mismatch(format!(
            "skeleton `{}` in {dims}D; mapping it onto `{}` needs {d}D positions{}",
            skeleton.name,
            target.name,
            if d == 3 {
                " (BlazePose world landmarks: `mp extract VIDEO --world`)"
            } else {
                ""
            }
        )));
    }
    Ok(Some(map))
}

/// A [`Forecaster`] of a model's skeleton run on tracks of another skeleton
/// through a [`SkeletonMap`] (see the module docs). Predictions have the
/// input's skeleton, frame rate and units.
#[derive(Debug, Clone)]
pub struct MappedForecaster<F> {
    inner: F,
    map: SkeletonMap,
}

impl<F: Forecaster> MappedForecaster<F> {
    /// `inner` (a forecaster of `map`'s target skeleton) on tracks of `map`'s source skeleton.
    pub fn new(inner: F, map: SkeletonMap) -> Self {
        MappedForecaster { inner, map }
    }
}

impl<F: Forecaster> Forecaster for MappedForecaster<F> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn context_frames(&self) -> Option<usize> {
        self.inner.context_frames()
    }
    fn predict(&self, past: &Track, horizon: usize) -> Result<Track> {
        let mapped = self.map.apply(past)?;
        let pred = self.inner.predict(&mapped, horizon)?;
        Ok(self
            .map
            .carry_back_with(past, &mapped, &pred, FramePairing::LastFrame)?)
    }
    fn predict_batch(&self, pasts: &[Track], horizon: usize) -> Result<Vec<Track>> {
        let mapped = pasts
            .iter()
            .map(|p| self.map.apply(p))
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let preds = self.inner.predict_batch(&mapped, horizon)?;
        pasts
            .iter()
            .zip(&mapped)
            .zip(&preds)
            .map(|((p, m), pr)| {
                Ok(self
                    .map
                    .carry_back_with(p, m, pr, FramePairing::LastFrame)?)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forecaster::Constant;
    use mp_geom::Units;
    use ndarray::Array3;

    fn names(s: &Skeleton) -> Vec<String> {
        s.joints.clone()
    }

    fn moving(skeleton: Skeleton, frames: usize, d: usize) -> Track {
        let j = skeleton.len();
        let pos = Array3::from_shape_fn((frames, j, d), |(f, a, k)| {
            100.0 + 7.0 * a as f64 + 13.0 * k as f64 + 2.0 * f as f64
        });
        Track::new(pos, None, 30.0, Units::Pixels, skeleton).unwrap()
    }

    #[test]
    fn product_skeletons_find_a_model() {
        assert_eq!(model_dataset(&Skeleton::coco17(), 2), Some("penn_action"));
        assert_eq!(
            model_dataset(&Skeleton::blazepose33(), 2),
            Some("penn_action")
        );
        assert_eq!(
            model_dataset(&Skeleton::blazepose33(), 3),
            Some("msr_action3d")
        );
        assert_eq!(model_dataset(&Skeleton::coco17(), 3), None);
        let penn = names(&Skeleton::penn13());
        assert!(map_to_model(&Skeleton::penn13(), 2, &penn)
            .unwrap()
            .is_none());
        let m = map_to_model(&Skeleton::coco17(), 2, &penn)
            .unwrap()
            .unwrap();
        assert_eq!(m.target().name, "penn13");
        // 2D BlazePose cannot reach the 3D MSR model: the message says what is needed
        let msr = names(&Skeleton::msr20());
        let e = map_to_model(&Skeleton::blazepose33(), 2, &msr)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--world"), "{e}");
        assert!(map_to_model(&Skeleton::msr20(), 3, &penn).is_err());
    }

    #[test]
    fn a_mapped_forecast_has_the_input_skeleton_and_continues_from_the_last_pose() {
        let penn = names(&Skeleton::penn13());
        for sk in [Skeleton::coco17(), Skeleton::blazepose33()] {
            let map = map_to_model(&sk, 2, &penn).unwrap().unwrap();
            let f = MappedForecaster::new(Constant, map);
            let past = moving(sk.clone(), 20, 2);
            let pred = f.predict(&past, 7).unwrap();
            assert_eq!(pred.skeleton().name, sk.name);
            assert_eq!(pred.n_frames(), 7);
            // holding the mapped last pose holds every joint, carried ones included
            for h in 0..7 {
                for j in 0..sk.len() {
                    for k in 0..2 {
                        let d = pred.point(h, j)[k] - past.point(19, j)[k];
                        assert!(d.abs() < 1e-9, "{} joint {j}: {d}", sk.name);
                    }
                }
            }
            let batch = f.predict_batch(&[past.clone(), past], 3).unwrap();
            assert_eq!(batch.len(), 2);
            assert_eq!(batch[1].skeleton().name, sk.name);
        }
    }
}
