//! `cargo xtask eval count --long --videos DIR --labels DIR --golf FILE --out FILE.json`:
//! a long recording of several activities — every labelled video and a
//! non-repetitive clip (a golf swing), each scaled to 640×360 at 30 fps,
//! played in order `--repeats` times (25: about an hour) — counted as
//! `mp run` counts after keypoints (`mp_pipeline::count` with
//! `Params::default()` on the keypoints and the frame thumbnails).
//!
//! The keypoint step (`mp_pipeline::keypoints`, as `mp run` makes it) runs
//! once per clip and is cached under `--cache`; the clips' keypoints are then
//! joined in order, as a tracker that follows the one performer through the
//! cuts would give them. The frame signal is what `mp run` reads for the
//! main person of a whole video: grey thumbnails of their own mean box over
//! the whole recording (with the margin `mp run` adds), the box being the
//! mean of the clips' boxes weighted by the frames where the person is found.
//!
//! Truth: each labelled clip is one interval, from the start of its first
//! cycle (the first cycle's end minus the second cycle's length, or the clip
//! start) to the end of its last cycle, holding as many repetitions as it
//! has labels.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{bail, Context};
use mp_geom::CancelToken;
use mp_geom::Track;
#[cfg(test)]
use mp_geom::{Skeleton, Units};
use mp_pipeline::{Input, Keep, Params, PoseParams, Silent};
use mp_pose::VideoReader;
use mp_pose::{grey_thumbnail_region, signal_side, thumbnail_track};
use serde_json::{json, Value};

use crate::intervals::one_to_one_pairs;

/// Frame size and rate every clip is scaled to.
pub const WIDTH: usize = 640;
pub const HEIGHT: usize = 360;
pub const FPS: f64 = 30.0;

/// A person's mean box `[x0, y0, x1, y1]` and the frames where they are found.
type PersonBox = ([f64; 4], usize);

/// One clip of the long recording.
struct ClipKp {
    name: String,
    video: PathBuf,
    track: Track,
    /// Main person's mean box and the frames where they are found.
    person_box: Option<PersonBox>,
    /// Labelled interval in the clip's frames and its count.
    truth: Option<(usize, usize, usize)>,
}

/// The clip scaled to 640×360 (aspect kept, padded) at 30 fps, made once.
fn scaled(video: &Path, cache: &Path) -> anyhow::Result<PathBuf> {
    let out = cache.join(format!("{}.mp4", crate::synth_sources::stem(video)));
    if out.is_file() {
        return Ok(out);
    }
    std::fs::create_dir_all(cache)?;
    let tmp = cache.join(format!("{}.tmp.mp4", crate::synth_sources::stem(video)));
    let vf = format!(
        "scale={WIDTH}:{HEIGHT}:force_original_aspect_ratio=decrease,pad={WIDTH}:{HEIGHT}:(ow-iw)/2:(oh-ih)/2,fps={FPS}"
    );
    let st = Command::new("ffmpeg")
        .args(["-y", "-loglevel", "error", "-i"])
        .arg(video)
        .args(["-vf", &vf, "-an", "-c:v", "libx264", "-crf", "18"])
        .arg(&tmp)
        .status()
        .context("running ffmpeg")?;
    if !st.success() {
        bail!("ffmpeg failed on {}", video.display());
    }
    std::fs::rename(&tmp, &out)?;
    Ok(out)
}

