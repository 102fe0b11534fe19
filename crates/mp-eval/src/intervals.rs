//! Repetitive intervals on the CMU mocap6 exercise features (part of
//! `cargo xtask eval loops`): the product's intervals (`mp_pipeline::count`,
//! what `mp run` and `mp loops` report) against the labelled exercise
//! blocks, with settings chosen by leave-one-recording-out, beside the raw
//! segmenter and the loops of the abstract program.

use std::path::PathBuf;

use anyhow::Context;
use mp_abstract::{iom, iou, segment_repetitions, IntervalParams};
use mp_geom::CmuFeatures;
use mp_pipeline::Params;
use serde_json::{json, Map, Value};

use crate::loops::ratio;

/// Maximal runs of equal labels: `(label, start, end)`.
pub(crate) fn blocks(labels: &[i64]) -> Vec<(i64, usize, usize)> {
    let mut out = Vec::new();
    let mut s = 0;
    for i in 1..=labels.len() {
        if i == labels.len() || labels[i] != labels[s] {
            out.push((labels[s], s, i));
            s = i;
        }
    }
    out
}

/// Greedy one-to-one matching of detections and labels by decreasing IoM (> 0.5):
/// the matched pairs `(detection, label)`.
pub(crate) fn one_to_one_pairs(
    det: &[(usize, usize)],
    gt: &[(usize, usize)],
) -> Vec<(usize, usize)> {
    let mut pairs: Vec<(f64, usize, usize)> = det
        .iter()
        .enumerate()
        .flat_map(|(a, x)| gt.iter().enumerate().map(move |(b, y)| (iom(*x, *y), a, b)))
        .filter(|p| p.0 > 0.5)
        .collect();
    pairs.sort_by(|x, y| y.0.total_cmp(&x.0));
    let (mut ud, mut ug) = (vec![false; det.len()], vec![false; gt.len()]);
    let mut out = Vec::new();
    for (_, a, b) in pairs {
        if !ud[a] && !ug[b] {
            ud[a] = true;
            ug[b] = true;
            out.push((a, b));
        }
    }
    out
}

/// The number of one-to-one matched pairs ([`one_to_one_pairs`]).
fn one_to_one(det: &[(usize, usize)], gt: &[(usize, usize)]) -> usize {
    one_to_one_pairs(det, gt).len()
}

/// Matching counts of detections against labels, summed over recordings.
#[derive(Default, Clone, Copy)]
struct Match {
    det: usize,
    gt: usize,
    det_iom: usize,
    gt_iom: usize,
    det_iou: usize,
    gt_iou: usize,
    one: usize,
}

impl Match {
    fn of(d: &[(usize, usize)], g: &[(usize, usize)]) -> Self {
        let any = |x: &(usize, usize), ys: &[(usize, usize)], f: fn(_, _) -> f64, t: f64| {
            ys.iter().any(|y| f(*x, *y) > t)
        };
        Match {
            det: d.len(),
            gt: g.len(),
            det_iom: d.iter().filter(|x| any(x, g, iom, 0.5)).count(),
            gt_iom: g.iter().filter(|x| any(x, d, iom, 0.5)).count(),
            det_iou: d.iter().filter(|x| any(x, g, iou, 0.4999)).count(),
            gt_iou: g.iter().filter(|x| any(x, d, iou, 0.4999)).count(),
            one: one_to_one(d, g),
        }
    }

    fn add(&mut self, o: Match) {
        self.det += o.det;
        self.gt += o.gt;
        self.det_iom += o.det_iom;
        self.gt_iom += o.gt_iom;
        self.det_iou += o.det_iou;
        self.gt_iou += o.gt_iou;
        self.one += o.one;
    }

    /// F1 of one-to-one matching (the criterion settings are chosen by).
    fn f1_one_to_one(&self) -> f64 {
        let (p, r) = (ratio(self.one, self.det), ratio(self.one, self.gt));
        if p + r > 0.0 {
            2.0 * p * r / (p + r)
        } else {
            0.0
        }
    }

    fn json(&self) -> Value {
        json!({
            "detected": self.det, "labelled": self.gt,
            "precision_iom": ratio(self.det_iom, self.det), "recall_iom": ratio(self.gt_iom, self.gt),
            "precision_iom_one_to_one": ratio(self.one, self.det), "recall_iom_one_to_one": ratio(self.one, self.gt),
            "precision_iou": ratio(self.det_iou, self.det), "recall_iou": ratio(self.gt_iou, self.gt),
        })
    }
}

/// The settings tried by leave-one-recording-out: the segmenter's cost of an
/// interval (seconds of periodic motion) and its merge ratio. The product's
/// defaults are one of them.
fn candidates() -> Vec<(String, Params)> {
    let mut out = Vec::new();
    for penalty in [0.25, 0.5, 1.0] {
        for merge in [0.5, 0.6, 0.7, 0.8, 0.9, 1.0, f64::INFINITY] {
            let mut p = Params::default();
            p.count.segment.interval_penalty_s = penalty;
            p.count.segment.merge_ratio = if merge.is_finite() { merge } else { 1e9 };
            let name = format!(
                "interval_penalty_s {penalty}, merge_ratio {}",
                if merge.is_finite() {
                    merge.to_string()
                } else {
                    "off".into()
                }
            );
            out.push((name, p));
        }
    }
    out
}

