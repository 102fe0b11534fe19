//! `cargo xtask eval count --long --synthetic --out FILE.json [--seed S] [--long-cases N]`:
//! long recordings of several activities with exact answers, counted by
//! the product (`mp_pipeline::count` with `Params::default()` on keypoints).
//!
//! * **Synthetic**, per keypoint source ([`crate::synth_sources`]): two to
//!   five repetitive stretches made by [`crate::synth_reps::make_case`],
//!   each a cycle of another clip whose period differs from the previous
//!   stretch's by at least a quarter, joined in time; between two stretches
//!   either the non-repetitive motion of the source played around them
//!   (half of the joins) or a straight cut. Truth: each stretch's frames and
//!   count.
//! * **Real**: the AIST++ moves of one camera joined one after the other
//!   (each file one move repeated to the beat: one interval, in a seeded
//!   order per camera), the CMU salsa takes joined (each take one interval),
//!   and the CMU exercise recordings joined (their labelled blocks).
//!   Intervals only: these have no per-interval count.

use std::path::Path;
use std::time::Instant;

use anyhow::anyhow;
use mp_geom::Track;
use mp_geom::{AistPlusPlus, CmuFeatures};
use mp_pipeline::Params;
use rayon::prelude::*;
use serde_json::{json, Value};

use crate::count_long::{interval_figures, join, write_long_report};
use crate::synth_reps::{make_case, Case, Rng, Source, SynthOpts};
use crate::synth_sources::{files, load_sources, stem, to_30fps};

/// Added to the seed for the long cases' own random numbers, so that their
/// stretches are not the single-activity cases of the same seed.
const LONG_SALT: u64 = 0x4C4F_4E47;

/// Two neighbouring stretches' periods differ by at least this ratio.
const MIN_PERIOD_RATIO: f64 = 1.25;

/// A long recording and its labelled intervals `(start, end, count)`.
pub struct LongCase {
    pub source: String,
    pub id: usize,
    pub track: Track,
    pub truth: Vec<(usize, usize, usize)>,
    /// For each join, whether it was a straight cut.
    pub cuts: Vec<bool>,
}

fn period_s(c: &Case) -> Option<f64> {
    c.cycle
        .as_ref()
        .map(|(_, cy)| (cy.b - cy.a) as f64 / c.track.fps())
}

/// Long case `id` of `src`: see the module docs. `None` when the source
/// cannot give two stretches.
pub fn make_long(src: &Source, id: usize, seed: u64) -> Option<LongCase> {
    let opts = SynthOpts {
        non_rep_share: 0.0,
        ..SynthOpts::default()
    };
    let mut rng = Rng::for_case(seed.wrapping_add(LONG_SALT), id);
    let want = 2 + rng.below(4);
    let mut parts: Vec<Case> = Vec::new();
    for attempt in 0..8 * want {
        if parts.len() == want {
            break;
        }
        let sub_seed = seed
            .wrapping_add(LONG_SALT)
            .wrapping_add(1 + attempt as u64);
        let Some(c) = make_case(src, id, sub_seed, &opts) else {
            continue;
        };
        let ok = match parts.last() {
            None => true,
            Some(p) => {
                let (a, b) = (period_s(p)?, period_s(&c)?);
                let other_clip = p.cycle.as_ref().map(|x| &x.0) != c.cycle.as_ref().map(|x| &x.0);
                (c.track.fps() - p.track.fps()).abs() < 1e-9
                    && other_clip
                    && a.max(b) >= MIN_PERIOD_RATIO * a.min(b)
            }
        };
        if ok && c.truth >= 2 {
            parts.push(c);
        }
    }
    if parts.len() < 2 {
        return None;
    }
    let cuts: Vec<bool> = (1..parts.len()).map(|_| rng.f64() < 0.5).collect();
    let mut pieces = Vec::new();
    let mut truth = Vec::new();
    let mut offset = 0;
    for (k, p) in parts.iter().enumerate() {
        let a = if k > 0 && cuts[k - 1] { p.rep_start } else { 0 };
        let b = if k + 1 < parts.len() && cuts[k] {
            p.rep_end
        } else {
            p.track.n_frames()
        };
        pieces.push(p.track.slice_frames(a, b).ok()?);
        truth.push((offset + p.rep_start - a, offset + p.rep_end - a, p.truth));
        offset += b - a;
    }
    let refs: Vec<&Track> = pieces.iter().collect();
    Some(LongCase {
        source: src.name.clone(),
        id,
        track: join(&refs).ok()?,
        truth,
        cuts,
    })
}

