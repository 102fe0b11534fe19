//! The BlazePose GHUM landmark model (`pose_landmark_{lite,full,heavy}.onnx`):
//! 39 landmarks (33 body + 2 auxiliary + 4 unused) from a rotated 256×256
//! crop, heatmap refinement, and the mapping back to the image.

use std::path::Path;

use ort::session::{HasSelectedOutputs, OutputSelector, RunOptions, Session};

use super::shared::SharedLandmarks;
use crate::error::{PoseError, Result};
use crate::imageops::{crop_u8, extend_f32, Border, RgbView, Roi};
use crate::runtime::{self, SessionParams};

/// Input side of the landmark model (pixels).
pub(crate) const LANDMARK_INPUT: usize = 256;
/// Landmarks in the model's output (33 body, 2 auxiliary, 4 more).
pub(crate) const NUM_LANDMARKS_ALL: usize = 39;
/// Body landmarks (BlazePose-33).
pub(crate) const NUM_BODY: usize = 33;
/// Heatmap side.
pub(crate) const HEATMAP_SIZE: usize = 64;
/// Input tensor name.
pub(crate) const INPUT_NAME: &str = "input_1";
/// Landmarks output (`[1, 195]`).
pub(crate) const LANDMARKS_NAME: &str = "Identity";
/// Pose presence output (`[1, 1]`, a probability).
pub(crate) const PRESENCE_NAME: &str = "Identity_1";
/// Heatmap output (`[1, 64, 64, 39]`).
pub(crate) const HEATMAP_NAME: &str = "Identity_3";
/// World landmarks output (`[1, 117]`).
pub(crate) const WORLD_NAME: &str = "Identity_4";

/// Which landmark model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum LandmarkModelKind {
    /// `pose_landmark_lite.onnx`
    Lite,
    /// `pose_landmark_full.onnx` (MediaPipe's `model_complexity=1`, the default)
    Full,
    /// `pose_landmark_heavy.onnx` (not shipped by `cargo xtask models`)
    Heavy,
}

impl LandmarkModelKind {
    /// The model file.
    pub fn file(self) -> runtime::ModelFile {
        match self {
            LandmarkModelKind::Lite => runtime::ModelFile::LandmarkLite,
            LandmarkModelKind::Full => runtime::ModelFile::LandmarkFull,
            LandmarkModelKind::Heavy => runtime::ModelFile::LandmarkHeavy,
        }
    }
    /// Short name.
    pub fn as_str(self) -> &'static str {
        match self {
            LandmarkModelKind::Lite => "lite",
            LandmarkModelKind::Full => "full",
            LandmarkModelKind::Heavy => "heavy",
        }
    }
}

/// Parameters of the heatmap refinement of landmark positions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineParams {
    /// Whether to refine at all. Default true (MediaPipe does).
    pub enabled: bool,
    /// Odd window side in heatmap cells. Default 7.
    pub kernel_size: usize,
    /// Refine only where the window's maximum sigmoid reaches this. Default 0.5.
    pub min_confidence: f32,
}

impl Default for RefineParams {
    fn default() -> Self {
        RefineParams {
            enabled: true,
            kernel_size: 7,
            min_confidence: 0.5,
        }
    }
}

impl RefineParams {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        if self.kernel_size == 0 || self.kernel_size & 1 == 0 || self.kernel_size > HEATMAP_SIZE {
            return Err(PoseError::param(
                "heatmap_kernel_size",
                format!(
                    "must be odd and in 1..={HEATMAP_SIZE}, got {}",
                    self.kernel_size
                ),
            ));
        }
        if !(self.min_confidence.is_finite() && (0.0..=1.0).contains(&self.min_confidence)) {
            return Err(PoseError::param(
                "heatmap_min_confidence",
                format!("must be in [0, 1], got {}", self.min_confidence),
            ));
        }
        Ok(())
    }
}

/// One landmark in the crop's normalised coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CropLandmark {
    /// x / 256.
    pub x: f32,
    /// y / 256.
    pub y: f32,
    /// z / 256 (same scale as x).
    pub z: f32,
    /// Sigmoid of the visibility logit.
    pub visibility: f32,
    /// Sigmoid of the presence logit.
    pub presence: f32,
}

/// Decoded output of one landmark-model run.
#[derive(Debug, Clone, PartialEq)]
pub struct LandmarkOutput {
    /// Pose presence probability.
    pub pose_presence: f32,
    /// All 39 landmarks, crop-normalised (refined when enabled).
    pub landmarks: Vec<CropLandmark>,
    /// 39 world points (metres, hip-centred, in the crop's rotation).
    pub world: Vec<[f32; 3]>,
}

fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x).exp())
}

/// Decodes the raw `[195]` landmark tensor (39 × x, y, z, visibility logit,
/// presence logit; pixels of the 256 input).
pub(crate) fn decode_landmarks(raw: &[f32]) -> Vec<CropLandmark> {
    let s = LANDMARK_INPUT as f32;
    raw.chunks_exact(5)
        .take(NUM_LANDMARKS_ALL)
        .map(|c| CropLandmark {
            x: c[0] / s,
            y: c[1] / s,
            z: c[2] / s,
            visibility: sigmoid(c[3]),
            presence: sigmoid(c[4]),
        })
        .collect()
}

/// Refines landmark positions with the heatmaps (`64 × 64 × 39`, HWC, logits):
/// in a `kernel × kernel` window around each landmark's cell, the
/// sigmoid-weighted mean of the cell indices replaces the position when the
/// window's maximum reaches `min_confidence`. Landmarks outside the heatmap
/// are left alone. (Cell indices are used as they are, as MediaPipe does.)
pub(crate) fn refine_with_heatmap(
    landmarks: &mut [CropLandmark],
    heatmap: &[f32],
    params: &RefineParams,
) {
    let (hw, hh, ch) = (HEATMAP_SIZE as i64, HEATMAP_SIZE as i64, NUM_LANDMARKS_ALL);
    if heatmap.len() != (hw * hh) as usize * ch {
        return;
    }
    let offset = (params.kernel_size as i64 - 1) / 2;
    for (k, lm) in landmarks.iter_mut().enumerate().take(ch) {
        // Truncation toward zero, as in a C++ float-to-int conversion.
        let center_col = (lm.x * hw as f32) as i64;
        let center_row = (lm.y * hh as f32) as i64;
        if center_col < 0 || center_col >= hw || center_row < 0 || center_row >= hh {
            continue;
        }
        let (c0, c1) = (
            (center_col - offset).max(0),
            (center_col + offset + 1).min(hw),
        );
        let (r0, r1) = (
            (center_row - offset).max(0),
            (center_row + offset + 1).min(hh),
        );
        let mut sum = 0.0f32;
        let mut wc = 0.0f32;
        let mut wr = 0.0f32;
        let mut max_conf = 0.0f32;
        for row in r0..r1 {
            for col in c0..c1 {
                let idx = (row * hw + col) as usize * ch + k;
                let conf = sigmoid(heatmap[idx]);
                sum += conf;
                max_conf = max_conf.max(conf);
                wc += col as f32 * conf;
                wr += row as f32 * conf;
            }
        }
        if max_conf >= params.min_confidence && sum > 0.0 {
            lm.x = wc / hw as f32 / sum;
            lm.y = wr / hh as f32 / sum;
        }
    }
}

/// Where a [`LandmarkModel`]'s runs happen.
enum Backend {
    /// Its own ONNX Runtime session.
    Own {
        session: Session,
        /// Asks only for the outputs this crate reads (ONNX Runtime still
        /// runs a mask head that is in the graph: the estimators therefore
        /// open the model without it, [`crate::runtime::ModelFile::without_mask`]).
        run_options: RunOptions<HasSelectedOutputs>,
    },
    /// The model of a [`super::SharedLandmarks`], on its own thread.
    Shared(SharedLandmarks),
}

/// The landmark model: an ONNX session plus pre- and post-processing.
pub struct LandmarkModel {
    backend: Backend,
    name: String,
    kind: LandmarkModelKind,
    refine: RefineParams,
    /// The graph takes several crops in one run (its batch dimension is
    /// open, as in the models `cargo xtask models` cuts).
    batch_open: bool,
    crop: Vec<u8>,
    input: Vec<f32>,
}

impl LandmarkModel {
    /// Opens a landmark model and checks its tensor contract.
    pub fn open(
        path: &Path,
        kind: LandmarkModelKind,
        refine: RefineParams,
        session: &SessionParams,
    ) -> Result<Self> {
        refine.validate()?;
        let session = runtime::open_session(path, session)?;
        let name = path.display().to_string();
        let ins = runtime::TensorInfo::inputs_of(&session);
        let outs = runtime::TensorInfo::outputs_of(&session);
        let input = runtime::TensorInfo::check(&name, &ins, INPUT_NAME, "f32", &[1, 256, 256, 3])?;
        let batch_open = input.shape.first().is_some_and(|&b| b < 0);
        runtime::TensorInfo::check(&name, &outs, LANDMARKS_NAME, "f32", &[1, 195])?;
        runtime::TensorInfo::check(&name, &outs, PRESENCE_NAME, "f32", &[1, 1])?;
        runtime::TensorInfo::check(&name, &outs, HEATMAP_NAME, "f32", &[1, 64, 64, 39])?;
        runtime::TensorInfo::check(&name, &outs, WORLD_NAME, "f32", &[1, 117])?;
        let run_options = RunOptions::new()
            .map_err(|e| PoseError::model(&name, e))?
            .with_outputs(
                OutputSelector::no_default()
                    .with(LANDMARKS_NAME)
                    .with(PRESENCE_NAME)
                    .with(HEATMAP_NAME)
                    .with(WORLD_NAME),
            );
        Ok(Self::with_backend(
            Backend::Own {
                session,
                run_options,
            },
            name,
            kind,
            refine,
            batch_open,
        ))
    }

