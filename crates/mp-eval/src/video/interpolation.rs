//! `cargo xtask eval interpolation`: every k-th frame kept, the rest
//! rebuilt by each method and scored against the dropped originals (KD of
//! elbows and wrists three ways, PSNR and SSIM); see the parent module.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::metrics::PixelBox;
use anyhow::bail;
use clap::Args;
use mp_geom::Track;
use mp_pipeline::Params;
use mp_pose::SessionParams;
use mp_pose::{Frame, VideoReader};
use mp_video::{interpolate_frames, keep_every, Guide};
use mp_video::{InterpMethod, InterpParams};
use serde_json::{json, Map, Value};

use super::{common_kd, kd, mean, num, shared_videos, stem, PoseStream, Scores, MIN_CONF};

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
        let view = mp_pose::RgbView {
            width: w,
            height: h,
            data: rgb,
        };
        let out = self.model.landmarks_mut().run(view, &roi)?;
        let found = BLAZE_ARM_JOINTS.map(|j| {
            out.landmarks
                .get(j)
                .filter(|lm| lm.visibility as f64 > MIN_CONF)
                .map(|lm| mp_pose::project(&roi, lm).0)
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
    /// `body_radius_frac=R`, `sigma_frac=S`, `agree_tau=T`, `max_bulge=B` (the earlier
    /// rule, `inbetween=bulge:B`), `inbetween=RULE` (`mp_concrete::InBetween::parse`),
    /// `recover_s=S`, `pixel_check=true|false`, `warp_check=true|false`, `min_confidence=C` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Also score the target poses of these in-between rules
    /// (`mp_concrete::InBetween::parse`) on the same keypoints and program.
    #[arg(long, value_delimiter = ',')]
    pub target_rules: Vec<String>,
    /// Only the target poses (no frames rebuilt): with `program` among the methods.
    #[arg(long)]
    pub targets_only: bool,
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
            "max_bulge" => {
                p.inbetween = mp_concrete::InBetween::Bulge {
                    max_bulge: v.parse()?,
                }
            }
            "inbetween" => p.inbetween = mp_concrete::InBetween::parse(v)?,
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
/// the true pose, before any pixel is moved. Both on the same entries: the
/// joints the pose model sees in both kept frames around the dropped one
/// (a joint seen in one of them only is held there by every rule).
fn target_kd(
    guide: &Guide,
    truth: &Track,
    k: usize,
    dropped: &[usize],
) -> anyhow::Result<(f64, f64)> {
    let (mut s_t, mut s_l, mut n) = (0.0, 0.0, 0usize);
    let g = &guide.track;
    for &t in dropped {
        let (i, w) = (t / k, (t % k) as f64 / k as f64);
        let tp = guide.target_pose(i, w)?;
        for j in ARM_JOINTS {
            if t >= truth.n_frames() || !truth.is_valid(t, j, MIN_CONF) {
                continue;
            }
            if !(i + 1 < g.n_frames()
                && g.is_valid(i, j, MIN_CONF)
                && g.is_valid(i + 1, j, MIN_CONF))
            {
                continue;
            }
            let Some(Some(p)) = tp.get(j) else { continue };
            let q = truth.point(t, j);
            let (a, b) = (g.point(i, j), g.point(i + 1, j));
            let l = [a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1])];
            s_t += (p[0] - q[0]).hypot(p[1] - q[1]);
            s_l += (l[0] - q[0]).hypot(l[1] - q[1]);
            n += 1;
        }
    }
    let m = |s: f64| if n > 0 { s / n as f64 } else { f64::NAN };
    Ok((m(s_t), m(s_l)))
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
        mp_video::InterpParams::check_factor(k)?;
    }
    let params = Params::default();
    let iparams = interp_params(&a.set)?;
    let target_rules: Vec<mp_concrete::InBetween> = a
        .target_rules
        .iter()
        .map(|r| mp_concrete::InBetween::parse(r))
        .collect::<Result<_, _>>()?;
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
                let mut others = Map::new();
                let (kd_target, kd_lin) = match guide {
                    Ok(mut g) => {
                        for r in &target_rules {
                            g.inbetween = *r;
                            let (t, _) = target_kd(&g, &truth, k, &dropped)?;
                            eprintln!(
                                "{name} ×{k} target poses with {}: KD arms {t:.2} px",
                                r.label()
                            );
                            others.insert(r.label(), num(t));
                        }
                        g.inbetween = iparams.inbetween;
                        target_kd(&g, &truth, k, &dropped)?
                    }
                    // No person: the program method fails below and is reported.
                    Err(_) => (f64::NAN, f64::NAN),
                };
                eprintln!(
                    "{name} ×{k} target poses: KD arms {kd_target:.2} px (linear keypoints {kd_lin:.2} px)"
                );
                fres.insert(
                    "target_pose".into(),
                    json!({"kd_arms_px": num(kd_target), "kd_arms_linear_keypoints_px": num(kd_lin),
                           "kd_arms_px_other_rules": others}),
                );
                let e = pooled_target.entry(k).or_default();
                e.0.push(kd_target);
                e.1.push(kd_lin);
            }
            for &method in methods.iter().filter(|_| !a.targets_only) {
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
                    mp_geom::write_track(
                        d.join(format!("{name}_x{k}_{}.npz", method.as_str())),
                        &pose,
                    )?;
                    mp_geom::write_track(d.join(format!("{name}_truth.npz")), &truth)?;
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
            "{:>4}×  {:<13}  {:>12.2}  {}    {}",
            k,
            m,
            mean(kds),
            s.columns(),
            n
        );
        summary.insert(format!("x{k}/{m}"), s.summary("kd_arms_px", mean(kds), *n));
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
    mp_geom::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    eprintln!("written to {}", a.out.display());
    Ok(())
}
