//! `cargo xtask eval inbetween`: the in-between poses of `mp interpolate`
//! on real keypoint tracks, against the kept keypoints interpolated linearly.
//!
//! For every track of the chosen sources (Penn Action, AIST++ at 30 fps,
//! the reference keypoints of the QUVA videos and the golf swing, MSR
//! Action3D projected into an image; see `sources`) and every factor k:
//! keep every k-th frame, build the guide of the kept keypoints exactly as
//! `mp interpolate` does after its pose model
//! (`mp_video::Guide::from_track`: the program of
//! `mp_pipeline::concrete_program` with `mp_pipeline::Params::default()`,
//! the in-between rule of `mp_video::InterpParams::default()`), and score
//! its target pose (`Guide::target_pose`, the pose the in-between frames are
//! warped to) at every dropped frame up to the last kept one against the
//! true keypoints (seen joints, confidence > 0.3). Every other rule of
//! `--rules` is scored on the same guide and entries (the rule is the only
//! change), `linear` among them: the kept keypoints interpolated linearly.
//!
//! Figures: KD in px of a 512-px frame (`px · 512 / max(H, W)`) and as a
//! percentage of the person's size (the median larger side of the seen
//! keypoints' box), means over tracks of per-track means; elbows and wrists
//! apart; per source and part, and the mean over sources.

mod sources;

use crate::stats::mean;
use crate::table::{Align::Left, Align::Right, Table};
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Args;
use mp_concrete::InBetween;
use mp_video::Guide;
use mp_video::InterpParams;
use rayon::prelude::*;
use serde_json::{json, Value};

pub use sources::Part;
use sources::{Clip, MIN_CONF};

/// Arguments of `cargo xtask eval inbetween`.
#[derive(Args, Debug)]
pub struct EvalInBetweenArgs {
    /// Sources: `penn`, `aist`, `quva`, `msr`.
    #[arg(long, value_delimiter = ',', default_value = "penn,aist,quva,msr")]
    pub sources: Vec<String>,
    /// Subsampling factors.
    #[arg(long, value_delimiter = ',', default_value = "2,4,8")]
    pub factors: Vec<usize>,
    /// Which tracks: `validation` (where settings are chosen), `held-out`
    /// (where they are reported) or `all`.
    #[arg(long, value_enum, default_value_t = Part::All)]
    pub part: Part,
    /// Rules compared with the product's (`mp_concrete::InBetween::parse`:
    /// `linear`, `bulge:B`, `hermite[:keypoints|program][:TENSION][:curved]`).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "linear,bulge:0.5,hermite:keypoints:1"
    )]
    pub rules: Vec<String>,
    /// At most this many tracks per source (evenly spread over its list).
    #[arg(long)]
    pub max_tracks: Option<usize>,
    /// Output JSON.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write Markdown tables to this file.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

/// Per rule: (sum of distances px, sum over elbows and wrists, entries, arm entries).
type Sums = Vec<(f64, f64, usize, usize)>;

/// One track at one factor.
struct TrackResult {
    source: &'static str,
    name: String,
    part: Part,
    factor: usize,
    frame_px: f64,
    person_px: f64,
    sums: Sums,
}

/// The joints whose names say elbow or wrist.
fn arm_joints(track: &mp_geom::Track) -> Vec<bool> {
    track
        .skeleton()
        .joints
        .iter()
        .map(|n| {
            let n = n.to_lowercase();
            n.contains("elbow") || n.contains("wrist")
        })
        .collect()
}