    /// Which model this is.
    pub fn kind(&self) -> LandmarkModelKind {
        self.kind
    }

    /// Its heatmap refinement.
    pub(crate) fn refine_params(&self) -> RefineParams {
        self.refine
    }

    /// Whether one run takes several crops ([`LandmarkModel::run_many`]
    /// makes one call for all of them).
    pub fn batch_open(&self) -> bool {
        self.batch_open
    }

    /// Runs the model on a prepared `[1, 256, 256, 3]` input in [0, 1].
    pub fn run_tensor(&mut self, input: &[f32]) -> Result<LandmarkOutput> {
        let out = self.run_batch(input, 1)?;
        self.single(out)
    }

    /// The one result of a run on one crop.
    fn single(&self, mut out: Vec<LandmarkOutput>) -> Result<LandmarkOutput> {
        out.pop().ok_or_else(|| PoseError::Contract {
            model: self.name.clone(),
            reason: "a run on one crop gave no result".into(),
        })
    }

    /// A model whose runs go to `shared` (see [`SharedLandmarks`]).
    pub(crate) fn client(
        shared: SharedLandmarks,
        name: String,
        kind: LandmarkModelKind,
        refine: RefineParams,
        batch_open: bool,
    ) -> Self {
        Self::with_backend(Backend::Shared(shared), name, kind, refine, batch_open)
    }

    fn with_backend(
        backend: Backend,
        name: String,
        kind: LandmarkModelKind,
        refine: RefineParams,
        batch_open: bool,
    ) -> Self {
        LandmarkModel {
            backend,
            name,
            kind,
            refine,
            batch_open,
            crop: Vec::new(),
            input: Vec::new(),
        }
    }

    /// The file the model was read from.
    pub(crate) fn name(&self) -> &str {
        &self.name
    }

