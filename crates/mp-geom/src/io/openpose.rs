//! OpenPose and AlphaPose keypoint files.
//!
//! **OpenPose**: a folder with one `*_keypoints.json` per frame (frames in
//! file-name order), each `{"people": [{"pose_keypoints_2d": [x, y, c, …]}]}`
//! (older files: `pose_keypoints`). 25 keypoints are BODY_25, 18 are COCO-18
//! (OpenPose's COCO order, with a neck). When several people are present the
//! one with the highest mean confidence is kept; a frame with nobody has
//! every joint missing. OpenPose writes `0, 0, 0` for joints it did not find,
//! which become confidence 0.
//!
//! **AlphaPose**: one results JSON, a list of `{"image_id", "keypoints":
//! [x, y, s, …], "score"}`; 17 keypoints (COCO-17; for Halpe-26/136 results
//! the first 17, which are COCO-17). One person per image: the highest
//! `score`. Frames follow the order in which image ids first appear.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use ndarray::{Array2, Array3};

use super::ReadOptions;
use crate::error::{GeomError, Result};
use crate::skeleton::Skeleton;
use crate::track::Track;

/// OpenPose BODY_25 joint names in order.
pub(crate) const BODY25_JOINTS: [&str; 25] = [
    "nose",
    "neck",
    "right_shoulder",
    "right_elbow",
    "right_wrist",
    "left_shoulder",
    "left_elbow",
    "left_wrist",
    "mid_hip",
    "right_hip",
    "right_knee",
    "right_ankle",
    "left_hip",
    "left_knee",
    "left_ankle",
    "right_eye",
    "left_eye",
    "right_ear",
    "left_ear",
    "left_big_toe",
    "left_small_toe",
    "left_heel",
    "right_big_toe",
    "right_small_toe",
    "right_heel",
];

const BODY25_BONES: [(usize, usize); 24] = [
    (1, 8),
    (1, 2),
    (1, 5),
    (2, 3),
    (3, 4),
    (5, 6),
    (6, 7),
    (8, 9),
    (9, 10),
    (10, 11),
    (8, 12),
    (12, 13),
    (13, 14),
    (1, 0),
    (0, 15),
    (15, 17),
    (0, 16),
    (16, 18),
    (14, 19),
    (19, 20),
    (14, 21),
    (11, 22),
    (22, 23),
    (11, 24),
];

/// OpenPose COCO-18 joint names in order.
pub(crate) const COCO18_JOINTS: [&str; 18] = [
    "nose",
    "neck",
    "right_shoulder",
    "right_elbow",
    "right_wrist",
    "left_shoulder",
    "left_elbow",
    "left_wrist",
    "right_hip",
    "right_knee",
    "right_ankle",
    "left_hip",
    "left_knee",
    "left_ankle",
    "right_eye",
    "left_eye",
    "right_ear",
    "left_ear",
];

const COCO18_BONES: [(usize, usize); 17] = [
    (1, 2),
    (1, 5),
    (2, 3),
    (3, 4),
    (5, 6),
    (6, 7),
    (1, 8),
    (8, 9),
    (9, 10),
    (1, 11),
    (11, 12),
    (12, 13),
    (1, 0),
    (0, 14),
    (14, 16),
    (0, 15),
    (15, 17),
];

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// OpenPose BODY_25 with its COCO-17 mapping (by joint name; root = mid hip).
pub fn body25_skeleton() -> Skeleton {
    Skeleton::custom(
        "body25",
        names(&BODY25_JOINTS),
        BODY25_BONES.to_vec(),
        Some(8),
    )
}

/// OpenPose COCO-18 with its COCO-17 mapping (by joint name).
pub fn coco18_skeleton() -> Skeleton {
    Skeleton::custom(
        "openpose_coco18",
        names(&COCO18_JOINTS),
        COCO18_BONES.to_vec(),
        None,
    )
}

fn keypoints_of(person: &serde_json::Value) -> Option<Vec<f64>> {
    let arr = person
        .get("pose_keypoints_2d")
        .or_else(|| person.get("pose_keypoints"))?
        .as_array()?;
    arr.iter().map(|v| v.as_f64()).collect()
}

/// Builds a track from parsed OpenPose frames (file, JSON), in order.
pub fn openpose_from_frames(
    frames: &[(PathBuf, serde_json::Value)],
    opts: &ReadOptions,
) -> Result<Track> {
    opts.validate()?;
    let mut per_frame: Vec<Option<Vec<f64>>> = Vec::with_capacity(frames.len());
    let mut n_joints: Option<usize> = None;
    for (path, value) in frames {
        let people = value
            .get("people")
            .and_then(|p| p.as_array())
            .ok_or_else(|| GeomError::format(path, "no `people` list"))?;
        let mut best: Option<(f64, Vec<f64>)> = None;
        for (pi, person) in people.iter().enumerate() {
            let kp = keypoints_of(person).ok_or_else(|| {
                GeomError::format(
                    path,
                    format!("people[{pi}] has no numeric `pose_keypoints_2d`"),
                )
            })?;
            if kp.is_empty() {
                continue;
            }
            if kp.len() / 3 * 3 != kp.len() {
                return Err(GeomError::format(
                    path,
                    format!("people[{pi}]: {} values is not a multiple of 3", kp.len()),
                ));
            }
            let nj = kp.len() / 3;
            if nj != 25 && nj != 18 {
                return Err(GeomError::format(
                    path,
                    format!("people[{pi}]: {nj} keypoints; BODY_25 (25) or COCO-18 (18) expected"),
                ));
            }
            match n_joints {
                None => n_joints = Some(nj),
                Some(n) if n != nj => {
                    return Err(GeomError::format(
                        path,
                        format!("people[{pi}] has {nj} keypoints, earlier frames {n}"),
                    ))
                }
                _ => {}
            }
            let mean = kp.iter().skip(2).step_by(3).sum::<f64>() / nj as f64;
            if best.as_ref().is_none_or(|(m, _)| mean > *m) {
                best = Some((mean, kp));
            }
        }
        per_frame.push(best.map(|(_, k)| k));
    }
    let j = n_joints.unwrap_or(25);
    let t = per_frame.len();
    if t == 0 {
        return Err(GeomError::NoData("no OpenPose frames".into()));
    }
    let mut pos = Array3::<f64>::zeros((t, j, 2));
    let mut conf = Array2::<f64>::zeros((t, j));
    for (f, kp) in per_frame.iter().enumerate() {
        if let Some(kp) = kp {
            for ji in 0..j {
                pos[[f, ji, 0]] = kp[3 * ji];
                pos[[f, ji, 1]] = kp[3 * ji + 1];
                conf[[f, ji]] = kp[3 * ji + 2];
            }
        }
    }
    let skeleton = match &opts.skeleton {
        Some(s) if s.len() == j => s.clone(),
        _ if j == 18 => coco18_skeleton(),
        _ => body25_skeleton(),
    };
    Track::new(pos, Some(conf), opts.rate(), opts.units_for(2), skeleton)
}