/// Keypoints of the scaled clip as `mp run` makes them (cached), with the
/// main person's mean box.
fn clip_keypoints(
    video: &Path,
    cache: &Path,
    params: &Params,
) -> anyhow::Result<(Track, Option<PersonBox>)> {
    let stem = crate::synth_sources::stem(video);
    let (tp, bp) = (
        cache.join(format!("{stem}.keypoints.npz")),
        cache.join(format!("{stem}.box.json")),
    );
    if tp.is_file() && bp.is_file() {
        let track = mp_geom::read_track(&tp)?;
        let b: Value = serde_json::from_slice(&std::fs::read(&bp)?)?;
        let person_box = serde_json::from_value(b["box"].clone())?;
        return Ok((track, person_box));
    }
    let (kp, _) = mp_pipeline::keypoints(
        Input::open(video, None)?,
        params,
        Keep::default(),
        &Silent,
        &CancelToken::new(),
    )?;
    let person_box = match (&kp.people, kp.person) {
        (Some(p), Some(id)) => p
            .get(id)
            .and_then(|q| q.mean_box().map(|b| (b, q.frames_found()))),
        _ => None,
    };
    mp_geom::write_track(&tp, &kp.track)?;
    crate::write_file(&bp, serde_json::to_vec(&json!({ "box": person_box }))?)?;
    Ok((kp.track, person_box))
}

/// The labelled interval of a clip (frames at `fps` of labels made at
/// `label_fps`): start of the first cycle to the end of the last, and count.
pub fn truth_interval(ends: &[i64], label_fps: f64, fps: f64) -> Option<(usize, usize, usize)> {
    let to = |f: f64| (f * fps / label_fps).round().max(0.0) as usize;
    let first = *ends.first()? as f64;
    let last = *ends.last()? as f64;
    let start = match ends.get(1) {
        Some(&second) => (first - (second as f64 - first)).max(0.0),
        None => 0.0,
    };
    Some((to(start), to(last + 1.0), ends.len()))
}

/// The mean of boxes weighted by frames.
pub fn weighted_box(boxes: &[([f64; 4], usize)]) -> Option<[f64; 4]> {
    let w: usize = boxes.iter().map(|b| b.1).sum();
    if w == 0 {
        return None;
    }
    let mut m = [0.0; 4];
    for (b, n) in boxes {
        for k in 0..4 {
            m[k] += b[k] * *n as f64 / w as f64;
        }
    }
    Some(m)
}

/// Grey thumbnails of `region` (the whole frame when `None`) of every frame.
fn thumbnails(video: &Path, region: Option<[f64; 4]>, size: usize) -> anyhow::Result<Track> {
    let reader = VideoReader::open(video)?;
    let fps = reader.info().fps;
    let r = region.unwrap_or([0.0, 0.0, WIDTH as f64, HEIGHT as f64]);
    let mut th = Vec::new();
    for f in reader {
        th.push(grey_thumbnail_region(&f?, size, r)?);
    }
    Ok(thumbnail_track(th, size, fps)?)
}

/// Tracks joined in time (same skeleton, units and rate).
pub fn join(parts: &[&Track]) -> anyhow::Result<Track> {
    Ok(Track::concat(parts)?)
}

/// Arguments of the long-recording evaluation.
pub struct LongArgs<'a> {
    pub videos: &'a Path,
    pub labels: &'a Path,
    pub golf: Option<&'a Path>,
    pub cache: &'a Path,
    pub repeats: usize,
    pub out: &'a Path,
    pub params: Params,
    pub overrides: &'a [String],
}

fn load_clips(a: &LongArgs) -> anyhow::Result<Vec<ClipKp>> {
    let mut items = crate::count::labelled(a.videos, a.labels)?;
    if items.is_empty() {
        bail!("no labelled video in {}", a.videos.display());
    }
    let mut clips = Vec::new();
    let golf = a.golf.map(|g| (g.to_path_buf(), None));
    for (video, label) in items.drain(..).map(|(v, l)| (v, Some(l))).chain(golf) {
        if !video.is_file() {
            bail!("{} not found", video.display());
        }
        let name = crate::synth_sources::stem(&video);
        eprint!("{name} … ");
        let sc = scaled(&video, a.cache)?;
        let (track, person_box) = clip_keypoints(&sc, a.cache, &a.params)?;
        let truth = match label {
            Some(l) => {
                let ends: Vec<i64> = mp_geom::read_npy(&l)?.to_i64()?.iter().copied().collect();
                let fps0 = VideoReader::open(&video)?.info().fps;
                truth_interval(&ends, fps0, FPS)
            }
            None => None,
        };
        eprintln!("{} frames", track.n_frames());
        clips.push(ClipKp {
            name,
            video: sc,
            track,
            person_box,
            truth,
        });
    }
    Ok(clips)
}