    /// Runs the model once on `count` prepared crops laid end to end
    /// (`[count, 256, 256, 3]`); the results in the same order. A model
    /// shared with other threads sends the crops to the thread that runs it.
    pub(crate) fn run_batch(&mut self, input: &[f32], count: usize) -> Result<Vec<LandmarkOutput>> {
        let (session, run_options) = match &mut self.backend {
            Backend::Own {
                session,
                run_options,
            } => (session, &*run_options),
            Backend::Shared(shared) => return shared.run(input, count),
        };
        let n = LANDMARK_INPUT;
        let tensor = runtime::image_batch_tensor(input, count, n, &self.name, "landmark")?;
        let outputs = session
            .run_with_options(ort::inputs![INPUT_NAME => tensor], run_options)
            .map_err(|e| PoseError::model(&self.name, e))?;
        let heat_len = HEATMAP_SIZE * HEATMAP_SIZE * NUM_LANDMARKS_ALL;
        let raw = runtime::output_f32(&outputs, &self.name, LANDMARKS_NAME, 195 * count)?;
        let presence = runtime::output_f32(&outputs, &self.name, PRESENCE_NAME, count)?;
        let world = runtime::output_f32(&outputs, &self.name, WORLD_NAME, 117 * count)?;
        let heatmap = runtime::output_f32(&outputs, &self.name, HEATMAP_NAME, heat_len * count)?;
        let mut results = Vec::with_capacity(count);
        for i in 0..count {
            let mut landmarks = decode_landmarks(&raw[i * 195..(i + 1) * 195]);
            if self.refine.enabled {
                let heat = &heatmap[i * heat_len..(i + 1) * heat_len];
                refine_with_heatmap(&mut landmarks, heat, &self.refine);
            }
            results.push(LandmarkOutput {
                pose_presence: presence[i],
                landmarks,
                world: world[i * 117..(i + 1) * 117]
                    .chunks_exact(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect(),
            });
        }
        Ok(results)
    }

    /// Crops `roi` from the image (border replicate) and runs the model.
    pub fn run(&mut self, image: RgbView<'_>, roi: &Roi) -> Result<LandmarkOutput> {
        let out = self.run_crops(image, std::slice::from_ref(roi))?;
        self.single(out)
    }

    /// The crops of `rois` (border replicate, in [0, 1]) laid end to end,
    /// through one run of the model.
    fn run_crops(&mut self, image: RgbView<'_>, rois: &[Roi]) -> Result<Vec<LandmarkOutput>> {
        let n = LANDMARK_INPUT;
        let mut input = std::mem::take(&mut self.input);
        input.clear();
        for roi in rois {
            crop_u8(image, roi, n, n, Border::Replicate, &mut self.crop);
            extend_f32(&self.crop, 1.0 / 255.0, 0.0, &mut input);
        }
        let result = self.run_batch(&input, rois.len());
        self.input = input;
        result
    }

    /// [`LandmarkModel::run`] on several regions of one image: one run of
    /// the model for all of them where its batch is open
    /// ([`LandmarkModel::batch_open`]), else one run each. The same values
    /// either way; the results in the order of `rois`.
    pub fn run_many(&mut self, image: RgbView<'_>, rois: &[Roi]) -> Result<Vec<LandmarkOutput>> {
        if !self.batch_open || rois.len() < 2 {
            return rois.iter().map(|roi| self.run(image, roi)).collect();
        }
        self.run_crops(image, rois)
    }
}

/// Image position `(x, y)` and depth (pixels) of a crop landmark.
pub fn project(roi: &Roi, lm: &CropLandmark) -> ([f64; 2], f64) {
    let (x, y) = roi.to_image(lm.x as f64, lm.y as f64);
    ([x, y], lm.z as f64 * roi.width_px)
}

/// World point rotated by the crop's rotation (the model predicts in the crop's frame).
pub(crate) fn rotate_world(roi: &Roi, w: &[f32; 3]) -> [f64; 3] {
    let (s, c) = roi.rotation_rad.sin_cos();
    let (x, y) = (w[0] as f64, w[1] as f64);
    [c * x - s * y, s * x + c * y, w[2] as f64]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_scales_and_applies_sigmoid() {
        let mut raw = vec![0.0f32; 195];
        raw[0] = 128.0;
        raw[1] = 64.0;
        raw[2] = -25.6;
        raw[3] = 0.0;
        raw[4] = 100.0;
        let lms = decode_landmarks(&raw);
        assert_eq!(lms.len(), 39);
        assert_eq!(lms[0].x, 0.5);
        assert_eq!(lms[0].y, 0.25);
        assert!((lms[0].z + 0.1).abs() < 1e-7);
        assert_eq!(lms[0].visibility, 0.5);
        assert!(lms[0].presence > 0.999);
    }

    #[test]
    fn refinement_moves_to_the_heatmap_peak() {
        let mut hm = vec![-20.0f32; 64 * 64 * 39];
        // Landmark 2 has a confident peak at column 10, row 20.
        hm[(20 * 64 + 10) * 39 + 2] = 20.0;
        let mut lms = vec![CropLandmark::default(); 39];
        lms[2].x = 12.0 / 64.0;
        lms[2].y = 21.5 / 64.0;
        // Landmark 3 has no confident cell: stays.
        lms[3].x = 0.3;
        lms[3].y = 0.3;
        refine_with_heatmap(&mut lms, &hm, &RefineParams::default());
        assert!((lms[2].x - 10.0 / 64.0).abs() < 1e-4, "{}", lms[2].x);
        assert!((lms[2].y - 20.0 / 64.0).abs() < 1e-4);
        assert_eq!((lms[3].x, lms[3].y), (0.3, 0.3));
    }

    #[test]
    fn refine_params_are_validated() {
        assert!(RefineParams {
            kernel_size: 4,
            ..Default::default()
        }
        .validate()
        .is_err());
        assert!(RefineParams {
            min_confidence: 2.0,
            ..Default::default()
        }
        .validate()
        .is_err());
        assert!(RefineParams::default().validate().is_ok());
    }

    #[test]
    fn projection_rotates_about_the_centre() {
        let roi = Roi {
            center_x_px: 100.0,
            center_y_px: 50.0,
            width_px: 200.0,
            height_px: 200.0,
            rotation_rad: std::f64::consts::FRAC_PI_2,
        };
        let lm = CropLandmark {
            x: 0.5,
            y: 0.0,
            z: 0.1,
            ..Default::default()
        };
        let (p, z) = project(&roi, &lm);
        // Crop "up" (−y) points to image +x after a quarter turn.
        assert!(
            (p[0] - 200.0).abs() < 1e-9 && (p[1] - 50.0).abs() < 1e-9,
            "{p:?}"
        );
        assert!((z - 20.0).abs() < 1e-6);
    }
}
