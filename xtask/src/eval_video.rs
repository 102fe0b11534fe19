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
//!   observed (`mp_video::analyse_video` on those frames only), the second
//!   half predicted (`mp_video::plan_prediction`) and scored: KD of the
//!   predicted poses (the pose model on the predicted frames) against the
//!   poses of the real second half, PSNR and SSIM against its frames.
//!
//! Frames stream: the truth is decoded alongside each output and the pose
//! model runs on its own thread fed through a bounded channel.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::thread::JoinHandle;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Args;
use mp_geom::Track;
use mp_pipeline::Params;
use mp_pose::video::{Frame, FrameSource, VideoReader};
use mp_pose::{extract, open_estimator, ExtractOptions, SessionParams};
use mp_video::interpolate::{interpolate_frames, keep_every, Guide};
use mp_video::plan::render;
use mp_video::predict::plan_prediction;
use mp_video::{analyse_video, InterpMethod, InterpParams, PixelBox, PredictMethod, PredictParams};
use serde_json::{json, Map, Value};

/// COCO-17 elbows and wrists.
const ARM_JOINTS: [usize; 4] = [7, 8, 9, 10];

/// BlazePose-33 elbows and wrists (the same joints as [`ARM_JOINTS`]).
const BLAZE_ARM_JOINTS: [usize; 4] = [13, 14, 15, 16];

/// KD with the truth's crops: on each true frame with a pose, the crop the
/// tracker used there and the elbows and wrists found in it. A rebuilt
/// frame is scored by running the landmark model on the same crop, so the
/// difference comes from the pixels alone, not from where each tracker
/// happens to have placed its crop (on the same pixels, two tracking
/// histories can give arms 100 px apart).
struct CropTruth {
    model: mp_pose::BlazePose,
    rois: Vec<Option<mp_pose::Roi>>,
    arms: Vec<[Option<[f64; 2]>; 4]>,
}

impl CropTruth {
    /// BlazePose with the product's settings, before the first frame.
    fn new() -> anyhow::Result<Option<Self>> {
        Ok(product_blazepose(true)?.map(|model| CropTruth {
            model,
            rois: Vec::new(),
            arms: Vec::new(),
        }))
    }

    /// The next true frame.
    fn push_truth(&mut self, f: &Frame) -> anyhow::Result<()> {
        let (pose, _) = self.model.process(f)?;
        self.rois.push(pose.as_ref().and_then(|p| p.roi));
        self.arms.push(arms_of(pose.as_ref()));
        Ok(())
    }

    /// Sum of distances and pairs of frame `t` rebuilt as `rgb`.
    fn score(&mut self, t: usize, rgb: &[u8], w: usize, h: usize) -> anyhow::Result<(f64, usize)> {
        let Some(Some(roi)) = self.rois.get(t).copied() else {
            return Ok((0.0, 0));
        };
        let view = mp_pose::imageops::RgbView {
            width: w,
            height: h,
            data: rgb,
        };
        let out = self.model.landmarks_mut().run(view, &roi)?;
        let found = BLAZE_ARM_JOINTS.map(|j| {
            out.landmarks
                .get(j)
                .filter(|lm| lm.visibility as f64 > MIN_CONF)
                .map(|lm| mp_pose::blazepose::landmarks::project(&roi, lm).0)
        });
        Ok(arm_distances(&found, &self.arms[t]))
    }
}

/// BlazePose with the product's settings (`Params::default().pose`), its
/// crop carried from frame to frame or not (`tracking`); `None` when the
/// product's pose model is MoveNet.
fn product_blazepose(tracking: bool) -> anyhow::Result<Option<mp_pose::BlazePose>> {
    let params = Params::default();
    let Some(kind) = params.pose.model.landmark_model() else {
        return Ok(None);
    };
    Ok(Some(mp_pose::BlazePose::new(mp_pose::BlazePoseParams {
        model: kind,
        session: SessionParams {
            intra_threads: params.pose.threads,
            ..Default::default()
        },
        recover_s: params.pose.recover_s,
        tracking,
        ..Default::default()
    })?))
}

