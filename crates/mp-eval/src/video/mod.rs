//! `cargo xtask eval interpolation` and `cargo xtask eval video-predict`:
//! motion programs on video pixels, through the same `mp_video` functions
//! and defaults as `mp interpolate` and `mp predict VIDEO --seconds`.
//!
//! * interpolation: every k-th frame of a video is kept (written losslessly,
//!   FFV1), the kept video is interpolated back to the full frame rate by
//!   each method (`mp_video::interpolate_frames`), and the rebuilt frames are
//!   scored against the dropped originals: KD of elbows and wrists (the pose
//!   model run on the rebuilt and on the true frames, px) three ways — the
//!   product's pose model with its tracking over each sequence, the landmark
//!   model in the crop the tracker used on the true frame (`CropTruth`), and
//!   the pose model on each frame alone, detector included (`StillTruth`) —
//!   and PSNR and SSIM on the whole frame and on the person's box (the true
//!   keypoints' box grown by 10 %).
//! * video-predict (§4.4 on pixels): the first half of each video is
//!   observed (`mp_video::VideoMotion::analyse` on those frames only), the second
//!   half predicted (`mp_video::VideoMotion::plan_prediction`) and scored: KD of the
//!   predicted poses (the pose model on the predicted frames) against the
//!   poses of the real second half, PSNR and SSIM against its frames.
//!
//! Frames stream: the truth is decoded alongside each output and the pose
//! model runs on its own thread fed through a bounded channel.
//!
//! Each command has its own submodule (`interpolation`, `predict`); this
//! module holds what they share: the shared videos, the streaming pose
//! model, KD, and the PSNR/SSIM scores.

mod interpolation;
pub mod metrics;
mod predict;

pub use interpolation::{run_interpolation, EvalInterpolationArgs};
pub use predict::{run_video_predict, EvalVideoPredictArgs};

use crate::stats::mean;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::thread::JoinHandle;

use anyhow::{bail, Context};
use metrics::PixelBox;
use mp_geom::Track;
use mp_pipeline::Params;
use mp_pose::{extract_track, open_estimator, ExtractOptions, SessionParams};
use mp_pose::{Frame, FrameSource};
use serde_json::{json, Value};

/// Confidence above which a joint is scored.
const MIN_CONF: f64 = mp_video::VideoMotion::MIN_CONFIDENCE;

