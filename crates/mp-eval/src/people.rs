//! `cargo xtask eval people --videos DIR --labels DIR --out FILE.json`:
//! several people in one video, through what `mp run` runs
//! (`mp_pipeline::analyse_input` with `Params::default()`).
//!
//! * **Panels**: videos of one person each (QUVA's form: `<stem>.npy` labels)
//!   side by side, 2 and 3 at a time, scaled to one height and frame rate
//!   with FFmpeg (a shorter panel holds its last frame). Per panel: the
//!   count of the panel's main person (of the people whose mean box centre
//!   lies in the panel, the one `mp_geom::People::main_person`'s rule picks: who moves most)
//!   against the label, and the share of the panel's own frames on which one
//!   id covers it.
//! * **Crossings**: two videos as panels that slide across each other (the
//!   second drawn over the first while they pass); the person who started on
//!   the left must end on the right with the same id, and the other way round.
//! * **Single people**: every labelled video alone, through the several-people
//!   path (the default) and through MediaPipe's single-person pipeline: the
//!   counts of both and the distance between the two paths' keypoints.
//!
//! * **Street scene**: OpenCV's pedestrian video (`vtest.avi`, fetched by
//!   `scripts/setup.sh`): a fixed camera over a path with a lamp post, two
//!   tripods and traffic cones. Per person and frame, whether their pose box
//!   lies half or more inside one of the static objects (boxes read off the
//!   first frame). People walking past cover an object for a moment; a
//!   skeleton left on one stays: runs of a second or more should be none.
//!
//! Videos where the single-person pipeline finds a person on fewer than half
//! of the frames (a bar lift in the dark) have no person to follow and are
//! left out of the panels and crossings.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Args;
use mp_geom::CancelToken;
use mp_geom::{People, Person, PersonId};
use mp_pipeline::{analyse_input, Input, Outcome, Params, Silent};
use serde_json::{json, Value};

/// Arguments of `cargo xtask eval people`.
#[derive(Args, Debug)]
pub struct EvalPeopleArgs {
    /// A folder of videos of one person each.
    #[arg(long)]
    pub videos: PathBuf,
    /// A folder of labels: `<video stem>.npy`, one entry per repetition.
    #[arg(long)]
    pub labels: PathBuf,
    /// Output JSON.
    #[arg(long)]
    pub out: PathBuf,
    /// Where the composite videos are written.
    #[arg(long, default_value = "target/eval-people")]
    pub work: PathBuf,
    /// Panel height (pixels).
    #[arg(long, default_value_t = 360)]
    pub height: usize,
    /// Frame rate of the composites.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Three-panel composites (two-panel ones: one per video).
    #[arg(long, default_value_t = 4)]
    pub triples: usize,
    /// Crossings.
    #[arg(long, default_value_t = 4)]
    pub crossings: usize,
    /// Skip the single-person comparison.
    #[arg(long)]
    pub no_single: bool,
    /// The street scene (default: `vtest.avi` of the set-up's test footage;
    /// skipped when absent).
    #[arg(long)]
    pub street: Option<PathBuf>,
}

/// Static objects of the street scene (`vtest.avi`, 768 × 576), as boxes
/// `[x0, y0, x1, y1]` in pixels read off its first frame.
const STREET_OBJECTS: [(&str, [f64; 4]); 4] = [
    ("lamp post", [410.0, 20.0, 445.0, 185.0]),
    ("tripod", [455.0, 335.0, 528.0, 485.0]),
    ("far tripod", [428.0, 112.0, 468.0, 182.0]),
    ("cloth on the grass", [65.0, 490.0, 165.0, 535.0]),
];