pub fn run(a: &LongArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let clips = load_clips(a)?;
    let boxes: Vec<([f64; 4], usize)> = clips.iter().filter_map(|c| c.person_box).collect();
    let region = weighted_box(&boxes).and_then(|b| PoseParams::own_box_region(b, WIDTH, HEIGHT));
    // The side `mp run` reads a recording of this length at.
    let total: usize = clips.iter().map(|c| c.track.n_frames()).sum::<usize>() * a.repeats;
    let size = signal_side(a.params.pose.thumbnail_size, total);
    let mut thumbs = Vec::new();
    for c in &clips {
        let th = thumbnails(&c.video, region, size)?;
        if th.n_frames() != c.track.n_frames() {
            bail!(
                "{}: {} thumbnails for {} keypoint frames",
                c.name,
                th.n_frames(),
                c.track.n_frames()
            );
        }
        thumbs.push(th);
    }
    // The long recording and its truth.
    let mut kp_parts = Vec::new();
    let mut th_parts = Vec::new();
    let mut truth: Vec<(usize, usize, usize, String)> = Vec::new();
    let mut offset = 0;
    for _ in 0..a.repeats {
        for (c, th) in clips.iter().zip(&thumbs) {
            if let Some((s, e, n)) = c.truth {
                truth.push((offset + s, offset + e, n, c.name.clone()));
            }
            kp_parts.push(&c.track);
            th_parts.push(th);
            offset += c.track.n_frames();
        }
    }
    let track = join(&kp_parts)?;
    let frames = join(&th_parts)?;
    drop(thumbs);
    let prep_s = t0.elapsed().as_secs_f64();
    eprintln!(
        "{} frames ({:.1} min), {} labelled intervals; counting …",
        track.n_frames(),
        track.n_frames() as f64 / FPS / 60.0,
        truth.len()
    );
    let mut variants = serde_json::Map::new();
    let signals: [(&str, bool, bool); 3] = [
        ("product", true, true),
        ("keypoints_only", true, false),
        ("frames_only", false, true),
    ];
    for (name, use_kp, use_fr) in signals {
        let t1 = Instant::now();
        let c = mp_abstract::count_signals(
            use_kp.then_some(&track),
            use_fr.then_some(&frames),
            &a.params.count,
        )?;
        let secs = t1.elapsed().as_secs_f64();
        let v = score(&c, &truth, secs)?;
        eprintln!("{name}: {}", summary_line(&v));
        variants.insert(name.into(), v);
    }
    let labelled: usize = truth.iter().map(|t| t.2).sum();
    let report = json!({
        "kind": "repetition_count_long_recording",
        "definition": "every labelled video and the golf swing, each scaled to 640×360 (aspect kept, padded) at 30 fps, played in order `repeats` times; keypoints: mp_pipeline::keypoints with Params::default() once per clip, joined in order; frame signal: grey thumbnails of the main person's mean box over the whole recording (frame-weighted mean of the clips' boxes, widened as PoseParams::own_box_region widens it; the whole frame where that region lies mostly outside the picture), as mp run reads them for the main person. `product`: mp_pipeline::count (keypoints and frames, as mp run after keypoints); `keypoints_only`/`frames_only`: one signal. Truth: one interval per labelled clip, from its first cycle's start (first end minus the second cycle's length, or the clip start) to its last cycle's end. Intervals matched one-to-one by IoM > 0.5 (greedy, as the CMU interval evaluation); count error over matched intervals.",
        "repeats": a.repeats,
        "frames": track.n_frames(),
        "minutes": track.n_frames() as f64 / FPS / 60.0,
        "labelled_intervals": truth.len(),
        "labelled_repetitions": labelled,
        "thumbnail_region": region,
        "thumbnail_side": size,
        "count_param_overrides": a.overrides,
        "clips": clips.iter().map(|c| json!({"name": c.name, "frames": c.track.n_frames(),
            "found": mp_abstract::found_fraction(&c.track),
            "truth": c.truth.map(|t| json!({"start_frame": t.0, "end_frame": t.1, "count": t.2}))})).collect::<Vec<_>>(),
        "prepare_s": prep_s,
        "runtime_s": t0.elapsed().as_secs_f64(),
        "results": variants,
    });
    write_long_report(a.out, &report)
}