/// The elbows and wrists of a BlazePose result that are seen (confidence > [`MIN_CONF`]).
fn arms_of(pose: Option<&mp_pose::Pose>) -> [Option<[f64; 2]>; 4] {
    match pose {
        Some(p) => {
            BLAZE_ARM_JOINTS.map(|j| (p.visibility[j] > MIN_CONF).then_some(p.keypoints_px[j]))
        }
        None => [None; 4],
    }
}

/// KD frame by frame: the pose model on each frame alone (the detector on
/// every frame, no crop carried from the frame before, as for still
/// images), on the true frame and on the rebuilt one. Neither sequence's
/// history decides where the model looks.
struct StillTruth {
    model: mp_pose::BlazePose,
    arms: Vec<[Option<[f64; 2]>; 4]>,
    fps: f64,
}

impl StillTruth {
    /// BlazePose without tracking, before the first frame.
    fn new(fps: f64) -> anyhow::Result<Option<Self>> {
        Ok(product_blazepose(false)?.map(|model| StillTruth {
            model,
            arms: Vec::new(),
            fps,
        }))
    }

    /// The next true frame.
    fn push_truth(&mut self, f: &Frame) -> anyhow::Result<()> {
        let (pose, _) = self.model.process(f)?;
        self.arms.push(arms_of(pose.as_ref()));
        Ok(())
    }

    /// Sum of distances and pairs of frame `t` rebuilt as `rgb`.
    fn score(&mut self, t: usize, rgb: &[u8], w: usize, h: usize) -> anyhow::Result<(f64, usize)> {
        let Some(truth) = self.arms.get(t).copied() else {
            return Ok((0.0, 0));
        };
        let frame = Frame::new(t, t as f64 / self.fps, w, h, rgb.to_vec())?;
        let (pose, _) = self.model.process(&frame)?;
        Ok(arm_distances(&arms_of(pose.as_ref()), &truth))
    }
}

/// Sum of distances and number of the joints seen in both `a` and `b`.
fn arm_distances(a: &[Option<[f64; 2]>; 4], b: &[Option<[f64; 2]>; 4]) -> (f64, usize) {
    a.iter()
        .zip(b)
        .filter_map(|(p, q)| Some((p.as_ref()?, q.as_ref()?)))
        .fold((0.0, 0), |(s, n), (p, q)| {
            (s + (p[0] - q[0]).hypot(p[1] - q[1]), n + 1)
        })
}

/// Confidence above which a joint is scored.
const MIN_CONF: f64 = mp_video::motion::MIN_CONFIDENCE;

/// Arguments of `cargo xtask eval interpolation`.
#[derive(Args, Debug)]
pub struct EvalInterpolationArgs {
    /// Videos (default: the shared golf swing and the shared QUVA videos).
    #[arg(long)]
    pub videos: Vec<PathBuf>,
    /// Factors.
    #[arg(long, value_delimiter = ',', default_value = "2,4,8")]
    pub factors: Vec<usize>,
    /// Frames scored per video (the first N).
    #[arg(long, default_value_t = 97)]
    pub max_frames: usize,
    /// Methods.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "program,linear,minterpolate"
    )]
    pub methods: Vec<String>,
    /// Output JSON.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write the pose tracks (COCO-17) of the true frames
    /// (`<video>_truth.npz`) and of each rebuilt sequence
    /// (`<video>_x<factor>_<method>.npz`) to this folder.
    #[arg(long)]
    pub tracks_dir: Option<PathBuf>,
    /// Settings other than the product's, for choosing defaults on a
    /// validation set: `warp=field|bones`, `blend_power=P`,
    /// `body_radius_frac=R`, `sigma_frac=S`, `agree_tau=T`, `max_bulge=B`,
    /// `recover_s=S`, `pixel_check=true|false`, `warp_check=true|false`, `min_confidence=C` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// `InterpParams::default()` with the `--set` overrides.
