//! The BlazePose person detector (`pose_detection.onnx`): SSD anchors, box
//! and keypoint decoding, weighted non-maximum suppression, and the crop
//! region derived from the detection's keypoints.

use std::path::Path;

use ort::session::Session;

use crate::error::{PoseError, Result};
use crate::imageops::{crop_u8, to_f32, Border, RgbView, Roi};
use crate::runtime::{self, SessionParams};

/// Input side of the detector (pixels).
pub(crate) const DETECTOR_INPUT: usize = 224;
/// Number of SSD anchors of the detector.
pub const NUM_ANCHORS: usize = 2254;
/// Values per anchor in the regressor output: box (4) + 4 keypoints × 2.
pub(crate) const NUM_COORDS: usize = 12;
/// Input tensor name.
pub(crate) const INPUT_NAME: &str = "input_1";
/// Regressor output name (`[1, 2254, 12]`).
pub(crate) const BOXES_NAME: &str = "Identity";
/// Score-logit output name (`[1, 2254, 1]`).
pub(crate) const SCORES_NAME: &str = "Identity_1";

/// SSD anchor centres `(x, y)` in the normalised 224×224 input: strides 8,
/// 16, 32, 32, 32, two anchors per layer and cell, offset 0.5, fixed size 1.
/// Layers with the same stride share a grid; anchors are ordered by layer
/// group, then row, column, anchor.
pub fn ssd_anchors() -> Vec<[f32; 2]> {
    let strides = [8usize, 16, 32, 32, 32];
    let mut anchors = Vec::with_capacity(NUM_ANCHORS);
    let mut layer = 0;
    while layer < strides.len() {
        let stride = strides[layer];
        let mut per_cell = 0;
        while layer < strides.len() && strides[layer] == stride {
            per_cell += 2; // aspect ratio 1 + the interpolated-scale anchor
            layer += 1;
        }
        let n = DETECTOR_INPUT.div_ceil(stride);
        for y in 0..n {
            for x in 0..n {
                let cx = (x as f32 + 0.5) / n as f32;
                let cy = (y as f32 + 0.5) / n as f32;
                for _ in 0..per_cell {
                    anchors.push([cx, cy]);
                }
            }
        }
    }
    anchors
}

/// One detection in the normalised letterboxed square (0..1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detection {
    /// Sigmoid score.
    pub score: f32,
    /// Face box `[xmin, ymin, xmax, ymax]`.
    pub bbox: [f32; 4],
    /// Keypoints: hip centre, full-body scale/rotation point, shoulder centre,
    /// upper-body scale point.
    pub keypoints: [[f32; 2]; 4],
}

fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x).exp())
}

/// Parameters of detection decoding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectorParams {
    /// Minimum sigmoid score of a detection. Default 0.5.
    pub min_score: f32,
    /// IoU above which detections are merged by weighted NMS. Default 0.3.
    pub nms_iou: f32,
    /// Raw score logits are clipped to ±this before the sigmoid. Default 100.
    pub score_clip: f32,
}

impl Default for DetectorParams {
    fn default() -> Self {
        DetectorParams {
            min_score: 0.5,
            nms_iou: 0.3,
            score_clip: 100.0,
        }
    }
}

impl DetectorParams {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        if !(self.min_score.is_finite() && (0.0..=1.0).contains(&self.min_score)) {
            return Err(PoseError::param(
                "min_detection_score",
                format!("must be in [0, 1], got {}", self.min_score),
            ));
        }
        if !(self.nms_iou.is_finite() && (0.0..=1.0).contains(&self.nms_iou)) {
            return Err(PoseError::param(
                "nms_iou",
                format!("must be in [0, 1], got {}", self.nms_iou),
            ));
        }
        if !(self.score_clip.is_finite() && self.score_clip > 0.0) {
            return Err(PoseError::param(
                "score_clip",
                format!("must be > 0, got {}", self.score_clip),
            ));
        }
        Ok(())
    }
}