/// Counting one long case: its figures and the numbers they are made of.
struct Scored {
    source: String,
    det: usize,
    gt: usize,
    matched: usize,
    /// Per labelled interval: |count − truth| / truth and within one, an
    /// unmatched interval counting 0.
    errs: Vec<(f64, bool)>,
    frames: usize,
    secs: f64,
    json: Value,
}

fn score(
    source: &str,
    id: usize,
    track: &Track,
    truth: &[(usize, usize, usize)],
    params: &Params,
) -> anyhow::Result<Scored> {
    let t0 = Instant::now();
    let c = mp_pipeline::count(track, None, params)?;
    let secs = t0.elapsed().as_secs_f64();
    let det: Vec<(usize, usize, usize)> = c
        .intervals
        .iter()
        .map(|i| (i.start_frame, i.end_frame, i.count))
        .collect();
    let d: Vec<(usize, usize)> = det.iter().map(|x| (x.0, x.1)).collect();
    let g: Vec<(usize, usize)> = truth.iter().map(|x| (x.0, x.1)).collect();
    let pairs = crate::intervals::one_to_one_pairs(&d, &g);
    let errs = truth
        .iter()
        .enumerate()
        .map(|(b, t)| {
            let got = pairs
                .iter()
                .find(|p| p.1 == b)
                .map_or(0.0, |p| det[p.0].2 as f64);
            let tc = t.2 as f64;
            ((got - tc).abs() / tc.max(1.0), (got - tc).abs() <= 1.0)
        })
        .collect();
    Ok(Scored {
        source: source.to_string(),
        det: det.len(),
        gt: truth.len(),
        matched: pairs.len(),
        errs,
        frames: track.n_frames(),
        secs,
        json: json!({"source": source, "id": id, "frames": track.n_frames(), "fps": track.fps(),
            "truth": truth, "detected": det, "method": c.method.as_str(),
            "figures": interval_figures(&det, truth)}),
    })
}

fn figures(items: &[&Scored], counts: bool) -> Value {
    let (det, gt, m) = items
        .iter()
        .fold((0, 0, 0), |a, s| (a.0 + s.det, a.1 + s.gt, a.2 + s.matched));
    let errs: Vec<(f64, bool)> = items.iter().flat_map(|s| s.errs.clone()).collect();
    let k = errs.len().max(1) as f64;
    let mut v = json!({
        "recordings": items.len(), "detected": det, "labelled": gt, "matched": m,
        "precision_one_to_one": crate::loops::ratio(m, det),
        "recall_one_to_one": crate::loops::ratio(m, gt),
    });
    if counts {
        v["interval_count_mae"] = json!(errs.iter().map(|e| e.0).sum::<f64>() / k);
        v["interval_count_obo"] = json!(errs.iter().filter(|e| e.1).count() as f64 / k);
    }
    v
}

/// The real long recordings: `(name, track, labelled intervals)` (counts 0: unknown).
type RealCase = (String, Track, Vec<(usize, usize, usize)>);