/// Intervals the product reports for a feature track.
fn product_intervals(
    track: &mp_geom::Track,
    params: &Params,
) -> anyhow::Result<Vec<(usize, usize)>> {
    let c = mp_pipeline::count(track, None, params)?;
    Ok(c.intervals
        .iter()
        .map(|i| (i.start_frame, i.end_frame))
        .collect())
}

pub fn eval_cmu(files: &[PathBuf]) -> anyhow::Result<Value> {
    let recs: Vec<(String, CmuFeatures)> = files
        .iter()
        .map(|f| {
            let name = f
                .file_name()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default();
            CmuFeatures::open(f)
                .with_context(|| format!("{}", f.display()))
                .map(|c| (name, c))
        })
        .collect::<anyhow::Result<_>>()?;
    let labels: Vec<Vec<(usize, usize)>> = recs
        .iter()
        .map(|(_, c)| blocks(&c.labels).iter().map(|b| (b.1, b.2)).collect())
        .collect();
    // Every candidate setting on every recording.
    let cands = candidates();
    let mut table: Vec<Vec<Match>> = Vec::new();
    for (_, p) in &cands {
        let mut row = Vec::new();
        for ((_, c), g) in recs.iter().zip(&labels) {
            row.push(Match::of(&product_intervals(&c.track, p)?, g));
        }
        table.push(row);
    }
    // Leave one recording out: choose on the others (one-to-one F1, the first
    // candidate on ties), score the one left out.
    let mut loro = Match::default();
    let mut folds = Vec::new();
    for (k, (name, _)) in recs.iter().enumerate() {
        let mut best = (f64::NEG_INFINITY, 0usize);
        for (ci, row) in table.iter().enumerate() {
            let mut m = Match::default();
            for (ri, x) in row.iter().enumerate() {
                if ri != k {
                    m.add(*x);
                }
            }
            if m.f1_one_to_one() > best.0 + 1e-12 {
                best = (m.f1_one_to_one(), ci);
            }
        }
        let held = table[best.1][k];
        loro.add(held);
        folds.push(json!({"left_out": name, "chosen": cands[best.1].0, "train_f1_one_to_one": best.0, "left_out_figures": held.json()}));
    }
    // The product's defaults (in-sample), the raw segmenter and the loops.
    let defaults = Params::default();
    let default_idx = cands.iter().position(|(_, p)| p.count == defaults.count);
    let mut product = Match::default();
    let mut seg = Match::default();
    let mut loops = Match::default();
    let mut by_file = Map::new();
    for ((name, c), g) in recs.iter().zip(&labels) {
        let d = product_intervals(&c.track, &defaults)?;
        let m = Match::of(&d, g);
        product.add(m);
        let segs = segment_repetitions(&c.track, &IntervalParams::default())?;
        let ds: Vec<(usize, usize)> = segs.iter().map(|s| (s.start_frame, s.end_frame)).collect();
        seg.add(Match::of(&ds, g));
        let an = mp_pipeline::analyse_track(&c.track, None, &defaults)?;
        let dl: Vec<(usize, usize)> = an
            .intervals
            .iter()
            .map(|i| (i.start_frame, i.end_frame))
            .collect();
        loops.add(Match::of(&dl, g));
        let blocks = blocks(&c.labels);
        by_file.insert(name.clone(), json!({
            "frames": c.track.n_frames(),
            "detected": d.iter().map(|x| json!({"start_frame": x.0, "end_frame": x.1})).collect::<Vec<_>>(),
            "labelled": blocks.iter().map(|b| json!({"label": c.action_names.get((b.0 - 1).max(0) as usize), "start_frame": b.1, "end_frame": b.2})).collect::<Vec<_>>(),
            "figures": m.json(),
        }));
    }
    let mut top = product.json();
    if let Value::Object(m) = &mut top {
        m.insert("kind".into(), json!("cmu_mocap6_features"));
        m.insert("method".into(), json!("mp_pipeline::count with Params::default() (the intervals mp run and mp loops report); top-level figures are in-sample: the defaults are one of the candidates below"));
        m.insert(
            "default_candidate".into(),
            json!(default_idx.map(|i| cands[i].0.clone())),
        );
        m.insert("leave_one_recording_out".into(), json!({
            "definition": "for each recording, the candidate with the best one-to-one F1 (IoM > 0.5) on the other recordings is chosen and scored on the one left out; the figures are summed over the left-out recordings",
            "candidates": cands.iter().map(|c| c.0.clone()).collect::<Vec<_>>(),
            "folds": folds,
            "left_out": loro.json(),
        }));
        m.insert("segmenter".into(), json!({"method": "mp_abstract::segment_repetitions with IntervalParams::default()", "figures": seg.json()}));
        m.insert(
            "loops".into(),
            json!({"method": "loops of the abstract program", "figures": loops.json()}),
        );
        m.insert("matching_definition".into(), json!("precision_iom/recall_iom: a detection (label) counts when it overlaps any label (detection) with IoM > 0.5; *_one_to_one: greedy one-to-one matching by IoM (each detection and each label used once); *_iou: any match with IoU ≥ 0.5"));
        m.insert("by_file".into(), Value::Object(by_file));
    }
    Ok(top)
}