fn interp_params(set: &[String]) -> anyhow::Result<InterpParams> {
    let mut p = InterpParams::default();
    for kv in set {
        let Some((k, v)) = kv.split_once('=') else {
            bail!("--set {kv}: expected KEY=VALUE");
        };
        match k {
            "warp" => {
                p.warp = match v {
                    "field" => mp_video::Warp::Field,
                    "bones" => mp_video::Warp::Bones,
                    _ => bail!("--set warp={v}: field or bones"),
                }
            }
            "blend_power" => p.blend_power = v.parse()?,
            "body_radius_frac" => p.body_radius_frac = v.parse()?,
            "sigma_frac" => p.sigma_frac = v.parse()?,
            "agree_tau" => p.agree_tau = v.parse()?,
            "max_bulge" => p.max_bulge = v.parse()?,
            "recover_s" => p.recover_s = v.parse()?,
            "pixel_check" => p.pixel_check = v.parse()?,
            "warp_check" => p.warp_check = v.parse()?,
            "min_confidence" => p.min_confidence = v.parse()?,
            _ => bail!("--set {k}: unknown setting"),
        }
    }
    p.validate()?;
    Ok(p)
}

/// KD (px) over elbows and wrists between the truth at the dropped frames
/// and (a) the program's target poses, (b) the kept frames' keypoints
/// interpolated linearly: how far the pose the frames are warped to is from
/// the true pose, before any pixel is moved.
fn target_kd(
    guide: &Guide,
    truth: &Track,
    k: usize,
    dropped: &[usize],
) -> anyhow::Result<(f64, f64)> {
    let (mut s_t, mut n_t, mut s_l, mut n_l) = (0.0, 0usize, 0.0, 0usize);
    let g = &guide.track;
    for &t in dropped {
        let (i, w) = (t / k, (t % k) as f64 / k as f64);
        let tp = guide.target_pose(i, w)?;
        for j in ARM_JOINTS {
            if t >= truth.n_frames() || !truth.is_valid(t, j, MIN_CONF) {
                continue;
            }
            let q = truth.point(t, j);
            if let Some(Some(p)) = tp.get(j) {
                s_t += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                n_t += 1;
            }
            if i + 1 < g.n_frames() && g.is_valid(i, j, MIN_CONF) && g.is_valid(i + 1, j, MIN_CONF)
            {
                let (a, b) = (g.point(i, j), g.point(i + 1, j));
                let p = [a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1])];
                s_l += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                n_l += 1;
            }
        }
    }
    let m = |s: f64, n: usize| if n > 0 { s / n as f64 } else { f64::NAN };
    Ok((m(s_t, n_t), m(s_l, n_l)))
}

/// Arguments of `cargo xtask eval video-predict`.
#[derive(Args, Debug)]
pub struct EvalVideoPredictArgs {
    /// Videos (default: the shared QUVA videos).
    #[arg(long)]
    pub videos: Vec<PathBuf>,
    /// Output JSON.
    #[arg(long)]
    pub out: PathBuf,
}