fn real_cases(data: &Path, seed: u64) -> anyhow::Result<Vec<RealCase>> {
    let mut out = Vec::new();
    let aist: Vec<AistPlusPlus> = files(&data.join("aistpp_keypoints2d"), "npz")
        .iter()
        .map(AistPlusPlus::open)
        .collect::<Result<_, _>>()?;
    if let Some(first) = aist.first() {
        for v in 0..first.views.len() {
            let mut order: Vec<usize> = (0..aist.len()).collect();
            let mut rng = Rng::for_case(seed.wrapping_add(LONG_SALT), 10_000 + v);
            for i in (1..order.len()).rev() {
                order.swap(i, rng.below(i + 1));
            }
            let tracks: Vec<Track> = order
                .iter()
                .map(|&k| to_30fps(&aist[k].views[v]))
                .collect::<Result<_, _>>()?;
            out.push(joined(format!("aistpp_view{v}"), &tracks, None)?);
        }
    }
    let salsa: Vec<Track> = files(&data.join("cmu_salsa_bvh"), "bvh")
        .iter()
        .map(|f| {
            mp_geom::read_track(f)
                .map_err(anyhow::Error::from)
                .and_then(|t| Ok(to_30fps(&t)?))
        })
        .collect::<anyhow::Result<_>>()?;
    if salsa.len() >= 2 {
        out.push(joined("cmu_salsa".into(), &salsa, None)?);
    }
    let cmu: Vec<CmuFeatures> = files(&data.join("cmu_mocap6_exercise"), "npz")
        .iter()
        .filter(|f| stem(f).ends_with("features10fps"))
        .map(CmuFeatures::open)
        .collect::<Result<_, _>>()?;
    if cmu.len() >= 2 {
        let tracks: Vec<Track> = cmu.iter().map(|c| c.track.clone()).collect();
        let labels: Vec<Vec<i64>> = cmu.iter().map(|c| c.labels.clone()).collect();
        out.push(joined(
            "cmu_mocap6_features".into(),
            &tracks,
            Some(&labels),
        )?);
    }
    Ok(out)
}

/// Tracks joined in time; each is one interval, or with `labels` its runs of
/// equal labels are.
fn joined(name: String, tracks: &[Track], labels: Option<&[Vec<i64>]>) -> anyhow::Result<RealCase> {
    let mut truth = Vec::new();
    let mut offset = 0;
    for (k, t) in tracks.iter().enumerate() {
        let n = t.n_frames();
        match labels {
            Some(l) => truth.extend(
                crate::intervals::blocks(&l[k])
                    .into_iter()
                    .map(|b| (offset + b.1, offset + b.2, 0)),
            ),
            None => truth.push((offset, offset + n, 0)),
        }
        offset += n;
    }
    let refs: Vec<&Track> = tracks.iter().collect();
    Ok((name, join(&refs)?, truth))
}