fn shared_videos(with_golf: bool) -> anyhow::Result<Vec<PathBuf>> {
    let mut v = Vec::new();
    if with_golf {
        if let Some(g) = mp_geom::data_file("golfdb/golf_swing.mp4") {
            v.push(g);
        }
    }
    if let Some(dir) = mp_geom::data_file("quva_repetition/videos") {
        let mut q: Vec<PathBuf> = std::fs::read_dir(&dir)
            .with_context(|| format!("listing {}", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| mp_pipeline::Input::is_video(p))
            .collect();
        q.sort();
        v.extend(q);
    }
    if v.is_empty() {
        bail!("no videos given and the shared data sets are absent");
    }
    Ok(v)
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The pose model on its own thread, fed frame by frame.
struct PoseStream {
    tx: Option<SyncSender<std::result::Result<Frame, mp_pose::PoseError>>>,
    handle: JoinHandle<anyhow::Result<Track>>,
    next: usize,
    fps: f64,
    size: (usize, usize),
}

impl PoseStream {
    /// The product's pose model and settings (`Params::default().pose`).
    fn start(width: usize, height: usize, fps: f64) -> anyhow::Result<Self> {
        let params = Params::default();
        let mut est = open_estimator(
            params.pose.model,
            SessionParams {
                intra_threads: params.pose.threads,
                ..Default::default()
            },
        )?;
        let (tx, rx) = sync_channel::<std::result::Result<Frame, mp_pose::PoseError>>(4);
        let handle = std::thread::spawn(move || -> anyhow::Result<Track> {
            let source = FrameSource {
                width,
                height,
                fps,
                frame_count: None,
                frames: Box::new(rx.into_iter()),
            };
            let ex = extract_track(source, est.as_mut(), &ExtractOptions::default(), |_, _| {})?;
            let t = ex.track;
            Ok(
                if t.skeleton().name != "coco17" && t.skeleton().maps_to_coco17() {
                    t.to_coco17()?
                } else {
                    t
                },
            )
        });
        Ok(PoseStream {
            tx: Some(tx),
            handle,
            next: 0,
            fps,
            size: (width, height),
        })
    }

    fn push(&mut self, rgb: &[u8]) -> anyhow::Result<()> {
        let f = Frame::new(
            self.next,
            self.next as f64 / self.fps,
            self.size.0,
            self.size.1,
            rgb.to_vec(),
        )?;
        self.next += 1;
        if let Some(tx) = &self.tx {
            if tx.send(Ok(f)).is_err() {
                bail!("the pose thread stopped");
            }
        }
        Ok(())
    }

    fn finish(mut self) -> anyhow::Result<Track> {
        self.tx = None;
        match self.handle.join() {
            Ok(r) => r,
            Err(_) => bail!("the pose thread panicked"),
        }
    }
}

/// KD (px) over the (frame, joint) pairs of `frames` × `joints` seen in both.
fn kd(a: &Track, b: &Track, frames: &[usize], joints: Option<&[usize]>) -> (f64, usize) {
    let (mut s, mut n) = (0.0, 0usize);
    let all: Vec<usize> = (0..a.n_joints().min(b.n_joints())).collect();
    let joints = joints.unwrap_or(&all);
    for &t in frames {
        if t >= a.n_frames() || t >= b.n_frames() {
            continue;
        }
        for &j in joints {
            if a.is_valid(t, j, MIN_CONF) && b.is_valid(t, j, MIN_CONF) {
                let (p, q) = (a.point(t, j), b.point(t, j));
                s += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                n += 1;
            }
        }
    }
    (if n > 0 { s / n as f64 } else { f64::NAN }, n)
}

#[derive(Default, Clone)]
struct Scores {
    psnr: Vec<f64>,
    ssim: Vec<f64>,
    psnr_box: Vec<f64>,
    ssim_box: Vec<f64>,
}

/// Per method, the mean of its per-video KD over the videos where every
/// method has one (so the means compare the same videos).
fn common_kd<K: Ord + Clone>(
    per_video: &std::collections::BTreeMap<K, std::collections::BTreeMap<String, f64>>,
    methods: &[K],
) -> (Vec<f64>, usize) {
    let Some(first) = methods.first().and_then(|m| per_video.get(m)) else {
        return (vec![f64::NAN; methods.len()], 0);
    };
    let videos: Vec<&String> = first
        .keys()
        .filter(|v| {
            methods.iter().all(|m| {
                per_video
                    .get(m)
                    .and_then(|x| x.get(*v))
                    .is_some_and(|k| k.is_finite())
            })
        })
        .collect();
    let means = methods
        .iter()
        .map(|m| {
            let vals: Vec<f64> = videos
                .iter()
                .filter_map(|v| per_video.get(m).and_then(|x| x.get(*v)).copied())
                .collect();
            mean(&vals)
        })
        .collect();
    (means, videos.len())
}

fn num(x: f64) -> Value {
    if x.is_finite() {
        json!((x * 10000.0).round() / 10000.0)
    } else {
        Value::Null
    }
}

impl Scores {
    /// The pooled means as table columns: PSNR, SSIM, PSNR and SSIM on the box.
    fn columns(&self) -> String {
        format!(
            "{:>9.2}  {:.4}  {:>8.2}  {:.4}",
            mean(&self.psnr),
            mean(&self.ssim),
            mean(&self.psnr_box),
            mean(&self.ssim_box)
        )
    }

    /// The pooled means as JSON, beside a KD under `kd_key` and the video count.
    fn summary(&self, kd_key: &str, kd: f64, videos: usize) -> Value {
        let mut o = serde_json::Map::new();
        o.insert(kd_key.into(), num(kd));
        o.insert("psnr_db".into(), num(mean(&self.psnr)));
        o.insert("ssim".into(), num(mean(&self.ssim)));
        o.insert("psnr_box_db".into(), num(mean(&self.psnr_box)));
        o.insert("ssim_box".into(), num(mean(&self.ssim_box)));
        o.insert("videos".into(), json!(videos));
        Value::Object(o)
    }

    fn add(
        &mut self,
        out: &[u8],
        truth: &[u8],
        w: usize,
        h: usize,
        pbox: Option<PixelBox>,
    ) -> anyhow::Result<()> {
        let full = PixelBox::full(w, h);
        self.psnr.push(metrics::psnr(out, truth, w, h, &full)?);
        self.ssim.push(metrics::ssim(out, truth, w, h, &full)?);
        if let Some(b) = pbox {
            self.psnr_box.push(metrics::psnr(out, truth, w, h, &b)?);
            self.ssim_box.push(metrics::ssim(out, truth, w, h, &b)?);
        }
        Ok(())
    }
}
