//! Skeletons as data: joint names, bones for drawing and the mapping to COCO-17.

use serde::{Deserialize, Serialize};

use crate::error::{GeomError, Result};

/// A named skeleton: joint names, bones (pairs of joint indices, for drawing)
/// and, where it exists, the mapping of each COCO-17 joint to a joint here.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Skeleton {
    /// Identifier, e.g. `coco17`, `blazepose33`, `penn13`, `msr20`, `bvh`.
    pub name: String,
    /// Joint names in storage order.
    pub joints: Vec<String>,
    /// Bones as (parent-ish, child-ish) joint index pairs, for drawing.
    pub bones: Vec<(usize, usize)>,
    /// For each of the 17 COCO joints, the index of the matching joint here
    /// (`None` where this skeleton has no such joint). Empty when no mapping exists.
    pub coco17: Vec<Option<usize>>,
    /// Index of the root joint (pelvis / hip centre), if the skeleton has one.
    pub root: Option<usize>,
}

/// COCO-17 joint names in order.
pub(crate) const COCO17_JOINTS: [&str; 17] = [
    "nose",
    "left_eye",
    "right_eye",
    "left_ear",
    "right_ear",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
];

const COCO17_BONES: [(usize, usize); 16] = [
    (0, 1),
    (0, 2),
    (1, 3),
    (2, 4),
    (5, 6),
    (5, 7),
    (7, 9),
    (6, 8),
    (8, 10),
    (5, 11),
    (6, 12),
    (11, 12),
    (11, 13),
    (13, 15),
    (12, 14),
    (14, 16),
];

/// BlazePose-33 landmark names in order.
pub(crate) const BLAZEPOSE33_JOINTS: [&str; 33] = [
    "nose",
    "left_eye_inner",
    "left_eye",
    "left_eye_outer",
    "right_eye_inner",
    "right_eye",
    "right_eye_outer",
    "left_ear",
    "right_ear",
    "mouth_left",
    "mouth_right",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_pinky",
    "right_pinky",
    "left_index",
    "right_index",
    "left_thumb",
    "right_thumb",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
    "left_heel",
    "right_heel",
    "left_foot_index",
    "right_foot_index",
];

/// The COCO-17 subset of BlazePose-33 (index into BlazePose for each COCO joint).
pub const BLAZEPOSE_TO_COCO17: [usize; 17] = [
    0, 2, 5, 7, 8, 11, 12, 13, 14, 15, 16, 23, 24, 25, 26, 27, 28,
];

const BLAZEPOSE33_BONES: [(usize, usize); 35] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 7),
    (0, 4),
    (4, 5),
    (5, 6),
    (6, 8),
    (9, 10),
    (11, 12),
    (11, 13),
    (13, 15),
    (15, 17),
    (15, 19),
    (15, 21),
    (17, 19),
    (12, 14),
    (14, 16),
    (16, 18),
    (16, 20),
    (16, 22),
    (18, 20),
    (11, 23),
    (12, 24),
    (23, 24),
    (23, 25),
    (24, 26),
    (25, 27),
    (26, 28),
    (27, 29),
    (28, 30),
    (29, 31),
    (30, 32),
    (27, 31),
    (28, 32),
];

/// Penn Action-13 joint names in order.
pub(crate) const PENN13_JOINTS: [&str; 13] = [
    "head",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
];

const PENN13_BONES: [(usize, usize); 12] = [
    (0, 1),
    (0, 2),
    (1, 3),
    (3, 5),
    (2, 4),
    (4, 6),
    (1, 7),
    (2, 8),
    (7, 9),
    (9, 11),
    (8, 10),
    (10, 12),
];

/// MSR Action3D-20 joint names in order (as stored in the shared npz).
pub(crate) const MSR20_JOINTS: [&str; 20] = [
    "right_shoulder",
    "left_shoulder",
    "neck",
    "spine",
    "right_hip",
    "left_hip",
    "hip_centre",
    "right_elbow",
    "left_elbow",
    "right_wrist",
    "left_wrist",
    "right_hand",
    "left_hand",
    "right_knee",
    "left_knee",
    "right_ankle",
    "left_ankle",
    "right_foot",
    "left_foot",
    "head",
];