pub fn run(
    out: &Path,
    seed: u64,
    per_source: usize,
    params: &Params,
    overrides: &[String],
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let data = mp_geom::data_dir()
        .ok_or_else(|| anyhow!("the shared data folder was not found: set MP_DATA_DIR"))?;
    let sources = load_sources(&data)?;
    let jobs: Vec<(usize, usize)> = (0..sources.len())
        .flat_map(|s| (0..per_source).map(move |i| (s, i)))
        .collect();
    let cases: Vec<LongCase> = jobs
        .par_iter()
        .filter_map(|&(s, i)| make_long(&sources[s], i, seed))
        .collect();
    eprintln!("{} synthetic long cases; counting …", cases.len());
    let scored: Vec<Scored> = cases
        .par_iter()
        .map(|c| score(&c.source, c.id, &c.track, &c.truth, params))
        .collect::<anyhow::Result<_>>()?;
    let reals = real_cases(&data, seed)?;
    let real: Vec<Scored> = reals
        .par_iter()
        .map(|(n, t, g)| score(n, 0, t, g, params))
        .collect::<anyhow::Result<_>>()?;
    let all: Vec<&Scored> = scored.iter().collect();
    let mut by_source = serde_json::Map::new();
    for s in &sources {
        let g: Vec<&Scored> = scored.iter().filter(|x| x.source == s.name).collect();
        by_source.insert(s.name.clone(), figures(&g, true));
    }
    let mut real_by = serde_json::Map::new();
    for (name, _, _) in &reals {
        let kind = name.split("_view").next().unwrap_or(name).to_string();
        let g: Vec<&Scored> = real
            .iter()
            .filter(|x| x.source.starts_with(&kind))
            .collect();
        real_by.insert(kind, figures(&g, false));
    }
    let real_all: Vec<&Scored> = real.iter().collect();
    let both: Vec<&Scored> = scored.iter().chain(&real).collect();
    let (frames, secs) = both
        .iter()
        .fold((0, 0.0), |a, s| (a.0 + s.frames, a.1 + s.secs));
    let report = json!({
        "kind": "repetition_intervals_long_recordings",
        "seed": seed, "per_source": per_source, "count_param_overrides": overrides,
        "cuts": cases.iter().map(|c| c.cuts.iter().filter(|&&x| x).count()).sum::<usize>(),
        "joins": cases.iter().map(|c| c.cuts.len()).sum::<usize>(),
        "definition": "synthetic: per keypoint source, 2–5 repetitive stretches (synth_reps::make_case, N ≥ 2, each a cycle of another clip, neighbouring periods differing by ≥ 25 %) joined, half of the joins through the source's non-repetitive motion played around them, half straight cuts; real: AIST++ moves of one camera joined in a seeded order (each file one interval), the CMU salsa takes joined (each one interval), the CMU exercise feature recordings joined (their labelled blocks). mp_pipeline::count(track, None, Params::default()); one-to-one matching by IoM > 0.5 (greedy); interval count MAE/OBO over labelled intervals, an unmatched one counting 0.",
        "synthetic": figures(&all, true),
        "synthetic_by_source": by_source,
        "real": figures(&real_all, false),
        "real_by_kind": real_by,
        "all_intervals": figures(&both, false),
        "count_ms_per_frame": 1000.0 * secs / frames.max(1) as f64,
        "frames": frames,
        "runtime_s": t0.elapsed().as_secs_f64(),
        "threads": rayon::current_num_threads(),
        "cases_detail": scored.iter().chain(&real).map(|s| s.json.clone()).collect::<Vec<_>>(),
    });
    write_long_report(out, &report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth_reps::SourceClip;
    use mp_geom::{Skeleton, Units};
    use ndarray::{Array2, Array3};

    /// A clip of a two-joint figure moving in a sine of `period` frames.
    fn sine_clip(name: &str, period: f64, frames: usize) -> SourceClip {
        let pos = Array3::from_shape_fn((frames, 2, 2), |(t, j, k)| {
            let ph = 2.0 * std::f64::consts::PI * t as f64 / period;
            j as f64 + if k == 0 { ph.sin() } else { 0.5 * ph.cos() }
        });
        SourceClip {
            name: name.into(),
            pos,
            conf: Array2::ones((frames, 2)),
            fps: 30.0,
            scale: 2.0,
            joints: vec![0, 1],
        }
    }

    #[test]
    fn long_cases_join_stretches_with_their_truth() {
        let src = crate::synth_sources::source_of(
            "sines",
            vec![sine_clip("a", 20.0, 600), sine_clip("b", 45.0, 600)],
            Units::Pixels,
            Skeleton::generic(2),
        );
        let c = make_long(&src, 0, 3).expect("two stretches");
        assert!(c.truth.len() >= 2);
        assert_eq!(c.cuts.len(), c.truth.len() - 1);
        for w in c.truth.windows(2) {
            assert!(w[0].1 <= w[1].0, "{:?}", c.truth);
        }
        let last = c.truth.last().unwrap();
        assert!(last.1 <= c.track.n_frames());
        assert!(c.truth.iter().all(|t| t.2 >= 2));
    }

    #[test]
    fn joined_real_recordings_give_one_interval_per_file_or_label_run() {
        let t = |n| {
            Track::new(
                Array3::zeros((n, 1, 1)),
                None,
                10.0,
                Units::Unitless,
                Skeleton::generic(1),
            )
            .unwrap()
        };
        let (_, track, truth) = joined("x".into(), &[t(5), t(3)], None).unwrap();
        assert_eq!(track.n_frames(), 8);
        assert_eq!(truth, vec![(0, 5, 0), (5, 8, 0)]);
        let labels = vec![vec![1, 1, 2, 2, 2], vec![3, 3, 3]];
        let (_, _, truth) = joined("x".into(), &[t(5), t(3)], Some(&labels)).unwrap();
        assert_eq!(truth, vec![(0, 2, 0), (2, 5, 0), (5, 8, 0)]);
    }
}
