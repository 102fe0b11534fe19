//! Refinement of tracks of other skeletons.
//!
//! The networks read the 20 MSR Action3D joints in 3D (metres, y up). A
//! BlazePose-33 track of world landmarks (`mp extract VIDEO --world`:
//! metres, hip-centred, y down) is mapped onto them with
//! [`SkeletonMap::blazepose33_world_to_msr20`] — y flipped; hip centre =
//! mean of the hips, neck = mean of the shoulders, spine midway between
//! them, hand = mean of the index and pinky knuckles, foot = foot index,
//! head = mean of the ears; the other joints selected. MSR Action3D is in
//! the Kinect's camera space (x to the camera's right, y up, z away from it),
//! BlazePose's world frame has the same x and z, so the flip keeps the body's
//! handedness, and [`crate::motion::canonicalize`] removes the remaining
//! difference (the root position and the heading about +y). The landmarks are
//! hip-centred in every frame, so the refined motion has no travel of the
//! whole body. Frames without a person are filled by interpolation before
//! refinement (and stay missing in the output).
//!
//! The refined MSR track is carried back onto the input's joints frame by
//! frame ([`SkeletonMap::carry_back_with`]): a joint that is an MSR joint
//! takes its refined position; the ears follow the refined head, the index
//! and pinky the refined hand, every other landmark the nearest MSR joint,
//! each translated by that joint's correction.

use mp_geom::Track;
use mp_geom::{FramePairing, SkeletonMap};

use crate::error::{RefineError, Result};
use crate::learned::{NetRefinement, NetRefiner};
use crate::motion::MSR_JOINTS;

/// How a track reaches the refinement networks: `None` for a 20-joint MSR
/// track in 3D, the map for BlazePose-33 world landmarks. Errors say what
/// is needed for 2D tracks and other skeletons.
pub(crate) fn msr20_map(track: &Track) -> Result<Option<SkeletonMap>> {
    let name = track.skeleton().name.as_str();
    if track.dims() != 3 {
        return Err(RefineError::Dims {
            what: format!(
                "refinement of a `{name}` track (it needs 3D positions in metres: 20 MSR Action3D \
                 joints, or BlazePose-33 world landmarks written by `mp extract VIDEO --world`)"
            ),
            expected: 3,
            got: track.dims(),
        });
    }
    if track.n_joints() == MSR_JOINTS && name != "blazepose33" {
        return Ok(None);
    }
    if name == "blazepose33" {
        return Ok(Some(SkeletonMap::blazepose33_world_to_msr20()?));
    }
    Err(RefineError::JointCount {
        what: format!(
            "refinement of a `{name}` track (20 MSR Action3D joints, or BlazePose-33 world \
             landmarks from `mp extract VIDEO --world`)"
        ),
        expected: MSR_JOINTS,
        got: track.n_joints(),
    })
}

/// A refinement carried back onto the input's skeleton.
#[derive(Debug, Clone)]
pub struct MappedRefinement {
    /// The refined track, on the input's skeleton.
    pub track: Track,
    /// The refinement of the 20 MSR joints (its report's joint indices are MSR joints).
    pub msr: NetRefinement,
    /// The map used (`None` for MSR-20 input).
    pub map: Option<SkeletonMap>,
}

/// Refines a 3D track of any supported skeleton (see the module docs) with
/// `refiner`; `action` as in [`NetRefiner::refine_track`].
pub fn refine_any(
    refiner: &NetRefiner<'_>,
    track: &Track,
    action: Option<u32>,
) -> Result<MappedRefinement> {
    let Some(map) = msr20_map(track)? else {
        let msr = refiner.refine_track(track, action)?;
        return Ok(MappedRefinement {
            track: msr.track.clone(),
            msr,
            map: None,
        });
    };
    let mut mapped = map.apply(track)?;
    mapped.fill_missing();
    let msr = refiner.refine_track(&mapped, action)?;
    let back = map.carry_back_with(track, &mapped, &msr.track, FramePairing::SameFrame)?;
    Ok(MappedRefinement {
        track: back,
        msr,
        map: Some(map),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_geom::{Skeleton, Units};
    use ndarray::Array3;

    #[test]
    fn two_d_tracks_and_other_skeletons_are_refused_naming_what_is_needed() {
        let flat = Track::new(
            Array3::zeros((10, 33, 2)),
            None,
            30.0,
            Units::Pixels,
            Skeleton::blazepose33(),
        )
        .unwrap();
        let e = msr20_map(&flat).unwrap_err().to_string();
        assert!(e.contains("--world"), "{e}");
        let coco = Track::new(
            Array3::zeros((10, 17, 3)),
            None,
            30.0,
            Units::Metres,
            Skeleton::coco17(),
        )
        .unwrap();
        let e = msr20_map(&coco).unwrap_err().to_string();
        assert!(e.contains("BlazePose-33 world"), "{e}");
        let msr = Track::new(
            Array3::zeros((10, 20, 3)),
            None,
            15.0,
            Units::Metres,
            Skeleton::msr20(),
        )
        .unwrap();
        assert!(msr20_map(&msr).unwrap().is_none());
        let world = Track::new(
            Array3::zeros((10, 33, 3)),
            None,
            30.0,
            Units::Metres,
            Skeleton::blazepose33(),
        )
        .unwrap();
        assert_eq!(msr20_map(&world).unwrap().unwrap().target().name, "msr20");
    }
}