fn run_track(
    c: &Clip,
    k: usize,
    rules: &[InBetween],
    analysis: &mp_pipeline::Params,
    iparams: &InterpParams,
) -> anyhow::Result<Option<TrackResult>> {
    let kept = c.track.subsample(k)?;
    if kept.n_frames() < 3 {
        return Ok(None);
    }
    let mut guide = match Guide::from_track(kept, Some(c.frame_px), analysis, iparams) {
        Ok(g) => g,
        // A track with nothing seen among the kept frames: nothing to score.
        Err(mp_video::VideoError::Param { .. }) => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("{} {} ×{k}", c.source, c.name)),
    };
    let n_kept = guide.track.n_frames();
    let last = (n_kept - 1) * k;
    let arms = arm_joints(&c.track);
    let mut sums: Sums = vec![(0.0, 0.0, 0, 0); rules.len()];
    let dropped: Vec<usize> = (0..=last).filter(|f| f % k != 0).collect();
    // Per rule, the poses at every dropped frame.
    let mut poses = Vec::with_capacity(rules.len());
    for r in rules {
        guide.inbetween = *r;
        let mut per = Vec::with_capacity(dropped.len());
        for &f in &dropped {
            per.push(guide.target_pose(f / k, (f % k) as f64 / k as f64)?);
        }
        poses.push(per);
    }
    for (row, &f) in dropped.iter().enumerate() {
        for (j, &arm) in arms.iter().enumerate() {
            if !c.track.is_valid(f, j, MIN_CONF) {
                continue;
            }
            // The same entries for every rule (they share the hold rule).
            if poses
                .iter()
                .any(|p| !matches!(p[row].get(j), Some(Some(_))))
            {
                continue;
            }
            let q = c.track.point(f, j);
            for (ri, p) in poses.iter().enumerate() {
                let Some(Some(p)) = p[row].get(j) else {
                    continue;
                };
                let e = (p[0] - q[0]).hypot(p[1] - q[1]);
                let s = &mut sums[ri];
                s.0 += e;
                s.2 += 1;
                if arm {
                    s.1 += e;
                    s.3 += 1;
                }
            }
        }
    }
    if sums[0].2 == 0 {
        return Ok(None);
    }
    Ok(Some(TrackResult {
        source: c.source,
        name: c.name.clone(),
        part: c.part,
        factor: k,
        frame_px: c.frame_px,
        person_px: c.person_px,
        sums,
    }))
}

/// Per rule: mean KD px@512, % of the person, arms px@512, tracks where the
/// rule beats the first (linear) rule.
fn summarise(rs: &[&TrackResult], n_rules: usize) -> Value {
    let per_rule: Vec<Value> = (0..n_rules)
        .map(|ri| {
            let px = mean(rs.iter().map(|r| {
                let s = r.sums[ri];
                s.0 / s.2 as f64 * 512.0 / r.frame_px
            }));
            let pct = mean(rs.iter().map(|r| {
                let s = r.sums[ri];
                100.0 * s.0 / s.2 as f64 / r.person_px
            }));
            let arms = mean(rs.iter().filter(|r| r.sums[ri].3 > 0).map(|r| {
                let s = r.sums[ri];
                s.1 / s.3 as f64 * 512.0 / r.frame_px
            }));
            let wins = rs.iter().filter(|r| r.sums[ri].0 < r.sums[0].0).count();
            json!({"kd_px_512": px, "kd_pct_person": pct, "kd_arms_px_512": arms, "tracks_below_linear": wins})
        })
        .collect();
    json!({"tracks": rs.len(), "rules": per_rule})
}

fn f(v: &Value, path: &[&str]) -> f64 {
    path.iter()
        .try_fold(v, |v, k| v.get(*k))
        .and_then(Value::as_f64)
        .unwrap_or(f64::NAN)
}