/// Writes the report and prints it without the per-interval detail.
pub fn write_long_report(out: &Path, report: &Value) -> anyhow::Result<()> {
    if let Some(dir) = out.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    crate::write_file(out, serde_json::to_string_pretty(report)?.as_bytes())?;
    let mut summary = report.clone();
    strip_detail(&mut summary);
    println!("{}", serde_json::to_string_pretty(&summary)?);
    eprintln!("written to {}", out.display());
    Ok(())
}

fn strip_detail(v: &mut Value) {
    match v {
        Value::Object(m) => {
            m.remove("intervals");
            m.remove("clips");
            m.remove("cases_detail");
            m.values_mut().for_each(strip_detail);
        }
        Value::Array(a) => a.iter_mut().for_each(strip_detail),
        _ => {}
    }
}

fn summary_line(v: &Value) -> String {
    format!(
        "total {} · {} intervals · P {:.2} R {:.2} · matched MAE {:.3} OBO {:.2} · {:.3} ms/frame · {}",
        v["total"], v["detected"], v["precision_one_to_one"].as_f64().unwrap_or(0.0),
        v["recall_one_to_one"].as_f64().unwrap_or(0.0),
        v["matched_count_mae"].as_f64().unwrap_or(f64::NAN),
        v["matched_count_obo"].as_f64().unwrap_or(f64::NAN),
        v["count_ms_per_frame"].as_f64().unwrap_or(0.0), v["signal"]
    )
}

/// Detected against labelled intervals: one-to-one matching by IoM > 0.5,
/// count error of the matched pairs.
pub fn interval_figures(det: &[(usize, usize, usize)], gt: &[(usize, usize, usize)]) -> Value {
    let d: Vec<(usize, usize)> = det.iter().map(|x| (x.0, x.1)).collect();
    let g: Vec<(usize, usize)> = gt.iter().map(|x| (x.0, x.1)).collect();
    let pairs = one_to_one_pairs(&d, &g);
    let k = pairs.len().max(1) as f64;
    let errs: Vec<(f64, bool)> = pairs
        .iter()
        .map(|&(a, b)| {
            let (c, t) = (det[a].2 as f64, gt[b].2 as f64);
            ((c - t).abs() / t.max(1.0), (c - t).abs() <= 1.0)
        })
        .collect();
    json!({
        "detected": det.len(), "labelled": gt.len(), "matched": pairs.len(),
        "precision_one_to_one": crate::loops::ratio(pairs.len(), det.len()),
        "recall_one_to_one": crate::loops::ratio(pairs.len(), gt.len()),
        "matched_count_mae": errs.iter().map(|e| e.0).sum::<f64>() / k,
        "matched_count_obo": errs.iter().filter(|e| e.1).count() as f64 / k,
    })
}

