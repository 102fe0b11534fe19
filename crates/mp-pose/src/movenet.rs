//! MoveNet SinglePose Lightning (int8): COCO-17 keypoints from the whole
//! frame, letterboxed to 192×192, uint8 input, output `(y, x, score)`
//! normalised to the square input.

use std::path::{Path, PathBuf};

use mp_geom::Skeleton;
use ort::session::Session;

use crate::error::{PoseError, Result};
use crate::imageops::{crop_u8, Border, RgbView, Roi};
use crate::pose::{Pose, PoseEstimator};
use crate::runtime::{self, ModelFile, SessionParams};
use crate::video::Frame;

/// Input side (pixels).
pub(crate) const MOVENET_INPUT: usize = 192;
/// Input tensor name.
pub(crate) const INPUT_NAME: &str = "serving_default_input:0";
/// Output tensor name (`[1, 1, 17, 3]`).
pub(crate) const OUTPUT_NAME: &str = "StatefulPartitionedCall:0";

/// Parameters of the MoveNet estimator.
#[derive(Debug, Clone, PartialEq)]
pub struct MoveNetParams {
    /// A frame has a person when the mean keypoint score reaches this.
    /// Default 0.25 (TensorFlow.js pose-detection's `minPoseScore`).
    pub min_pose_score: f64,
    /// ONNX Runtime session settings.
    pub session: SessionParams,
    /// Folder of the ONNX file; `None` = the usual search.
    pub model_dir: Option<PathBuf>,
}

impl Default for MoveNetParams {
    fn default() -> Self {
        MoveNetParams {
            min_pose_score: 0.25,
            session: SessionParams::default(),
            model_dir: None,
        }
    }
}

impl MoveNetParams {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        if !(self.min_pose_score.is_finite() && (0.0..=1.0).contains(&self.min_pose_score)) {
            return Err(PoseError::param(
                "min_pose_score",
                format!("must be in [0, 1], got {}", self.min_pose_score),
            ));
        }
        Ok(self.session.validate()?)
    }
}

/// MoveNet SinglePose Lightning.
pub struct MoveNet {
    session: Session,
    name: String,
    params: MoveNetParams,
    crop: Vec<u8>,
}

impl MoveNet {
    /// Opens the model and checks its tensor contract.
    pub fn new(params: MoveNetParams) -> Result<Self> {
        params.validate()?;
        let file = ModelFile::MoveNetLightning;
        let path = match &params.model_dir {
            Some(d) => {
                let p = d.join(file.file_name());
                if !p.is_file() {
                    return Err(PoseError::ModelMissing {
                        file: file.file_name().into(),
                        searched: d.display().to_string(),
                    });
                }
                p
            }
            None => runtime::model_path(file)?,
        };
        Self::open(&path, params)
    }

    /// Opens a given model file.
    pub fn open(path: &Path, params: MoveNetParams) -> Result<Self> {
        params.validate()?;
        let session = runtime::open_session(path, &params.session)?;
        let name = path.display().to_string();
        let ins = runtime::TensorInfo::inputs_of(&session);
        let outs = runtime::TensorInfo::outputs_of(&session);
        runtime::TensorInfo::check(&name, &ins, INPUT_NAME, "u8", &[1, 192, 192, 3])?;
        runtime::TensorInfo::check(&name, &outs, OUTPUT_NAME, "f32", &[1, 1, 17, 3])?;
        Ok(MoveNet {
            session,
            name,
            params,
            crop: Vec::new(),
        })
    }

    /// Runs the model on a prepared `[1, 192, 192, 3]` uint8 input; returns
    /// 17 × (y, x, score).
    pub fn run_tensor(&mut self, input: &[u8]) -> Result<Vec<[f32; 3]>> {
        let n = MOVENET_INPUT;
        let tensor = runtime::image_tensor(input, n, &self.name, "MoveNet")?;
        let outputs = self
            .session
            .run(ort::inputs![INPUT_NAME => tensor])
            .map_err(|e| PoseError::model(&self.name, e))?;
        let out = runtime::output_f32(&outputs, &self.name, OUTPUT_NAME, 51)?;
        Ok(out.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    /// Keypoints of the person in an image (image pixels), with scores.
    pub fn run(&mut self, image: RgbView<'_>) -> Result<Vec<([f64; 2], f64)>> {
        let n = MOVENET_INPUT;
        let letterbox = Roi::letterbox(image.width, image.height);
        let mut crop = std::mem::take(&mut self.crop);
        crop_u8(image, &letterbox, n, n, Border::Zero, &mut crop);
        let result = self.run_tensor(&crop);
        self.crop = crop;
        Ok(result?
            .into_iter()
            .map(|[y, x, s]| {
                let (px, py) = letterbox.to_image(x as f64, y as f64);
                ([px, py], s as f64)
            })
            .collect())
    }
}

impl PoseEstimator for MoveNet {
    fn name(&self) -> &str {
        "movenet-lightning"
    }
    fn skeleton(&self) -> Skeleton {
        Skeleton::coco17()
    }
    fn has_world(&self) -> bool {
        false
    }
    fn estimate(&mut self, frame: &Frame) -> Result<Option<Pose>> {
        frame.validate()?;
        let kps = self.run(frame.view())?;
        if kps.is_empty() {
            return Ok(None);
        }
        let score = kps.iter().map(|k| k.1).sum::<f64>() / kps.len() as f64;
        if score.is_nan() || score < self.params.min_pose_score {
            return Ok(None);
        }
        // Object scale: diagonal of the box around the confident keypoints.
        let conf: Vec<[f64; 2]> = kps.iter().filter(|k| k.1 >= 0.3).map(|k| k.0).collect();
        let object_scale_px = if conf.len() >= 2 {
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in &conf {
                for d in 0..2 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
            }
            ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt()
        } else {
            frame.width.max(frame.height) as f64
        };
        let visibility: Vec<f64> = kps.iter().map(|k| k.1.clamp(0.0, 1.0)).collect();
        Ok(Some(Pose {
            keypoints_px: kps.iter().map(|k| k.0).collect(),
            depth_px: None,
            presence: visibility.clone(),
            visibility,
            world_m: None,
            score,
            object_scale_px,
            roi: None,
            detector_ran: false,
        }))
    }
    fn reset(&mut self) {}
}