/// Scores the street scene: people, frames where a pose box lies half or
/// more inside a static object, and runs of a second or more of that (a
/// skeleton left on the object).
fn score_street(o: &Outcome) -> Value {
    let Some(people) = &o.keypoints.people else {
        return json!({"people": 0});
    };
    let n = people.n_frames();
    let mut on_objects = Vec::new();
    let mut with_someone = 0usize;
    let mut person_frames = 0usize;
    for f in 0..n {
        let here: Vec<&Person> = people.people().iter().filter(|p| found_at(p, f)).collect();
        with_someone += usize::from(!here.is_empty());
        person_frames += here.len();
    }
    // Runs of consecutive frames of one person on one object: a person
    // walking past an object covers it for a moment; a skeleton left on it
    // stays (a run of a second or more).
    let min_run = people.fps().round().max(1.0) as usize;
    let mut stuck = Vec::new();
    for p in people.people() {
        for (name, o) in STREET_OBJECTS {
            let mut run: Option<(usize, usize)> = None;
            let mut close = |run: &mut Option<(usize, usize)>| {
                if let Some((a, b)) = run.take() {
                    if b + 1 - a >= min_run {
                        stuck.push(json!({"person": p.id, "object": name, "frames": [a, b]}));
                    }
                }
            };
            for f in p.first_frame..=p.last_frame() {
                let on = p.box_at(f).is_some_and(|b| {
                    let area = ((b[2] - b[0]) * (b[3] - b[1])).max(1e-9);
                    let ix = (b[2].min(o[2]) - b[0].max(o[0])).max(0.0);
                    let iy = (b[3].min(o[3]) - b[1].max(o[1])).max(0.0);
                    ix * iy >= 0.5 * area
                });
                if on {
                    on_objects.push(json!({"person": p.id, "frame": f, "object": name}));
                    run = Some(run.map_or((f, f), |(a, _)| (a, f)));
                } else {
                    close(&mut run);
                }
            }
            close(&mut run);
        }
    }
    json!({
        "frames": n,
        "fps": people.fps(),
        "people": people.len(),
        "frames_with_someone": with_someone as f64 / n.max(1) as f64,
        "people_per_frame": person_frames as f64 / n.max(1) as f64,
        "frames_on_objects": on_objects.len(),
        "on_objects": on_objects,
        "stuck_on_objects": stuck,
        "main_person": o.keypoints.person,
        "main_count": o.counts.total,
        "main_signal": o.counts.signal.as_str(),
        "counted_people": o.people.iter().filter(|p| p.counts.is_some()).count(),
        "pose_s": o.stages.iter().filter(|s| s.stage == mp_pipeline::Stage::Pose).map(|s| s.time.as_secs_f64()).sum::<f64>(),
    })
}

/// A labelled video and how it is placed in a composite.
#[derive(Debug, Clone)]
struct Source {
    name: String,
    path: PathBuf,
    truth: usize,
    /// Panel width at the composite's height.
    width: usize,
    /// Frames of the panel at the composite's frame rate.
    frames: usize,
    /// Share of frames where the single-person pipeline finds the person.
    found: f64,
}

fn labelled(videos: &Path, labels: &Path) -> anyhow::Result<Vec<(String, PathBuf, usize)>> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(videos)
        .with_context(|| format!("listing {}", videos.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| Input::is_video(p))
        .collect();
    v.sort();
    let mut out = Vec::new();
    for p in v {
        let stem = p
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        let l = labels.join(format!("{stem}.npy"));
        if l.is_file() {
            let truth = mp_geom::read_npy(&l)?.to_i64()?.len();
            out.push((stem, p, truth));
        }
    }
    Ok(out)
}