/// `cargo xtask eval inbetween`.
pub fn run(a: &EvalInBetweenArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let data = mp_geom::data_dir()
        .context("the shared data folder was not found: set MP_DATA_DIR to it")?;
    for &k in &a.factors {
        if k < 2 {
            bail!("factor {k}: must be at least 2");
        }
    }
    let iparams = InterpParams::default();
    let product = iparams.inbetween;
    // Linear first (the reference), the product's rule second, then the rest.
    let mut rules = vec![InBetween::Linear, product];
    for r in &a.rules {
        let r = InBetween::parse(r)?;
        if !rules.contains(&r) {
            rules.push(r);
        }
    }
    let analysis = mp_pipeline::Params::default();
    let mut clips = sources::load(&data, &a.sources, a.part)?;
    if let Some(m) = a.max_tracks {
        let mut kept = Vec::new();
        for s in &a.sources {
            let of: Vec<Clip> = clips.extract_if(.., |c| c.source == s.as_str()).collect();
            let n = of.len();
            let step = n.div_ceil(m.max(1)).max(1);
            kept.extend(
                of.into_iter()
                    .enumerate()
                    .filter(|(i, _)| i % step == 0)
                    .map(|(_, c)| c),
            );
        }
        clips = kept;
    }
    let jobs: Vec<(usize, usize)> = (0..clips.len())
        .flat_map(|c| a.factors.iter().map(move |&k| (c, k)))
        .collect();
    let results: Vec<anyhow::Result<Option<TrackResult>>> = jobs
        .par_iter()
        .map(|&(c, k)| run_track(&clips[c], k, &rules, &analysis, &iparams))
        .collect();
    let mut ok = Vec::new();
    for r in results {
        if let Some(r) = r? {
            ok.push(r);
        }
    }
    let labels: Vec<String> = rules.iter().map(InBetween::label).collect();
    let mut groups = serde_json::Map::new();
    let mut md = String::new();
    let parts: Vec<Part> = match a.part {
        Part::All => vec![Part::Validation, Part::HeldOut],
        p => vec![p],
    };
    for part in parts {
        md += &format!(
            "\n{} — KD % of the person's size (px at 512); rule / linear\n\n",
            part.as_str()
        );
        let mut table = Table::new(["source", "factor", "tracks"]).align([Left, Right, Right]);
        for l in &labels {
            table.column(l.clone(), Right);
        }
        for &k in &a.factors {
            let mut per_source = Vec::new();
            for s in &a.sources {
                let rs: Vec<&TrackResult> = ok
                    .iter()
                    .filter(|r| r.part == part && r.factor == k && r.source == s.as_str())
                    .collect();
                if rs.is_empty() {
                    continue;
                }
                let v = summarise(&rs, rules.len());
                table.row(row(s, k, &v, rules.len()));
                groups.insert(format!("{}/{s}/x{k}", part.as_str()), v.clone());
                per_source.push(v);
            }
            // The mean over sources, each source counting once.
            let macro_rules: Vec<Value> = (0..rules.len())
                .map(|ri| {
                    let m = |key: &str| {
                        mean(per_source.iter().map(|v| f(&v["rules"][ri], &[key])))
                    };
                    json!({"kd_px_512": m("kd_px_512"), "kd_pct_person": m("kd_pct_person"), "kd_arms_px_512": m("kd_arms_px_512")})
                })
                .collect();
            let tracks: u64 = per_source.iter().filter_map(|v| v["tracks"].as_u64()).sum();
            let v = json!({"tracks": tracks, "rules": macro_rules});
            table.row(row("**mean of sources**", k, &v, rules.len()));
            groups.insert(format!("{}/mean/x{k}", part.as_str()), v);
        }
        md += &table.markdown();
    }
    let per_track: Vec<Value> = ok
        .iter()
        .map(|r| {
            json!({"source": r.source, "name": r.name, "part": r.part.as_str(), "factor": r.factor,
                   "frame_px": r.frame_px, "person_px": r.person_px,
                   "kd_px": r.sums.iter().map(|s| s.0 / s.2 as f64).collect::<Vec<_>>(),
                   "entries": r.sums[0].2})
        })
        .collect();
    let report = json!({
        "protocol": "keep every k-th frame; Guide::from_track on the kept keypoints (mp_pipeline::Params::default(), mp_video::InterpParams::default()); Guide::target_pose at the dropped frames vs the true keypoints",
        "rules": labels,
        "product_rule": product.label(),
        "factors": a.factors,
        "part": a.part.as_str(),
        "groups": groups,
        "tracks": per_track,
        "seconds": t0.elapsed().as_secs_f64(),
        "threads": rayon::current_num_threads(),
    });
    crate::write_file(&a.out, serde_json::to_vec_pretty(&report)?)?;
    if let Some(p) = &a.markdown {
        crate::write_file(p, md.as_bytes())?;
    }
    println!("{md}");
    eprintln!(
        "{} track × factor results in {:.0} s → {}",
        ok.len(),
        t0.elapsed().as_secs_f64(),
        a.out.display()
    );
    Ok(())
}

/// The cells of one table row: source, factor, tracks, then one per rule.
fn row(name: &str, k: usize, v: &Value, n_rules: usize) -> Vec<String> {
    let lin = f(&v["rules"][0], &["kd_pct_person"]);
    let mut cells = vec![
        name.to_string(),
        format!("{k}×"),
        v["tracks"].as_u64().unwrap_or(0).to_string(),
    ];
    cells.extend((0..n_rules).map(|ri| {
        let r = &v["rules"][ri];
        let pct = f(r, &["kd_pct_person"]);
        let px = f(r, &["kd_px_512"]);
        if ri == 0 {
            format!("{pct:.2} ({px:.2})")
        } else {
            format!("{pct:.2} ({px:.2}) {:.3}", pct / lin)
        }
    }));
    cells
}
