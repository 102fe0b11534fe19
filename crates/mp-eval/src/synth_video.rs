//! Video cases of known count for `cargo xtask eval count --synthetic-video`:
//! real repetitions cut from the QUVA videos at their labelled cycles,
//! repeated N times (0–12, each repeat at its own speed), placed between
//! stretches of non-repetitive footage and re-joined with FFmpeg.
//!
//! The footage around the repetitions is the golf swing of the shared data
//! folder: real camera footage of a real person making one movement that
//! does not repeat (address, swing, finish), so a count that reaches into it,
//! or counts it, is wrong — and its N = 0 cases say whether a lone movement
//! is counted.
//!
//! Three variants of every case:
//! - `plain`: the joined footage as it is;
//! - `small`: the joined footage scaled to a third of the frame side and laid
//!   at a random place over a cluttered, moving picture (the golf footage at
//!   half speed, enlarged, with the camera panning across it): a repetition
//!   that fills a ninth of the picture, as an apparatus filmed in competition;
//! - `covered`: the joined footage with an opaque, textured block (the golf
//!   footage blurred beyond recognition) of about a third of the picture
//!   sliding once across it, hiding the body for part of the time, as a hula
//!   hoop or a spotter does — hard for the pose model.
//!
//! Case `k` of a seed depends only on the seed, `k` and the source videos;
//! made clips are cached (`<cache>/seed<S>/<variant>_<k>.mp4`).

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context};

use crate::synth_reps::Rng;

/// The variants of each case.
pub const VARIANTS: [&str; 3] = ["plain", "small", "covered"];

/// Repetition counts of a seed's cases, one case per count (each variant has
/// them all): 0 and 1 to check that nothing (or one movement) is not
/// counted as more, then up to 12.
pub const COUNTS: [usize; 12] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12];

/// A labelled source video.
#[derive(Debug, Clone)]
pub struct Source {
    pub path: PathBuf,
    pub name: String,
    /// Frame where each cycle ends (QUVA's labels).
    pub ends: Vec<usize>,
    pub width: usize,
    pub height: usize,
    pub fps: f64,
}

/// One made case.
#[derive(Debug, Clone)]
pub struct VideoCase {
    pub path: PathBuf,
    pub variant: &'static str,
    pub index: usize,
    /// Repetitions in the clip.
    pub truth: usize,
    /// Source video and the labelled cycles cut from it (first, count).
    pub source: String,
    pub cycles: (usize, usize),
    /// Speed of each repeat (1: as recorded).
    pub speeds: Vec<f64>,
    /// Seconds of footage before and after the repetitions.
    pub pad_s: (f64, f64),
}

/// The labelled videos of `videos` (labels `<stem>.npy` in `labels`) with
/// at least three labelled cycles.
pub fn sources(videos: &Path, labels: &Path) -> anyhow::Result<Vec<Source>> {
    let mut out = Vec::new();
    let mut files: Vec<PathBuf> = std::fs::read_dir(videos)
        .with_context(|| format!("listing {}", videos.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "mp4"))
        .collect();
    files.sort();
    for path in files {
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        let label = labels.join(format!("{name}.npy"));
        if !label.is_file() {
            continue;
        }
        let ends: Vec<usize> = mp_geom::read_npy(&label)?
            .to_i64()?
            .into_iter()
            .map(|v| v.max(0) as usize)
            .collect();
        if ends.len() < 3 {
            continue;
        }
        let info = mp_pose::probe(&path)?;
        let (width, height, fps) = (info.width, info.height, info.fps);
        out.push(Source {
            path,
            name,
            ends,
            width,
            height,
            fps,
        });
    }
    Ok(out)
}

/// Even number not below `v` (H.264 wants even sides).
fn even(v: f64) -> usize {
    ((v / 2.0).round() as usize).max(1) * 2
}