/// Decodes raw regressors (`NUM_ANCHORS × 12`) and score logits
/// (`NUM_ANCHORS`) into detections above `min_score`.
pub fn decode(
    boxes: &[f32],
    scores: &[f32],
    anchors: &[[f32; 2]],
    params: &DetectorParams,
) -> Vec<Detection> {
    let s = DETECTOR_INPUT as f32;
    let mut out = Vec::new();
    let n = anchors
        .len()
        .min(scores.len())
        .min(boxes.len() / NUM_COORDS);
    for i in 0..n {
        let logit = scores[i].clamp(-params.score_clip, params.score_clip);
        let score = sigmoid(logit);
        if score.is_nan() || score < params.min_score {
            continue;
        }
        let r = &boxes[i * NUM_COORDS..(i + 1) * NUM_COORDS];
        let [ax, ay] = anchors[i];
        let cx = r[0] / s + ax;
        let cy = r[1] / s + ay;
        let w = r[2] / s;
        let h = r[3] / s;
        if !(w > 0.0 && h > 0.0) {
            continue;
        }
        let mut keypoints = [[0.0f32; 2]; 4];
        for (k, kp) in keypoints.iter_mut().enumerate() {
            *kp = [r[4 + 2 * k] / s + ax, r[5 + 2 * k] / s + ay];
        }
        out.push(Detection {
            score,
            bbox: [cx - w / 2.0, cy - h / 2.0, cx + w / 2.0, cy + h / 2.0],
            keypoints,
        });
    }
    out
}

fn iou(a: &[f32; 4], b: &[f32; 4]) -> f32 {
    let ix = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
    let iy = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
    let inter = ix * iy;
    let area = |r: &[f32; 4]| (r[2] - r[0]).max(0.0) * (r[3] - r[1]).max(0.0);
    let union = area(a) + area(b) - inter;
    if union > 0.0 {
        inter / union
    } else {
        0.0
    }
}

/// Weighted non-maximum suppression: repeatedly take the best remaining
/// detection, gather every remaining detection overlapping it by more than
/// `iou_threshold` (itself included), and output the best one's score with
/// the score-weighted mean of their boxes and keypoints. Ordered by score.
pub(crate) fn weighted_nms(mut dets: Vec<Detection>, iou_threshold: f32) -> Vec<Detection> {
    dets.sort_by(|a, b| b.score.total_cmp(&a.score));
    let mut out = Vec::new();
    let mut remaining = dets;
    while let Some(best) = remaining.first().copied() {
        let (cluster, rest): (Vec<Detection>, Vec<Detection>) = remaining
            .into_iter()
            .partition(|d| iou(&d.bbox, &best.bbox) > iou_threshold);
        let mut merged = best;
        let total: f32 = cluster.iter().map(|d| d.score).sum();
        if !cluster.is_empty() && total > 0.0 {
            let mut bbox = [0.0f32; 4];
            let mut kps = [[0.0f32; 2]; 4];
            for d in &cluster {
                for k in 0..4 {
                    bbox[k] += d.bbox[k] * d.score;
                    kps[k][0] += d.keypoints[k][0] * d.score;
                    kps[k][1] += d.keypoints[k][1] * d.score;
                }
            }
            for k in 0..4 {
                bbox[k] /= total;
                kps[k][0] /= total;
                kps[k][1] /= total;
            }
            merged.bbox = bbox;
            merged.keypoints = kps;
        }
        out.push(merged);
        if cluster.is_empty() {
            // Cannot happen (the best overlaps itself) unless its box is degenerate.
            remaining = rest.into_iter().skip(1).collect();
        } else {
            remaining = rest;
        }
    }
    out
}

/// A detection mapped back to image pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageDetection {
    /// Sigmoid score.
    pub score: f64,
    /// Face box `[xmin, ymin, xmax, ymax]` in pixels.
    pub bbox_px: [f64; 4],
    /// The four keypoints in pixels.
    pub keypoints_px: [[f64; 2]; 4],
}