fn shared_videos(with_golf: bool) -> anyhow::Result<Vec<PathBuf>> {
    let mut v = Vec::new();
    if with_golf {
        if let Some(g) = mp_geom::paths::data_file("golfdb/golf_swing.mp4") {
            v.push(g);
        }
    }
    if let Some(dir) = mp_geom::paths::data_file("quva_repetition/videos") {
        let mut q: Vec<PathBuf> = std::fs::read_dir(&dir)
            .with_context(|| format!("listing {}", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| mp_pipeline::is_video(p))
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
    tx: Option<SyncSender<mp_pose::Result<Frame>>>,
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
        let (tx, rx) = sync_channel::<mp_pose::Result<Frame>>(4);
        let handle = std::thread::spawn(move || -> anyhow::Result<Track> {
            let source = FrameSource {
                width,
                height,
                fps,
                frame_count: None,
                frames: Box::new(rx.into_iter()),
            };
            let ex = extract(source, est.as_mut(), &ExtractOptions::default(), |_, _| {})?;
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

fn mean(v: &[f64]) -> f64 {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if f.is_empty() {
        f64::NAN
    } else {
        f.iter().sum::<f64>() / f.len() as f64
    }
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
    fn add(
        &mut self,
        out: &[u8],
        truth: &[u8],
        w: usize,
        h: usize,
        pbox: Option<PixelBox>,
    ) -> anyhow::Result<()> {
        let full = PixelBox::full(w, h);
        self.psnr.push(mp_video::psnr(out, truth, w, h, &full)?);
        self.ssim.push(mp_video::ssim(out, truth, w, h, &full)?);
        if let Some(b) = pbox {
            self.psnr_box.push(mp_video::psnr(out, truth, w, h, &b)?);
            self.ssim_box.push(mp_video::ssim(out, truth, w, h, &b)?);
        }
        Ok(())
    }
}

/// The true frames' poses, decoded once: the product's pose model over the
/// first `n` frames, and the references of the truth's crops and of the
/// frame-by-frame KD (`None` for a MoveNet product).
struct Truth {
    track: Track,
    info: mp_pose::VideoInfo,
    crops: Option<CropTruth>,
    stills: Option<StillTruth>,
}

fn truth_pose(video: &Path, n: usize) -> anyhow::Result<Truth> {
    let reader = VideoReader::open(video)?;
    let info = reader.info().clone();
    let mut ps = PoseStream::start(info.width, info.height, info.fps)?;
    let mut crops = CropTruth::new()?;
    let mut stills = StillTruth::new(info.fps)?;
    for f in reader.take(n) {
        let f = f?;
        if let Some(c) = crops.as_mut() {
            c.push_truth(&f)?;
        }
        if let Some(c) = stills.as_mut() {
            c.push_truth(&f)?;
        }
        ps.push(&f.rgb)?;
    }
    Ok(Truth {
        track: ps.finish()?,
        info,
        crops,
        stills,
    })
}

fn parse_interp(m: &str) -> anyhow::Result<InterpMethod> {
    Ok(match m {
        "program" => InterpMethod::Program,
        "linear" => InterpMethod::Linear,
        "minterpolate" => InterpMethod::Minterpolate,
        other => bail!("unknown method {other} (program, linear, minterpolate)"),
    })
}

/// `cargo xtask eval interpolation`.
pub fn run_interpolation(a: &EvalInterpolationArgs) -> anyhow::Result<()> {
    let t_all = Instant::now();
    let videos = if a.videos.is_empty() {
        shared_videos(true)?
    } else {
        a.videos.clone()
    };
    let methods: Vec<InterpMethod> = a
        .methods
        .iter()
        .map(|m| parse_interp(m))
        .collect::<anyhow::Result<_>>()?;
    for &k in &a.factors {
        mp_video::interpolate::check_factor(k)?;
    }
    let params = Params::default();
    let iparams = interp_params(&a.set)?;
    let tmp = std::env::temp_dir().join(format!("mp-eval-interp-{}", std::process::id()));
    std::fs::create_dir_all(&tmp)?;
    let mut per_video = Map::new();
    // (factor, method) → pooled values.
    let mut pooled: std::collections::BTreeMap<(usize, String), (Vec<f64>, usize, Scores)> =
        Default::default();
    let mut pooled_target: std::collections::BTreeMap<usize, (Vec<f64>, Vec<f64>)> =
        Default::default();
    let mut kd_by: std::collections::BTreeMap<
        (usize, String),
        std::collections::BTreeMap<String, f64>,
    > = Default::default();
    let mut crop_by = kd_by.clone();
    let mut still_by = kd_by.clone();
    for video in &videos {
        let name = stem(video);
        let Truth {
            track: truth,
            info,
            mut crops,
            mut stills,
        } = truth_pose(video, a.max_frames)?;
        let (w, h) = (info.width, info.height);
        let mut vres = Map::new();
        for &k in &a.factors {
            let kept = tmp.join(format!("{name}_k{k}.mkv"));
            let m = keep_every(video, k, Some(a.max_frames), &kept)?;
            if m < 2 {
                continue;
            }
            let n_out = (m - 1) * k + 1;
            let dropped: Vec<usize> = (0..n_out).filter(|t| !t.is_multiple_of(k)).collect();
            let mut fres = Map::new();
            if methods.contains(&InterpMethod::Program) {
                // The poses the program-guided frames are warped to, and the
                // kept keypoints interpolated linearly, against the truth.
                let guide = Guide::fit(&kept, &params, &iparams);
                let (kd_target, kd_lin) = match guide {
                    Ok(g) => target_kd(&g, &truth, k, &dropped)?,
                    // No person: the program method fails below and is reported.
                    Err(_) => (f64::NAN, f64::NAN),
                };
                eprintln!(
                    "{name} ×{k} target poses: KD arms {kd_target:.2} px (linear keypoints {kd_lin:.2} px)"
                );
                fres.insert(
                    "target_pose".into(),
                    json!({"kd_arms_px": num(kd_target), "kd_arms_linear_keypoints_px": num(kd_lin)}),
                );
                let e = pooled_target.entry(k).or_default();
                e.0.push(kd_target);
                e.1.push(kd_lin);
            }
            for &method in &methods {
                let t0 = Instant::now();
                eprint!("{name} ×{k} {} … ", method.as_str());
                let mut truth_frames = VideoReader::open(video)?;
                let mut ps = PoseStream::start(w, h, info.fps)?;
                let mut scores = Scores::default();
                let (mut crop_sum, mut crop_n) = (0.0, 0usize);
                let (mut still_sum, mut still_n) = (0.0, 0usize);
                let mut t = 0usize;
                let r = interpolate_frames(&kept, k, method, &iparams, &params, |rgb| {
                    let tf = truth_frames.next().ok_or_else(|| {
                        mp_video::VideoError::Edit("the truth ended early".into())
                    })??;
                    ps.push(rgb)
                        .map_err(|e| mp_video::VideoError::Edit(e.to_string()))?;
                    if !t.is_multiple_of(k) {
                        let pbox = PixelBox::around_pose(&truth, t, MIN_CONF, 0.1, w, h);
                        scores
                            .add(rgb, &tf.rgb, w, h, pbox)
                            .map_err(|e| mp_video::VideoError::Edit(e.to_string()))?;
                        if let Some(c) = crops.as_mut() {
                            let (s, n) = c
                                .score(t, rgb, w, h)
                                .map_err(|e| mp_video::VideoError::Edit(e.to_string()))?;
                            crop_sum += s;
                            crop_n += n;
                        }
                        if let Some(c) = stills.as_mut() {
                            let (s, n) = c
                                .score(t, rgb, w, h)
                                .map_err(|e| mp_video::VideoError::Edit(e.to_string()))?;
                            still_sum += s;
                            still_n += n;
                        }
                    }
                    t += 1;
                    Ok(())
                });
                // A method that failed before its first frame leaves the pose
                // thread without frames: its error is the one reported.
                let pose = ps.finish();
                let r = match r {
                    Ok(r) => r,
                    Err(e) => {
                        eprintln!("failed: {e}");
                        fres.insert(method.as_str().into(), json!({"error": e.to_string()}));
                        continue;
                    }
                };
                let pose = pose?;
                if let Some(d) = &a.tracks_dir {
                    std::fs::create_dir_all(d)?;
                    mp_geom::io::write_track(
                        d.join(format!("{name}_x{k}_{}.npz", method.as_str())),
                        &pose,
                    )?;
                    mp_geom::io::write_track(d.join(format!("{name}_truth.npz")), &truth)?;
                }
                let (kd_arms, n_arms) = kd(&pose, &truth, &dropped, Some(&ARM_JOINTS));
                let (kd_all, _) = kd(&pose, &truth, &dropped, None);
                let ratio = |s: f64, n: usize| if n > 0 { s / n as f64 } else { f64::NAN };
                let kd_crop = ratio(crop_sum, crop_n);
                let kd_still = ratio(still_sum, still_n);
                eprintln!(
                    "KD arms {kd_arms:.2} px ({kd_crop:.2} in the truth's crops, {kd_still:.2} frame by frame), PSNR {:.2} dB ({:.2} box), SSIM {:.4} ({:.4} box), {:.1} s",
                    mean(&scores.psnr),
                    mean(&scores.psnr_box),
                    mean(&scores.ssim),
                    mean(&scores.ssim_box),
                    t0.elapsed().as_secs_f64()
                );
                fres.insert(
                    method.as_str().into(),
                    json!({
                        "kd_arms_px": num(kd_arms),
                        "kd_arms_pairs": n_arms,
                        "kd_arms_truth_crops_px": num(kd_crop),
                        "kd_arms_truth_crops_pairs": crop_n,
                        "kd_arms_frame_by_frame_px": num(kd_still),
                        "kd_arms_frame_by_frame_pairs": still_n,
                        "kd_all_px": num(kd_all),
                        "psnr_db": num(mean(&scores.psnr)),
                        "ssim": num(mean(&scores.ssim)),
                        "psnr_box_db": num(mean(&scores.psnr_box)),
                        "ssim_box": num(mean(&scores.ssim_box)),
                        "frames_out": r.frames_out,
                        "frames_scored": dropped.len(),
                        "seconds": num(t0.elapsed().as_secs_f64()),
                    }),
                );
                kd_by
                    .entry((k, method.as_str().to_string()))
                    .or_default()
                    .insert(name.clone(), kd_arms);
                crop_by
                    .entry((k, method.as_str().to_string()))
                    .or_default()
                    .insert(name.clone(), kd_crop);
                still_by
                    .entry((k, method.as_str().to_string()))
                    .or_default()
                    .insert(name.clone(), kd_still);
                let e = pooled.entry((k, method.as_str().to_string())).or_default();
                if kd_arms.is_finite() {
                    e.0.push(kd_arms);
                }
                e.1 += 1;
                e.2.psnr.push(mean(&scores.psnr));
                e.2.ssim.push(mean(&scores.ssim));
                e.2.psnr_box.push(mean(&scores.psnr_box));
                e.2.ssim_box.push(mean(&scores.ssim_box));
            }
            let _ = std::fs::remove_file(&kept);
            vres.insert(format!("x{k}"), Value::Object(fres));
        }
        per_video.insert(name, Value::Object(vres));
    }
    let _ = std::fs::remove_dir_all(&tmp);
    let mut summary = Map::new();
    println!("factor  method         KD arms (px)  PSNR (dB)  SSIM    PSNR box  SSIM box  videos");
    for ((k, m), (kds, n, s)) in &pooled {
        println!(
            "{:>4}×  {:<13}  {:>12.2}  {:>9.2}  {:.4}  {:>8.2}  {:.4}    {}",
            k,
            m,
            mean(kds),
            mean(&s.psnr),
            mean(&s.ssim),
            mean(&s.psnr_box),
            mean(&s.ssim_box),
            n
        );
        summary.insert(
            format!("x{k}/{m}"),
            json!({
                "kd_arms_px": num(mean(kds)),
                "psnr_db": num(mean(&s.psnr)),
                "ssim": num(mean(&s.ssim)),
                "psnr_box_db": num(mean(&s.psnr_box)),
                "ssim_box": num(mean(&s.ssim_box)),
                "videos": n,
            }),
        );
    }
    for &k in &a.factors {
        let keys: Vec<(usize, String)> = methods
            .iter()
            .map(|m| (k, m.as_str().to_string()))
            .collect();
        let (means, n) = common_kd(&kd_by, &keys);
        let (crop_means, crop_n) = common_kd(&crop_by, &keys);
        let (still_means, still_n) = common_kd(&still_by, &keys);
        let text = |means: &[f64]| -> String {
            keys.iter()
                .zip(means)
                .map(|((_, m), x)| format!("{m} {x:.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        println!(
            "{k:>4}×  KD arms over the {n} videos where every method has one: {}",
            text(&means)
        );
        println!(
            "{k:>4}×  KD arms in the truth's crops, over the {crop_n} videos where every method has one: {}",
            text(&crop_means)
        );
        println!(
            "{k:>4}×  KD arms frame by frame, over the {still_n} videos where every method has one: {}",
            text(&still_means)
        );
        for ((((_, m), x), c), f) in keys.iter().zip(&means).zip(&crop_means).zip(&still_means) {
            if let Some(Value::Object(o)) = summary.get_mut(&format!("x{k}/{m}")) {
                o.insert("kd_arms_common_px".into(), num(*x));
                o.insert("kd_common_videos".into(), json!(n));
                o.insert("kd_arms_truth_crops_common_px".into(), num(*c));
                o.insert("kd_truth_crops_common_videos".into(), json!(crop_n));
                o.insert("kd_arms_frame_by_frame_common_px".into(), num(*f));
                o.insert("kd_frame_by_frame_common_videos".into(), json!(still_n));
            }
        }
    }
    for (k, (t, l)) in &pooled_target {
        println!(
            "{k:>4}×  program target poses: KD arms {:.2} px; kept keypoints interpolated linearly {:.2} px",
            mean(t),
            mean(l)
        );
        summary.insert(
            format!("x{k}/target_pose"),
            json!({"kd_arms_px": num(mean(t)), "kd_arms_linear_keypoints_px": num(mean(l))}),
        );
    }
    let report = json!({
        "task": "interpolation",
        "settings": a.set,
        "protocol": "keep every k-th of the first max_frames frames, rebuild the dropped ones, score them against the originals; means over videos of per-video means",
        "max_frames": a.max_frames,
        "factors": a.factors,
        "videos": videos.iter().map(|v| stem(v)).collect::<Vec<_>>(),
        "summary": summary,
        "per_video": per_video,
        "seconds": num(t_all.elapsed().as_secs_f64()),
    });
    mp_geom::io::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    eprintln!("written to {}", a.out.display());
    Ok(())
}

/// `cargo xtask eval video-predict`.
pub fn run_video_predict(a: &EvalVideoPredictArgs) -> anyhow::Result<()> {
    let t_all = Instant::now();
    let videos = if a.videos.is_empty() {
        shared_videos(false)?
    } else {
        a.videos.clone()
    };
    let params = Params::default();
    let pparams = PredictParams::default();
    let methods = [
        PredictMethod::Loop,
        PredictMethod::Nearest,
        PredictMethod::Constant,
    ];
    let mut per_video = Map::new();
    let mut pooled: std::collections::BTreeMap<&'static str, (Vec<f64>, Scores)> =
        Default::default();
    let mut kd_by: std::collections::BTreeMap<
        &'static str,
        std::collections::BTreeMap<String, f64>,
    > = Default::default();
    for video in &videos {
        let name = stem(video);
        let n = VideoReader::open(video)?.count();
        let half = n / 2;
        if half < 2 {
            continue;
        }
        let horizon = n - half;
        eprint!("{name}: observing {half} frames … ");
        let m = analyse_video(video, &params, Some(half))?;
        // The poses of the real second half, from the pose model run on those frames alone.
        let info = mp_pose::probe(video)?;
        let (w, h) = (info.width, info.height);
        let mut ps = PoseStream::start(w, h, info.fps)?;
        for f in VideoReader::open(video)?.skip(half) {
            ps.push(&f?.rgb)?;
        }
        let truth = ps.finish()?;
        eprintln!("{} loop(s) counted", m.counts.intervals.len());
        let mut vres = Map::new();
        for method in methods {
            let t0 = Instant::now();
            let plan = match plan_prediction(&m, horizon, method, &pparams) {
                Ok(p) => p,
                Err(e) => {
                    vres.insert(method.as_str().into(), json!({"error": e.to_string()}));
                    continue;
                }
            };
            let mut truth_frames = VideoReader::open(video)?.skip(half);
            let mut ps = PoseStream::start(w, h, info.fps)?;
            let mut scores = Scores::default();
            let mut t = 0usize;
            render(video, &plan.plan, &pparams.render, |rgb| {
                let tf = truth_frames
                    .next()
                    .ok_or_else(|| mp_video::VideoError::Edit("the truth ended early".into()))??;
                ps.push(rgb)
                    .map_err(|e| mp_video::VideoError::Edit(e.to_string()))?;
                let pbox = PixelBox::around_pose(&truth, t, MIN_CONF, 0.1, w, h);
                scores
                    .add(rgb, &tf.rgb, w, h, pbox)
                    .map_err(|e| mp_video::VideoError::Edit(e.to_string()))?;
                t += 1;
                Ok(())
            })?;
            let pose = ps.finish()?;
            let frames: Vec<usize> = (0..horizon).collect();
            let (kd_all, pairs) = kd(&pose, &truth, &frames, None);
            eprintln!(
                "  {:<9} KD {kd_all:.2} px, PSNR {:.2} dB, SSIM {:.4}, cycle {:?} ({}, {})",
                method.as_str(),
                mean(&scores.psnr),
                mean(&scores.ssim),
                plan.cycle,
                plan.used.as_str(),
                plan.source
            );
            vres.insert(
                method.as_str().into(),
                json!({
                    "kd_px": num(kd_all),
                    "kd_pairs": pairs,
                    "psnr_db": num(mean(&scores.psnr)),
                    "ssim": num(mean(&scores.ssim)),
                    "psnr_box_db": num(mean(&scores.psnr_box)),
                    "ssim_box": num(mean(&scores.ssim_box)),
                    "used": plan.used.as_str(),
                    "source": plan.source,
                    "cycle": [plan.cycle.0, plan.cycle.1],
                    "seconds": num(t0.elapsed().as_secs_f64()),
                }),
            );
            kd_by
                .entry(method.as_str())
                .or_default()
                .insert(name.clone(), kd_all);
            let e = pooled.entry(method.as_str()).or_default();
            if kd_all.is_finite() {
                e.0.push(kd_all);
            }
            e.1.psnr.push(mean(&scores.psnr));
            e.1.ssim.push(mean(&scores.ssim));
            e.1.psnr_box.push(mean(&scores.psnr_box));
            e.1.ssim_box.push(mean(&scores.ssim_box));
        }
        per_video.insert(
            name,
            json!({"frames": n, "observed": half, "predicted": horizon, "methods": vres}),
        );
    }
    let mut summary = Map::new();
    println!("method     KD (px)  PSNR (dB)  SSIM    PSNR box  SSIM box  videos");
    for (m, (kds, s)) in &pooled {
        println!(
            "{:<9}  {:>7.2}  {:>9.2}  {:.4}  {:>8.2}  {:.4}    {}",
            m,
            mean(kds),
            mean(&s.psnr),
            mean(&s.ssim),
            mean(&s.psnr_box),
            mean(&s.ssim_box),
            s.psnr.len()
        );
        summary.insert(
            (*m).into(),
            json!({
                "kd_px": num(mean(kds)),
                "psnr_db": num(mean(&s.psnr)),
                "ssim": num(mean(&s.ssim)),
                "psnr_box_db": num(mean(&s.psnr_box)),
                "ssim_box": num(mean(&s.ssim_box)),
                "videos": s.psnr.len(),
            }),
        );
    }
    let keys: Vec<&'static str> = methods.iter().map(|m| m.as_str()).collect();
    let (means, n_common) = common_kd(&kd_by, &keys);
    let text: Vec<String> = keys
        .iter()
        .zip(&means)
        .map(|(m, x)| format!("{m} {x:.2}"))
        .collect();
    println!(
        "KD over the {n_common} videos where every method has one: {}",
        text.join(", ")
    );
    for (m, x) in keys.iter().zip(&means) {
        if let Some(Value::Object(o)) = summary.get_mut(*m) {
            o.insert("kd_common_px".into(), num(*x));
            o.insert("kd_common_videos".into(), json!(n_common));
        }
    }
    let report = json!({
        "task": "video-predict",
        "protocol": "observe the first half of each video, predict the second half; KD of the pose model on predicted vs real frames (all COCO-17 joints seen in both), PSNR/SSIM per frame; means over videos of per-video means",
        "videos": videos.iter().map(|v| stem(v)).collect::<Vec<_>>(),
        "summary": summary,
        "per_video": per_video,
        "seconds": num(t_all.elapsed().as_secs_f64()),
    });
    mp_geom::io::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    eprintln!("written to {}", a.out.display());
    Ok(())
}