const MSR20_BONES: [(usize, usize); 19] = [
    (19, 2),
    (2, 0),
    (2, 1),
    (2, 3),
    (3, 6),
    (6, 4),
    (6, 5),
    (0, 7),
    (7, 9),
    (9, 11),
    (1, 8),
    (8, 10),
    (10, 12),
    (4, 13),
    (13, 15),
    (15, 17),
    (5, 14),
    (14, 16),
    (16, 18),
];

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// Builds a COCO mapping by matching joint names.
fn coco_by_name(joints: &[String]) -> Vec<Option<usize>> {
    COCO17_JOINTS
        .iter()
        .map(|c| joints.iter().position(|j| j == c))
        .collect()
}

impl Skeleton {
    /// COCO-17 (also used by AIST++ and MoveNet).
    pub fn coco17() -> Self {
        Skeleton {
            name: "coco17".into(),
            joints: names(&COCO17_JOINTS),
            bones: COCO17_BONES.to_vec(),
            coco17: (0..17).map(Some).collect(),
            root: None,
        }
    }

    /// BlazePose-33 (MediaPipe Pose).
    pub fn blazepose33() -> Self {
        Skeleton {
            name: "blazepose33".into(),
            joints: names(&BLAZEPOSE33_JOINTS),
            bones: BLAZEPOSE33_BONES.to_vec(),
            coco17: BLAZEPOSE_TO_COCO17.iter().map(|&i| Some(i)).collect(),
            root: None,
        }
    }

    /// Penn Action-13.
    pub fn penn13() -> Self {
        let joints = names(&PENN13_JOINTS);
        let mut coco = coco_by_name(&joints);
        coco[0] = Some(0); // head stands in for the nose
        Skeleton {
            name: "penn13".into(),
            joints,
            bones: PENN13_BONES.to_vec(),
            coco17: coco,
            root: None,
        }
    }

    /// MSR Action3D-20 (Kinect v1 order as stored in the shared data).
    pub fn msr20() -> Self {
        let joints = names(&MSR20_JOINTS);
        let mut coco = coco_by_name(&joints);
        coco[0] = Some(19); // head stands in for the nose
        coco[9] = Some(10); // wrists
        coco[10] = Some(9);
        Skeleton {
            name: "msr20".into(),
            joints,
            bones: MSR20_BONES.to_vec(),
            coco17: coco,
            root: Some(6),
        }
    }

    /// A skeleton with the given joint names and bones and no COCO mapping
    /// beyond what matching names provide (used for BVH hierarchies).
    pub fn custom(
        name: &str,
        joints: Vec<String>,
        bones: Vec<(usize, usize)>,
        root: Option<usize>,
    ) -> Self {
        let coco = coco_by_name(&joints);
        let coco = if coco.iter().any(|c| c.is_some()) {
            coco
        } else {
            Vec::new()
        };
        Skeleton {
            name: name.into(),
            joints,
            bones,
            coco17: coco,
            root,
        }
    }

    /// A skeleton of `n` unnamed joints (`j0`, `j1`, …) without bones.
    pub fn generic(n: usize) -> Self {
        Skeleton {
            name: "generic".into(),
            joints: (0..n).map(|i| format!("j{i}")).collect(),
            bones: Vec::new(),
            coco17: Vec::new(),
            root: None,
        }
    }

    /// Looks a built-in skeleton up by name (`coco17`, `blazepose33`, `penn13`, `msr20`).
    pub fn by_name(name: &str) -> Result<Self> {
        match name {
            "coco17" | "coco" | "aistpp" | "movenet" => Ok(Self::coco17()),
            "blazepose33" | "blazepose" => Ok(Self::blazepose33()),
            "penn13" | "penn" => Ok(Self::penn13()),
            "msr20" | "msr" => Ok(Self::msr20()),
            _ => Err(GeomError::Unknown {
                kind: "skeleton",
                name: name.into(),
            }),
        }
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// True when the skeleton has no joints.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// Index of a joint by name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j == name)
    }

    /// Whether a complete mapping to COCO-17 exists.
    pub fn maps_to_coco17(&self) -> bool {
        self.coco17.len() == 17
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_are_consistent() {
        for s in [
            Skeleton::coco17(),
            Skeleton::blazepose33(),
            Skeleton::penn13(),
            Skeleton::msr20(),
        ] {
            for &(a, b) in &s.bones {
                assert!(a < s.len() && b < s.len(), "{}: bone out of range", s.name);
            }
            assert_eq!(s.coco17.len(), 17, "{}", s.name);
        }
        let b = Skeleton::blazepose33();
        assert_eq!(b.joints[b.coco17[5].unwrap()], "left_shoulder");
        let m = Skeleton::msr20();
        assert_eq!(m.joints[m.coco17[15].unwrap()], "left_ankle");
        assert!(Skeleton::by_name("nope").is_err());
    }
}