fn score(
    c: &mp_abstract::Counts,
    truth: &[(usize, usize, usize, String)],
    secs: f64,
) -> anyhow::Result<Value> {
    let det: Vec<(usize, usize, usize)> = c
        .intervals
        .iter()
        .map(|i| (i.start_frame, i.end_frame, i.count))
        .collect();
    let gt: Vec<(usize, usize, usize)> = truth.iter().map(|t| (t.0, t.1, t.2)).collect();
    let mut v = interval_figures(&det, &gt);
    let labelled: usize = gt.iter().map(|t| t.2).sum();
    if let Value::Object(m) = &mut v {
        m.insert("total".into(), json!(c.total));
        m.insert("labelled_total".into(), json!(labelled));
        m.insert(
            "total_rel_error".into(),
            json!((c.total as f64 - labelled as f64) / labelled.max(1) as f64),
        );
        m.insert("signal".into(), json!(c.signal.as_str()));
        m.insert("method".into(), json!(c.method.as_str()));
        m.insert("periodicity".into(), json!(c.periodicity));
        m.insert("count_seconds".into(), json!(secs));
        m.insert(
            "count_ms_per_frame".into(),
            json!(1000.0 * secs / c.frames.max(1) as f64),
        );
        m.insert(
            "intervals".into(),
            json!(c
                .intervals
                .iter()
                .map(|i| json!([i.start_frame, i.end_frame, i.count, i.period_frames]))
                .collect::<Vec<_>>()),
        );
    }
    Ok(v)
}

/// A unitless one-channel track (tests).
#[cfg(test)]
fn ramp(n: usize) -> Track {
    let pos = ndarray::Array3::from_shape_fn((n, 1, 1), |(t, _, _)| t as f64);
    Track::new(pos, None, FPS, Units::Unitless, Skeleton::generic(1)).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truth_starts_one_cycle_before_the_first_end() {
        // Ends at 10, 20, 30 at 15 fps, read at 30 fps: start 0, end 62.
        assert_eq!(truth_interval(&[10, 20, 30], 15.0, 30.0), Some((0, 62, 3)));
        // A first cycle longer than the frames before it starts at the clip start.
        assert_eq!(truth_interval(&[5, 20], 30.0, 30.0), Some((0, 21, 2)));
        assert_eq!(truth_interval(&[40, 50], 30.0, 30.0), Some((30, 51, 2)));
        assert_eq!(truth_interval(&[], 30.0, 30.0), None);
    }

    #[test]
    fn box_is_weighted_by_frames() {
        let b =
            weighted_box(&[([0.0, 0.0, 10.0, 10.0], 3), ([10.0, 10.0, 20.0, 20.0], 1)]).unwrap();
        let want = [2.5, 2.5, 12.5, 12.5];
        for k in 0..4 {
            assert!((b[k] - want[k]).abs() < 1e-9, "{b:?}");
        }
        assert_eq!(weighted_box(&[]), None);
    }

    #[test]
    fn joined_tracks_follow_each_other() {
        let t = join(&[&ramp(3), &ramp(2)]).unwrap();
        let p = t.positions();
        let v: Vec<f64> = (0..5).map(|i| p[[i, 0, 0]]).collect();
        assert_eq!(v, vec![0.0, 1.0, 2.0, 0.0, 1.0]);
    }

    #[test]
    fn matched_intervals_give_precision_recall_and_count_error() {
        let det = [(0, 100, 10), (200, 300, 4), (500, 520, 2)];
        let gt = [(10, 100, 9), (190, 310, 5)];
        let v = interval_figures(&det, &gt);
        assert_eq!(v["matched"], 2);
        assert!((v["precision_one_to_one"].as_f64().unwrap() - 2.0 / 3.0).abs() < 1e-9);
        assert_eq!(v["recall_one_to_one"].as_f64().unwrap(), 1.0);
        let mae = (1.0 / 9.0 + 1.0 / 5.0) / 2.0;
        assert!((v["matched_count_mae"].as_f64().unwrap() - mae).abs() < 1e-9);
        assert_eq!(v["matched_count_obo"].as_f64().unwrap(), 1.0);
    }
}