/// Reads an OpenPose output folder (`*_keypoints.json`, sorted by file name;
/// when there are none, every `*.json`).
pub fn read_openpose_dir(dir: impl AsRef<Path>, opts: &ReadOptions) -> Result<Track> {
    let dir = dir.as_ref();
    let entries = std::fs::read_dir(dir).map_err(|e| GeomError::io(dir, e))?;
    let mut files: Vec<PathBuf> = Vec::new();
    for e in entries {
        let e = e.map_err(|e| GeomError::io(dir, e))?;
        let p = e.path();
        if p.extension().and_then(|x| x.to_str()) == Some("json") {
            files.push(p);
        }
    }
    let keyed: Vec<PathBuf> = files
        .iter()
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.ends_with("_keypoints.json"))
        })
        .cloned()
        .collect();
    let mut files = if keyed.is_empty() { files } else { keyed };
    files.sort();
    if files.is_empty() {
        return Err(GeomError::format(
            dir,
            "no OpenPose *_keypoints.json files in this folder",
        ));
    }
    let mut frames = Vec::with_capacity(files.len());
    for p in files {
        let text = std::fs::read_to_string(&p).map_err(|e| GeomError::io(&p, e))?;
        let v: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| GeomError::format(&p, format!("invalid JSON: {e}")))?;
        frames.push((p, v));
    }
    openpose_from_frames(&frames, opts)
}

/// Builds a track from a parsed AlphaPose result list.
pub fn alphapose_from_value(
    value: &serde_json::Value,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Track> {
    opts.validate()?;
    let list = value
        .as_array()
        .ok_or_else(|| GeomError::format(path, "AlphaPose results must be a JSON list"))?;
    let mut order: Vec<String> = Vec::new();
    let mut best: HashMap<String, (f64, Vec<f64>)> = HashMap::new();
    for (i, item) in list.iter().enumerate() {
        let id = match item.get("image_id") {
            Some(serde_json::Value::String(s)) => s.clone(),
            Some(serde_json::Value::Number(n)) => n.to_string(),
            _ => {
                return Err(GeomError::format(
                    path,
                    format!("entry {i} has no `image_id`"),
                ))
            }
        };
        let kp: Vec<f64> = item
            .get("keypoints")
            .and_then(|k| k.as_array())
            .and_then(|a| a.iter().map(|v| v.as_f64()).collect::<Option<Vec<f64>>>())
            .ok_or_else(|| {
                GeomError::format(
                    path,
                    format!("entry {i} (`{id}`) has no numeric `keypoints`"),
                )
            })?;
        if kp.len() / 3 * 3 != kp.len() || kp.len() / 3 < 17 {
            return Err(GeomError::format(
                path,
                format!(
                    "entry {i} (`{id}`): {} keypoint values; at least 17 (x, y, score) triples expected",
                    kp.len()
                ),
            ));
        }
        let score = item
            .get("score")
            .and_then(|s| s.as_f64())
            .unwrap_or_else(|| kp.iter().skip(2).step_by(3).take(17).sum::<f64>() / 17.0);
        if !best.contains_key(&id) {
            order.push(id.clone());
        }
        let replace = best.get(&id).is_none_or(|(s, _)| score > *s);
        if replace {
            best.insert(id, (score, kp));
        }
    }
    if order.is_empty() {
        return Err(GeomError::NoData(format!(
            "{}: no detections",
            path.display()
        )));
    }
    let t = order.len();
    let mut pos = Array3::<f64>::zeros((t, 17, 2));
    let mut conf = Array2::<f64>::zeros((t, 17));
    for (f, id) in order.iter().enumerate() {
        if let Some((_, kp)) = best.get(id) {
            for ji in 0..17 {
                pos[[f, ji, 0]] = kp[3 * ji];
                pos[[f, ji, 1]] = kp[3 * ji + 1];
                conf[[f, ji]] = kp[3 * ji + 2];
            }
        }
    }
    Track::new(
        pos,
        Some(conf),
        opts.rate(),
        opts.units_for(2),
        Skeleton::coco17(),
    )
    .map_err(|e| GeomError::format(path, e.to_string()))
}

/// Reads an AlphaPose results JSON file.
pub fn read_alphapose(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<Track> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| GeomError::io(path, e))?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| GeomError::format(path, format!("invalid JSON: {e}")))?;
    alphapose_from_value(&v, path, opts)
}