/// The square crop region for the landmark model from two points: centre
/// `p0`, side `2·|p1 − p0|·scale`, rotated so that `p0 → p1` points up
/// (rotation = 90° − atan2(−(y1 − y0), x1 − x0), wrapped to [−π, π)).
pub fn roi_from_points(p0: [f64; 2], p1: [f64; 2], scale: f64) -> Roi {
    let dx = p1[0] - p0[0];
    let dy = p1[1] - p0[1];
    let side = 2.0 * (dx * dx + dy * dy).sqrt() * scale;
    let rotation = normalize_radians(std::f64::consts::FRAC_PI_2 - (-dy).atan2(dx));
    Roi {
        center_x_px: p0[0],
        center_y_px: p0[1],
        width_px: side,
        height_px: side,
        rotation_rad: rotation,
    }
}

/// Wraps an angle to [−π, π).
pub(crate) fn normalize_radians(a: f64) -> f64 {
    use std::f64::consts::PI;
    a - 2.0 * PI * ((a + PI) / (2.0 * PI)).floor()
}

/// The person detector: an ONNX session plus decoding.
pub struct PoseDetector {
    session: Session,
    name: String,
    anchors: Vec<[f32; 2]>,
    params: DetectorParams,
    crop: Vec<u8>,
    input: Vec<f32>,
}

impl PoseDetector {
    /// Opens `pose_detection.onnx` and checks its tensor contract.
    pub fn open(path: &Path, params: DetectorParams, session: &SessionParams) -> Result<Self> {
        params.validate()?;
        let session = runtime::open_session(path, session)?;
        let name = path.display().to_string();
        let ins = runtime::TensorInfo::inputs_of(&session);
        let outs = runtime::TensorInfo::outputs_of(&session);
        runtime::TensorInfo::check(&name, &ins, INPUT_NAME, "f32", &[1, 224, 224, 3])?;
        runtime::TensorInfo::check(
            &name,
            &outs,
            BOXES_NAME,
            "f32",
            &[1, NUM_ANCHORS as i64, 12],
        )?;
        runtime::TensorInfo::check(
            &name,
            &outs,
            SCORES_NAME,
            "f32",
            &[1, NUM_ANCHORS as i64, 1],
        )?;
        Ok(PoseDetector {
            session,
            name,
            anchors: ssd_anchors(),
            params,
            crop: Vec::new(),
            input: Vec::new(),
        })
    }

    /// Runs the model on a prepared `[1, 224, 224, 3]` input in [−1, 1] and
    /// returns the decoded detections after NMS (normalised square coordinates).
    pub fn run_tensor(&mut self, input: &[f32]) -> Result<Vec<Detection>> {
        let n = DETECTOR_INPUT;
        let tensor = runtime::image_tensor(input, n, &self.name, "detector")?;
        let outputs = self
            .session
            .run(ort::inputs![INPUT_NAME => tensor])
            .map_err(|e| PoseError::model(&self.name, e))?;
        let boxes =
            runtime::output_f32(&outputs, &self.name, BOXES_NAME, NUM_ANCHORS * NUM_COORDS)?;
        let scores = runtime::output_f32(&outputs, &self.name, SCORES_NAME, NUM_ANCHORS)?;
        let dets = decode(boxes, scores, &self.anchors, &self.params);
        Ok(weighted_nms(dets, self.params.nms_iou))
    }

    /// Detects people in an image; best first, in image pixels.
    pub fn detect(&mut self, image: RgbView<'_>) -> Result<Vec<ImageDetection>> {
        self.detect_in(image, &Roi::letterbox(image.width, image.height))
    }