fn ffmpeg(args: &[String]) -> anyhow::Result<()> {
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-y"])
        .args(args)
        .output()
        .context("running ffmpeg")?;
    if !out.status.success() {
        bail!(
            "ffmpeg failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    Ok(())
}

/// The filter that brings input `k` to the composite's height and frame rate.
fn scaled(k: usize, s: &Source, height: usize, fps: f64) -> String {
    format!("[{k}:v]fps={fps},scale={}:{height},setsar=1[p{k}]", s.width)
}

/// Panels side by side (a shorter one holds its last frame).
fn side_by_side(panels: &[&Source], out: &Path, height: usize, fps: f64) -> anyhow::Result<()> {
    let mut args = Vec::new();
    for s in panels {
        args.extend(["-i".to_string(), s.path.display().to_string()]);
    }
    let mut filter: Vec<String> = panels
        .iter()
        .enumerate()
        .map(|(k, s)| scaled(k, s, height, fps))
        .collect();
    let ins: String = (0..panels.len()).map(|k| format!("[p{k}]")).collect();
    filter.push(format!("{ins}hstack=inputs={}[v]", panels.len()));
    args.extend([
        "-filter_complex".into(),
        filter.join(";"),
        "-map".into(),
        "[v]".into(),
    ]);
    args.extend(encode_to(out));
    ffmpeg(&args)
}

/// Seconds before the panels of a crossing start to move, and how long they move.
const CROSS_START_S: f64 = 2.0;
const CROSS_MOVE_S: f64 = 2.0;

/// Two panels that swap places: `a` slides from the left to the right while
/// `b` slides from the right to the left, drawn over `a` as they pass.
fn crossing(a: &Source, b: &Source, out: &Path, height: usize, fps: f64) -> anyhow::Result<()> {
    let w = a.width.max(b.width);
    let total_w = 2 * w;
    let secs = (a.frames.max(b.frames) as f64 / fps).max(CROSS_START_S + CROSS_MOVE_S + 2.0);
    let (t0, t1) = (CROSS_START_S, CROSS_START_S + CROSS_MOVE_S);
    let ramp = format!("if(lt(t,{t0}),0,if(lt(t,{t1}),(t-{t0})/{CROSS_MOVE_S},1))");
    let filter = [
        format!("color=c=black:s={total_w}x{height}:r={fps}:d={secs:.3}[bg]"),
        format!(
            "{},tpad=stop_mode=clone:stop_duration={secs:.3}[pa]",
            scaled(0, a, height, fps).trim_end_matches("[p0]")
        ),
        format!(
            "{},tpad=stop_mode=clone:stop_duration={secs:.3}[pb]",
            scaled(1, b, height, fps).trim_end_matches("[p1]")
        ),
        format!("[bg][pa]overlay=x='{w}*{ramp}':y=0:shortest=1[t]"),
        format!("[t][pb]overlay=x='{w}-{w}*{ramp}':y=0:shortest=1[v]"),
    ]
    .join(";");
    ffmpeg(
        &[
            "-i".into(),
            a.path.display().to_string(),
            "-i".into(),
            b.path.display().to_string(),
            "-filter_complex".into(),
            filter,
            "-map".into(),
            "[v]".into(),
            "-t".into(),
            format!("{secs:.3}"),
        ]
        .into_iter()
        .chain(encode_to(out))
        .collect::<Vec<_>>(),
    )
}

/// FFmpeg's output arguments of a composite: H.264 (CRF 20), 4:2:0, `out`.
fn encode_to(out: &Path) -> Vec<String> {
    [
        "-c:v", "libx264", "-preset", "veryfast", "-crf", "20", "-pix_fmt", "yuv420p",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([out.display().to_string()])
    .collect()
}

fn analyse(path: &Path, params: &Params) -> anyhow::Result<Outcome> {
    analyse_input(
        Input::open(path, None)?,
        params,
        &Silent,
        &CancelToken::new(),
    )
    .with_context(|| format!("analysing {}", path.display()))
}

/// The mean box centre's x of a person.
fn centre_x(p: &Person) -> Option<f64> {
    p.mean_box().map(|b| (b[0] + b[2]) / 2.0)
}

/// Whether the person was found on video frame `f`.
fn found_at(p: &Person, f: usize) -> bool {
    f >= p.first_frame
        && f <= p.last_frame()
        && p.track
            .confidence()
            .row(f - p.first_frame)
            .iter()
            .any(|&c| c > 0.0)
}

/// The people whose mean box centre lies in `[x0, x1)`, and among them the
/// main one (the rule of `People::main_person`).
fn panel_people(people: &People, x0: f64, x1: f64) -> (Vec<PersonId>, Option<PersonId>) {
    let inside: Vec<&Person> = people
        .people()
        .iter()
        .filter(|p| centre_x(p).is_some_and(|c| c >= x0 && c < x1))
        .collect();
    let main = People::new(
        people.n_frames(),
        people.fps(),
        inside.iter().map(|p| (*p).clone()).collect(),
    )
    .ok()
    .and_then(|p| p.main_person().map(|m| m.id));
    (inside.iter().map(|p| p.id).collect(), main)
}

/// Share of frames `0..frames` on which one id (the best) is found.
fn coverage(people: &People, ids: &[PersonId], frames: usize) -> (f64, Option<PersonId>) {
    ids.iter()
        .filter_map(|id| people.get(*id))
        .map(|p| {
            let n = (0..frames).filter(|&f| found_at(p, f)).count();
            (n as f64 / frames.max(1) as f64, Some(p.id))
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap_or((0.0, None))
}

fn count_of(o: &Outcome, id: Option<PersonId>) -> usize {
    id.and_then(|id| o.people.iter().find(|p| p.id == id))
        .and_then(|p| p.counts.as_ref())
        .map_or(0, |c| c.total)
}

/// Scores the panels of a side-by-side composite.
fn score_panels(o: &Outcome, panels: &[&Source]) -> anyhow::Result<Vec<Value>> {
    let Some(people) = &o.keypoints.people else {
        bail!("no people in the outcome (several-people tracking is off?)");
    };
    let mut x0 = 0.0;
    let mut out = Vec::new();
    for s in panels {
        let x1 = x0 + s.width as f64;
        let (ids, main) = panel_people(people, x0, x1);
        let (cov, cov_id) = coverage(people, &ids, s.frames);
        let count = count_of(o, main);
        out.push(json!({
            "video": s.name, "true_count": s.truth, "count": count,
            "abs_error": (count as i64 - s.truth as i64).abs(),
            "within_one": (count as i64 - s.truth as i64).abs() <= 1,
            "main_person": main, "people_in_panel": ids.len(),
            "coverage": cov, "coverage_id": cov_id, "covered": cov >= 0.8,
        }));
        x0 = x1;
    }
    Ok(out)
}

/// Scores a crossing: the ids on the left and right before and after.
fn score_crossing(o: &Outcome, a: &Source, b: &Source, fps: f64) -> anyhow::Result<Value> {
    let Some(people) = &o.keypoints.people else {
        bail!("no people in the outcome");
    };
    let w = a.width.max(b.width) as f64;
    let n = people.n_frames();
    let before = (0.5 * fps) as usize..(CROSS_START_S * fps) as usize;
    let after = (((CROSS_START_S + CROSS_MOVE_S + 0.5) * fps) as usize).min(n)..n;
    // The id found most often with its box centre in a half over some frames.
    let id_in = |half: usize, frames: std::ops::Range<usize>| -> Option<PersonId> {
        people
            .people()
            .iter()
            .map(|p| {
                let k = frames
                    .clone()
                    .filter(|&f| {
                        p.box_at(f).is_some_and(|bx| {
                            let c = (bx[0] + bx[2]) / 2.0;
                            c >= half as f64 * w && c < (half + 1) as f64 * w
                        })
                    })
                    .count();
                (k, p.id)
            })
            .filter(|x| x.0 > 0)
            .max()
            .map(|x| x.1)
    };
    let (la, rb) = (id_in(0, before.clone()), id_in(1, before));
    let (ra, lb) = (id_in(1, after.clone()), id_in(0, after));
    let kept_a = la.is_some() && la == ra;
    let kept_b = rb.is_some() && rb == lb;
    Ok(json!({
        "videos": [a.name, b.name],
        "left_before": la, "right_after": ra, "right_before": rb, "left_after": lb,
        "kept_ids": kept_a && kept_b, "people": people.len(),
    }))
}

pub fn run(a: &EvalPeopleArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let items = labelled(&a.videos, &a.labels)?;
    if items.is_empty() {
        bail!(
            "no video in {} has a label file <stem>.npy in {}",
            a.videos.display(),
            a.labels.display()
        );
    }
    std::fs::create_dir_all(&a.work)?;
    let params = Params::default();
    let mut single_params = Params::default();
    single_params.pose.people = false;

    // Single people: both paths, and whether a person is there to follow.
    let mut sources = Vec::new();
    let mut singles = Vec::new();
    for (name, path, truth) in &items {
        let info = mp_pose::probe(path)?;
        let width =
            2 * ((info.width as f64 * a.height as f64 / info.height as f64 / 2.0).round() as usize);
        let dur = info
            .duration_s
            .or_else(|| info.frame_count.map(|n| n as f64 / info.fps))
            .unwrap_or(0.0);
        let src = Source {
            name: name.clone(),
            path: path.clone(),
            truth: *truth,
            width,
            frames: (dur * a.fps).round() as usize,
            found: 0.0,
        };
        eprint!("{name}: ");
        if a.no_single {
            let one = mp_pipeline::keypoints(
                Input::open(path, None)?,
                &single_params,
                mp_pipeline::Keep::default(),
                &Silent,
                &CancelToken::new(),
            )?
            .0;
            if one.found_fraction >= 0.5 {
                sources.push(Source {
                    found: one.found_fraction,
                    ..src
                });
            }
            eprintln!(
                "person found on {:.0} % of frames",
                100.0 * one.found_fraction
            );
            continue;
        }
        let single = analyse(path, &single_params)?;
        let one = &single.keypoints;
        let found = one.found_fraction;
        if found >= 0.5 {
            sources.push(Source { found, ..src });
        }
        let multi = analyse(path, &params)?;
        // Keypoints of both paths on the frames where both found the person.
        let (ta, tb) = (&multi.keypoints.track, &one.track);
        let mut d = Vec::new();
        for t in 0..ta.n_frames().min(tb.n_frames()) {
            for j in 0..ta.n_joints().min(tb.n_joints()) {
                if ta.confidence()[[t, j]] > 0.0 && tb.confidence()[[t, j]] > 0.0 {
                    let (p, q) = (ta.point(t, j), tb.point(t, j));
                    d.push((p[0] - q[0]).hypot(p[1] - q[1]));
                }
            }
        }
        d.sort_by(f64::total_cmp);
        let med = d.get(d.len() / 2).copied().unwrap_or(f64::NAN);
        let mean = d.iter().sum::<f64>() / d.len().max(1) as f64;
        eprintln!(
            "{} (single {}, labelled {truth}), keypoints {med:.2} px median",
            multi.counts.total, single.counts.total
        );
        let pose_s = |o: &Outcome| -> f64 {
            o.stages
                .iter()
                .filter(|s| s.stage == mp_pipeline::Stage::Pose)
                .map(|s| s.time.as_secs_f64())
                .sum()
        };
        singles.push(json!({
            "pose_s": pose_s(&multi), "pose_s_single_person": pose_s(&single),
            "video": name, "true_count": truth,
            "count": multi.counts.total, "count_single_person": single.counts.total,
            "people": multi.people.len(),
            "keypoints_median_px": med, "keypoints_mean_px": mean,
            "person_found": multi.keypoints.found_fraction, "person_found_single": found,
        }));
    }
    let score_counts = |key: &str| -> (f64, f64) {
        let k = singles.len().max(1) as f64;
        let (mut mae, mut obo) = (0.0, 0.0);
        for s in &singles {
            let (c, t) = (
                s[key].as_f64().unwrap_or(0.0),
                s["true_count"].as_f64().unwrap_or(1.0),
            );
            mae += (c - t).abs() / t.max(1.0);
            obo += f64::from((c - t).abs() <= 1.0);
        }
        (mae / k, obo / k)
    };

    // Panels.
    let n = sources.len();
    let mut sets: Vec<Vec<usize>> = (0..n).map(|i| vec![i, (i + 1) % n]).collect();
    for i in 0..a.triples.min(n) {
        let step = (n / 3).max(1);
        sets.push(vec![i, (i + step) % n, (i + 2 * step) % n]);
    }
    let mut composites = Vec::new();
    let mut panels_all = Vec::new();
    for set in &sets {
        if n < set.len() {
            break;
        }
        let panels: Vec<&Source> = set.iter().map(|&k| &sources[k]).collect();
        let name = panels
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join("+");
        let file = a.work.join(format!("{name}.mp4"));
        side_by_side(&panels, &file, a.height, a.fps)?;
        let t = Instant::now();
        let o = analyse(&file, &params)?;
        let scored = score_panels(&o, &panels)?;
        eprintln!(
            "{name}: {}",
            scored
                .iter()
                .map(|p| format!(
                    "{}/{} ({:.0} %)",
                    p["count"],
                    p["true_count"],
                    100.0 * p["coverage"].as_f64().unwrap_or(0.0)
                ))
                .collect::<Vec<_>>()
                .join(", ")
        );
        panels_all.extend(scored.iter().cloned());
        let frames = o.keypoints.track.n_frames();
        let pose_s: f64 = o
            .stages
            .iter()
            .filter(|s| s.stage == mp_pipeline::Stage::Pose)
            .map(|s| s.time.as_secs_f64())
            .sum();
        composites.push(json!({
            "composite": name, "panels": scored, "people": o.people.len(),
            "frames": frames, "pose_fps": frames as f64 / pose_s.max(1e-9),
            "seconds": t.elapsed().as_secs_f64(),
        }));
    }
    let k = panels_all.len().max(1) as f64;
    let within = panels_all
        .iter()
        .filter(|p| p["within_one"] == true)
        .count();
    let covered = panels_all.iter().filter(|p| p["covered"] == true).count();
    let mae = panels_all
        .iter()
        .map(|p| {
            p["abs_error"].as_f64().unwrap_or(0.0)
                / p["true_count"].as_f64().unwrap_or(1.0).max(1.0)
        })
        .sum::<f64>()
        / k;

    // Crossings, of the people the single-person pipeline finds most often
    // (a crossing tests the ids, not the finding of a hard pose).
    let mut steady: Vec<&Source> = sources.iter().collect();
    steady.sort_by(|x, y| y.found.total_cmp(&x.found).then(x.name.cmp(&y.name)));
    let mut crossings = Vec::new();
    for i in 0..a.crossings.min(n / 2) {
        let (sa, sb) = (steady[2 * i], steady[2 * i + 1]);
        let file = a.work.join(format!("cross_{}_{}.mp4", sa.name, sb.name));
        crossing(sa, sb, &file, a.height, a.fps)?;
        let o = analyse(&file, &params)?;
        let s = score_crossing(&o, sa, sb, a.fps)?;
        eprintln!(
            "crossing {} × {}: ids kept {}",
            sa.name, sb.name, s["kept_ids"]
        );
        crossings.push(s);
    }
    let kept = crossings.iter().filter(|c| c["kept_ids"] == true).count();

    // The street scene.
    let street_path = a
        .street
        .clone()
        .or_else(|| mp_geom::footage_file("vtest.avi"));
    let street = match street_path {
        Some(path) => {
            let o = analyse(&path, &params)?;
            let s = score_street(&o);
            eprintln!(
                "street scene: {} people, {} frames with a pose on a static object, {} runs of 1 s or more",
                s["people"], s["frames_on_objects"], s["stuck_on_objects"].as_array().map_or(0, Vec::len)
            );
            s
        }
        None => {
            eprintln!("street scene: no vtest.avi (bash scripts/setup.sh fetches it); skipped");
            Value::Null
        }
    };
    let (mae_m, obo_m) = score_counts("count");
    let sum_of = |key: &str| {
        singles
            .iter()
            .map(|s| s[key].as_f64().unwrap_or(0.0))
            .sum::<f64>()
    };
    let pose_ratio = sum_of("pose_s") / sum_of("pose_s_single_person").max(1e-9);
    let mut px: Vec<f64> = singles
        .iter()
        .filter_map(|s| s["keypoints_median_px"].as_f64())
        .collect();
    px.sort_by(f64::total_cmp);
    let (mae_s, obo_s) = score_counts("count_single_person");
    let report = json!({
        "kind": "several_people",
        "definition": "mp_pipeline::analyse_input with Params::default() on composites of labelled one-person videos. Per panel: the count of the panel's main person (of the people whose mean box centre lies in the panel, the one who moves most: People::main_person) against the label; coverage = share of the panel's own frames on which its best-covering id is found. Crossings: the ids on the left and right before the panels move and after they have swapped places. Single: each video alone, several-people path (default) against the single-person pipeline (pose.people = false).",
        "panels": panels_all.len(),
        "panels_within_one": within as f64 / k,
        "panels_count_mae": mae,
        "panels_covered_80": covered as f64 / k,
        "crossings": crossings.len(),
        "crossings_kept_ids": kept,
        "single_videos": singles.len(),
        "single_count_mae": mae_m, "single_count_obo": obo_m,
        "single_person_path_count_mae": mae_s, "single_person_path_count_obo": obo_s,
        "single_pose_time_ratio": pose_ratio,
        "single_keypoints_median_px_worst": px.last(),
        "composites": composites,
        "crossing_results": crossings,
        "street": street,
        "single": singles,
        "left_out": items.iter().filter(|(name, _, _)| !sources.iter().any(|s| &s.name == name)).map(|x| x.0.clone()).collect::<Vec<_>>(),
        "runtime_s": t0.elapsed().as_secs_f64(),
    });
    if let Some(dir) = a.out.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    mp_geom::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    let mut summary = report.clone();
    if let Value::Object(m) = &mut summary {
        for k in ["composites", "crossing_results", "single"] {
            m.remove(k);
        }
        if let Some(Value::Object(street)) = m.get_mut("street") {
            street.remove("on_objects");
        }
    }
    println!("{}", serde_json::to_string_pretty(&summary)?);
    eprintln!("written to {}", a.out.display());
    Ok(())
}