/// Makes (or finds cached) case `index` of `variant` under `seed`.
pub fn make_case(
    sources: &[Source],
    golf: &Path,
    cache: &Path,
    seed: u64,
    variant: &'static str,
    index: usize,
) -> anyhow::Result<VideoCase> {
    let truth = COUNTS[index % COUNTS.len()];
    // The repetitions and footage of case `index` are the same in every
    // variant (one stream per case); the variant only changes how it is shown.
    let mut rng = Rng::for_case(seed, index);
    let src = &sources[rng.below(sources.len())];
    // Cycles 1.. (the first has no labelled start): a stretch of one cycle,
    // or of two when the count is even and the draw says so.
    let per = if truth >= 2 && truth.is_multiple_of(2) && rng.f64() < 0.5 {
        2
    } else {
        1
    };
    let first = 1 + rng.below(src.ends.len() - per);
    let (a, b) = (src.ends[first - 1] + 1, src.ends[first - 1 + per] + 1);
    let repeats = truth / per;
    let speeds: Vec<f64> = (0..repeats).map(|_| rng.uniform(0.85, 1.15)).collect();
    let pad_s = (rng.uniform(1.5, 4.0), rng.uniform(1.5, 4.0));
    // Golf footage before and after (the swing is 8.8 s long).
    let golf_at = (
        rng.uniform(0.0, 8.8 - pad_s.0),
        rng.uniform(0.0, 8.8 - pad_s.1),
    );
    let place = (rng.f64(), rng.f64());
    let dir = cache.join(format!("seed{seed}"));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(format!("{variant}_{index}.mp4"));
    let case = VideoCase {
        path: path.clone(),
        variant,
        index,
        truth,
        source: src.name.clone(),
        cycles: (first, per),
        speeds: speeds.clone(),
        pad_s,
    };
    if path.is_file() {
        return Ok(case);
    }
    let (w, h, fps) = (src.width, src.height, src.fps);
    let fit = format!(
        "fps={fps},scale={w}:{h}:force_original_aspect_ratio=decrease,pad={w}:{h}:(ow-iw)/2:(oh-ih)/2,setsar=1"
    );
    let mut g = Vec::new();
    let parts = repeats + 2;
    if repeats > 0 {
        g.push(format!(
            "[0:v]split={repeats}{}",
            (0..repeats).map(|r| format!("[c{r}]")).collect::<String>()
        ));
    }
    for (r, s) in speeds.iter().enumerate() {
        // A repeat at speed s lasts 1/s times as long.
        g.push(format!(
            "[c{r}]trim=start_frame={a}:end_frame={b},setpts=(PTS-STARTPTS)/{s:.4},fps={fps},setsar=1[r{r}]"
        ));
    }
    g.push("[1:v]split=2[g0][g1]".into());
    g.push(format!(
        "[g0]trim=start={:.3}:duration={:.3},setpts=PTS-STARTPTS,{fit}[pre]",
        golf_at.0, pad_s.0
    ));
    g.push(format!(
        "[g1]trim=start={:.3}:duration={:.3},setpts=PTS-STARTPTS,{fit}[post]",
        golf_at.1, pad_s.1
    ));
    g.push(format!(
        "[pre]{}[post]concat=n={parts}:v=1:a=0[base]",
        (0..repeats).map(|r| format!("[r{r}]")).collect::<String>()
    ));
    match variant {
        "plain" => g.push("[base]null[out]".into()),
        "small" => {
            // The golf footage at half speed, 1.6× enlarged, panned once
            // across; the case at a third of the side at a random place.
            let (bw, bh) = (even(w as f64 * 1.6), even(h as f64 * 1.6));
            let total = pad_s.0 + pad_s.1 + 2.0;
            g.push(format!(
                "[2:v]setpts=2*PTS,fps={fps},scale={bw}:{bh}:force_original_aspect_ratio=increase,crop={bw}:{bh},tpad=stop=-1:stop_mode=clone,crop={w}:{h}:x='(iw-ow)*min(t/{total:.1}/4,1)':y='(ih-oh)*min(t/{total:.1}/6,1)'[bg]"
            ));
            let (sw, sh) = (even(w as f64 / 3.0), even(h as f64 / 3.0));
            g.push(format!("[base]scale={sw}:{sh}[s]"));
            let (x, y) = (
                (place.0 * (w - sw) as f64) as usize,
                (place.1 * (h - sh) as f64) as usize,
            );
            g.push(format!("[bg][s]overlay=x={x}:y={y}:shortest=1[out]"));
        }
        "covered" => {
            // A block 45 % wide and 70 % high, textured with the golf footage
            // blurred beyond recognition, sliding once from the left edge to
            // the right one over the case.
            let (bw, bh) = (even(w as f64 * 0.45), even(h as f64 * 0.7));
            let dur =
                pad_s.0 + pad_s.1 + speeds.iter().map(|s| (b - a) as f64 / fps / s).sum::<f64>();
            g.push(format!(
                "[2:v]fps={fps},scale={bw}:{bh},boxblur=12:3,tpad=stop=-1:stop_mode=clone[blk]"
            ));
            g.push(format!(
                "[base][blk]overlay=x='-{bw}/2+({w})*t/{dur:.3}':y={}:shortest=1[out]",
                (h - bh) / 2
            ));
        }
        _ => bail!("unknown variant {variant}"),
    }
    let tmp = dir.join(format!("{variant}_{index}.tmp.mp4"));
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(&src.path)
        .arg("-i")
        .arg(golf)
        .arg("-i")
        .arg(golf)
        .args(["-filter_complex", &g.join(";")])
        .args([
            "-map", "[out]", "-an", "-c:v", "libx264", "-preset", "veryfast",
        ])
        .args(["-crf", "20", "-pix_fmt", "yuv420p", "-threads", "2"])
        .arg(&tmp)
        .output()
        .context("running ffmpeg")?;
    if !out.status.success() {
        bail!(
            "ffmpeg could not make {}: {}",
            path.display(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    std::fs::rename(&tmp, &path)?;
    Ok(case)
}