    /// Detects people in one square region of an image (a tile, or the
    /// crop around a tracked person), read at the detector's input size;
    /// what lies outside the image reads black. Best first, in image pixels.
    pub fn detect_in(&mut self, image: RgbView<'_>, region: &Roi) -> Result<Vec<ImageDetection>> {
        let n = DETECTOR_INPUT;
        let letterbox = *region;
        crop_u8(image, &letterbox, n, n, Border::Zero, &mut self.crop);
        let mut input = std::mem::take(&mut self.input);
        to_f32(&self.crop, 2.0 / 255.0, -1.0, &mut input);
        let result = self.run_tensor(&input);
        self.input = input;
        let dets = result?;
        let map = |x: f32, y: f32| -> [f64; 2] {
            let (px, py) = letterbox.to_image(x as f64, y as f64);
            [px, py]
        };
        Ok(dets
            .into_iter()
            .map(|d| {
                let a = map(d.bbox[0], d.bbox[1]);
                let b = map(d.bbox[2], d.bbox[3]);
                ImageDetection {
                    score: d.score as f64,
                    bbox_px: [a[0], a[1], b[0], b[1]],
                    keypoints_px: d.keypoints.map(|k| map(k[0], k[1])),
                }
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anchors_count_and_layout() {
        let a = ssd_anchors();
        assert_eq!(a.len(), NUM_ANCHORS);
        // First grid: 28×28 cells, 2 anchors each, first cell centre 0.5/28.
        assert!((a[0][0] - 0.5 / 28.0).abs() < 1e-7);
        assert_eq!(a[0], a[1]);
        assert!((a[2][0] - 1.5 / 28.0).abs() < 1e-7);
        // 1568 anchors of stride 8, then 392 of stride 16, then 294 of stride 32 (6 per cell).
        assert!((a[1568][0] - 0.5 / 14.0).abs() < 1e-7);
        assert!((a[1960][0] - 0.5 / 7.0).abs() < 1e-7);
        assert_eq!(a[1960], a[1965]);
        assert!((a[1966][0] - 1.5 / 7.0).abs() < 1e-7);
    }

    fn det(score: f32, x: f32) -> Detection {
        Detection {
            score,
            bbox: [x, 0.0, x + 0.2, 0.2],
            keypoints: [[x, 0.5]; 4],
        }
    }

    #[test]
    fn weighted_nms_merges_overlaps_and_keeps_separate() {
        let out = weighted_nms(vec![det(0.6, 0.02), det(0.9, 0.0), det(0.7, 0.6)], 0.3);
        assert_eq!(out.len(), 2);
        assert_eq!(out[0].score, 0.9);
        // Weighted mean of x = 0.0 (w 0.9) and 0.02 (w 0.6).
        let want = (0.0 * 0.9 + 0.02 * 0.6) / 1.5;
        assert!((out[0].keypoints[0][0] - want).abs() < 1e-6);
        assert_eq!(out[1].score, 0.7);
    }

    #[test]
    fn decode_applies_anchor_offsets_and_threshold() {
        let anchors = vec![[0.25f32, 0.75], [0.5, 0.5]];
        let mut boxes = vec![0.0f32; 24];
        boxes[0] = 22.4; // +0.1
        boxes[2] = 44.8; // w 0.2
        boxes[3] = 44.8;
        boxes[4] = -22.4; // kp0 x −0.1
        let scores = vec![3.0f32, -3.0];
        let d = decode(&boxes, &scores, &anchors, &DetectorParams::default());
        assert_eq!(d.len(), 1);
        assert!((d[0].bbox[0] - 0.25).abs() < 1e-6);
        assert!((d[0].keypoints[0][0] - 0.15).abs() < 1e-6);
        assert!((d[0].keypoints[0][1] - 0.75).abs() < 1e-6);
    }

    #[test]
    fn roi_points_up_along_the_body() {
        // Hip centre below the scale point (person upright): no rotation.
        let r = roi_from_points([100.0, 200.0], [100.0, 120.0], 1.25);
        assert!(r.rotation_rad.abs() < 1e-12);
        assert!((r.width_px - 200.0).abs() < 1e-9);
        // Person lying with the head to the right: scale point to the right of the hips.
        let r = roi_from_points([100.0, 200.0], [180.0, 200.0], 1.0);
        assert!((r.rotation_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(
            (normalize_radians(3.0 * std::f64::consts::PI) + std::f64::consts::PI).abs() < 1e-12
        );
    }
}
