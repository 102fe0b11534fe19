//! `cargo xtask eval grammar --data PATH… --out FILE.json`: motion grammars
//! (Park, Lee & Lee 2011) on real motion.
//!
//! Each `--data` is one of:
//! * CMU mocap6 exercise features (`*_features10fps.npz`, a file or a
//!   folder of them; 12 joint-angle channels at 10 fps with a hand label per
//!   frame): one motion per file;
//! * a folder of BVH takes (`cmu_salsa_bvh`): one motion per performer (the
//!   takes whose names share the prefix before the first `_`, joined in name
//!   order), every `--frame-step`-th frame kept (default 4: 120 → 30 fps).
//!
//! For every motion and every K: symbols (GA + SA), the sentence partition
//! (MDL) and ABL grammar, then for several seeds a grammar synthesis of at
//! least as many segments as the training string and a finite-state-machine
//! synthesis of exactly as many, both stitched the same way. Reported:
//!
//! * symbols: segments, `F`, and for labelled motions purity and NMI of the
//!   per-frame symbols against the per-frame labels;
//! * grammar: sentences, nonterminals, rules, description length (and that
//!   of the whole string as one sentence), wall times;
//! * synthesis: seam pose distance after blending (mean and p90 over all
//!   seams of all seeds) and before blending (the selection gaps), in the
//!   pose-distance units of the symbols (root-relative RMS joint distance
//!   over body size for BVH; Euclidean distance of the angle features);
//!   block structure: the fraction of the synthesised string's n-grams
//!   (n = 2, 3, 4) that occur in the training string, the mean run length of
//!   equal symbols, the fraction of derived sentences that are not training
//!   sentences (grammar only) and, for labelled motions, the mean run length
//!   of the *labels* of the chosen source segments (how long the synthesis
//!   stays in one exercise), in segments.
//!
//! Then, unless `--no-heldout`, the held-out evaluation
//! (`grammar_heldout.rs`): symbols and grammar learned on
//! all takes of a group but one, the held-out take labelled with the learned
//! symbols and scored in bits per symbol under the grammar, the FSM and a
//! unigram model.

use crate::stats::mean;
use crate::table::{Align::Left, Align::Right, Table};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context};
use clap::Args;
use mp_geom::CmuFeatures;
use mp_grammar::score_partition;
use mp_grammar::{bvh_files, read_motions, Motion};
use mp_grammar::{find_symbols, learn_grammar, GrammarModel};
use mp_grammar::{symbol_name, DeriveParams, Fsm, FsmWeighting, PoseDistanceParams, SymbolParams};
use mp_grammar::{StitchParams, SynthesizedMotion};
use serde_json::{json, Value};

#[path = "grammar_heldout.rs"]
mod heldout;

/// Arguments of `cargo xtask eval grammar`.
#[derive(Args, Debug)]
pub struct EvalGrammarArgs {
    /// CMU features (file or folder) or a folder of BVH takes; repeatable.
    #[arg(long, required = true, num_args = 1..)]
    pub data: Vec<PathBuf>,
    /// Output JSON.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write the tables as Markdown.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// Symbol counts K for BVH motions.
    #[arg(long, value_delimiter = ',', default_value = "12,20,30")]
    pub k_bvh: Vec<usize>,
    /// Symbol counts K for CMU feature motions.
    #[arg(long, value_delimiter = ',', default_value = "6,12")]
    pub k_features: Vec<usize>,
    /// Keep every N-th BVH frame (4: 120 → 30 fps).
    #[arg(long, default_value_t = 4)]
    pub frame_step: usize,
    /// Synthesis seeds per motion and K.
    #[arg(long, default_value_t = 10)]
    pub seeds: u64,
    /// Seed of symbol identification and of the partition search.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Skip the held-out evaluation (learn on all takes but one, score the one left out).
    #[arg(long)]
    pub no_heldout: bool,
}

struct Input {
    name: String,
    motion: Motion,
    labels: Option<Vec<i64>>,
    features: bool,
}

/// The CMU feature files (`*_features10fps.npz`) at `path` (a folder, sorted
/// by name, or one file); empty when there are none.
pub(crate) fn feature_files(path: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let is_features = |p: &Path| {
        p.file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.ends_with("_features10fps.npz"))
    };
    Ok(if path.is_dir() {
        let mut v: Vec<PathBuf> = std::fs::read_dir(path)
            .with_context(|| path.display().to_string())?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| is_features(p))
            .collect();
        v.sort();
        v
    } else if is_features(path) {
        vec![path.to_path_buf()]
    } else {
        Vec::new()
    })
}

fn inputs(path: &Path, frame_step: usize) -> anyhow::Result<Vec<Input>> {
    let mut out = Vec::new();
    let feature_files = feature_files(path)?;
    if !feature_files.is_empty() {
        for f in feature_files {
            let c = CmuFeatures::open(&f)?;
            let name = f
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or("?")
                .trim_end_matches("_features10fps.npz")
                .to_string();
            out.push(Input {
                name: format!("cmu {name}"),
                motion: Motion {
                    track: c.track,
                    bvh: None,
                    paths: vec![f.clone()],
                    frame_step: 1,
                },
                labels: Some(c.labels),
                features: true,
            });
        }
        return Ok(out);
    }
    if path.is_dir() {
        let files = bvh_files(path)?;
        let mut groups: Vec<(String, Vec<PathBuf>)> = Vec::new();
        for f in files {
            let stem = f
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or("")
                .split('_')
                .next()
                .unwrap_or("")
                .to_string();
            match groups.iter_mut().find(|(g, _)| *g == stem) {
                Some((_, v)) => v.push(f),
                None => groups.push((stem, vec![f])),
            }
        }
        for (g, files) in groups {
            let motion = read_motions(&files, frame_step)?;
            out.push(Input {
                name: format!("salsa {g} ({} takes)", files.len()),
                motion,
                labels: None,
                features: false,
            });
        }
        return Ok(out);
    }
    bail!(
        "{}: neither CMU features (*_features10fps.npz) nor a folder of BVH files",
        path.display()
    )
}

/// Purity and NMI (arithmetic normalisation) of `a` against `b`.
fn purity_nmi(a: &[usize], b: &[i64]) -> (f64, f64) {
    let n = a.len().min(b.len());
    if n == 0 {
        return (0.0, 0.0);
    }
    let mut joint: HashMap<(usize, i64), f64> = HashMap::new();
    let mut pa: HashMap<usize, f64> = HashMap::new();
    let mut pb: HashMap<i64, f64> = HashMap::new();
    for i in 0..n {
        *joint.entry((a[i], b[i])).or_default() += 1.0;
        *pa.entry(a[i]).or_default() += 1.0;
        *pb.entry(b[i]).or_default() += 1.0;
    }
    let nf = n as f64;
    let mut best: HashMap<usize, f64> = HashMap::new();
    for (&(x, _), &c) in &joint {
        let e = best.entry(x).or_default();
        *e = e.max(c);
    }
    let purity = best.values().sum::<f64>() / nf;
    let h =
        |m: &dyn Fn() -> Vec<f64>| -> f64 { m().iter().map(|&c| -(c / nf) * (c / nf).ln()).sum() };
    let ha = h(&|| pa.values().copied().collect());
    let hb = h(&|| pb.values().copied().collect());
    let mut mi = 0.0;
    for (&(x, y), &c) in &joint {
        let pxy = c / nf;
        mi += pxy * (pxy / ((pa[&x] / nf) * (pb[&y] / nf))).ln();
    }
    let nmi = if ha + hb > 0.0 {
        2.0 * mi / (ha + hb)
    } else {
        0.0
    };
    (purity, nmi)
}

fn p90(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let i = ((s.len() as f64 * 0.9).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}

/// Majority label of each source segment.
fn segment_labels(m: &GrammarModel, labels: &[i64]) -> Vec<i64> {
    m.symbols
        .segments
        .iter()
        .map(|s| {
            let mut c: HashMap<i64, usize> = HashMap::new();
            for &l in labels.iter().take(s.end).skip(s.start) {
                *c.entry(l).or_default() += 1;
            }
            c.into_iter()
                .max_by_key(|&(l, n)| (n, -l))
                .map_or(0, |(l, _)| l)
        })
        .collect()
}

fn run_len_i64(v: &[i64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.len() as f64 / (1 + v.windows(2).filter(|w| w[0] != w[1]).count()) as f64
}

#[derive(Default)]
struct Acc {
    seams: Vec<f64>,
    gaps: Vec<f64>,
    ngram: [Vec<f64>; 3],
    run: Vec<f64>,
    label_run: Vec<f64>,
    novel: Vec<f64>,
    segments: Vec<f64>,
    frames: Vec<f64>,
}

impl Acc {
    fn add(
        &mut self,
        s: &SynthesizedMotion,
        seams: Vec<f64>,
        gaps: Vec<f64>,
        train: &[usize],
        seg_labels: Option<&[i64]>,
    ) {
        self.seams.extend(seams);
        self.gaps.extend(gaps);
        for (i, n) in [2usize, 3, 4].iter().enumerate() {
            self.ngram[i].push(ngram_overlap(&s.symbols, train, *n));
        }
        self.run.push(mean_run_length(&s.symbols));
        if let Some(l) = seg_labels {
            let v: Vec<i64> = s.pieces.iter().map(|p| l[p.segment]).collect();
            self.label_run.push(run_len_i64(&v));
        }
        self.segments.push(s.pieces.len() as f64);
        self.frames.push(s.n_frames() as f64);
    }
    fn json(&self) -> Value {
        json!({
            "segments_mean": mean(&self.segments),
            "frames_mean": mean(&self.frames),
            "seam_distance": {"mean": mean(&self.seams), "p90": p90(&self.seams), "n": self.seams.len()},
            "seam_gap_before_blending": {"mean": mean(&self.gaps), "p90": p90(&self.gaps)},
            "ngram_in_training": {"2": mean(&self.ngram[0]), "3": mean(&self.ngram[1]), "4": mean(&self.ngram[2])},
            "symbol_run_length": mean(&self.run),
            "label_run_length_segments": if self.label_run.is_empty() { Value::Null } else { json!(mean(&self.label_run)) },
            "novel_sentences": if self.novel.is_empty() { Value::Null } else { json!(mean(&self.novel)) },
        })
    }
}

pub(crate) fn symbol_params(features: bool, k: usize, seed: u64) -> SymbolParams {
    let mut p = SymbolParams {
        k,
        seed,
        ..Default::default()
    };
    if features {
        // 10 fps: candidate cuts every 0.5 s, segments 0.3–4 s.
        p.candidate_step_frames = 5;
        p.min_segment_frames = 3;
        p.max_segment_frames = 40;
        p.sa.initial_step_frames = Some(2);
    }
    p
}

fn eval_one(input: &Input, k: usize, a: &EvalGrammarArgs) -> anyhow::Result<Value> {
    let t0 = Instant::now();
    let sp = symbol_params(input.features, k, a.seed);
    let sym = find_symbols(&input.motion, &PoseDistanceParams::default(), &sp)
        .with_context(|| format!("{}: symbols, K = {k}", input.name))?;
    let t_sym = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let mut pp = mp_grammar::PartitionParams {
        seed: a.seed,
        ..Default::default()
    };
    pp.abl.seed = a.seed;
    let model = learn_grammar(&sym, &pp)?;
    let t_gram = t1.elapsed().as_secs_f64();
    let train = model.training_string();
    let train_u32: Vec<u32> = train.iter().map(|&s| s as u32).collect();
    let terminals: Vec<String> = (0..k).map(symbol_name).collect();
    let single = score_partition(&train_u32, &[], &terminals, &pp.abl)?;

    let (purity, nmi) = match &input.labels {
        Some(l) => {
            let (p, n) = purity_nmi(&model.symbols.frame_symbols(), l);
            (json!(p), json!(n))
        }
        None => (Value::Null, Value::Null),
    };
    let seg_labels = input.labels.as_ref().map(|l| segment_labels(&model, l));

    // Synthesis.
    let t2 = Instant::now();
    let st = model.stitcher(&input.motion, &StitchParams::default())?;
    let derive = DeriveParams::default();
    let fsm = Fsm::from_symbols(&train_u32, k, FsmWeighting::Counts)?;
    let training_sentences: std::collections::HashSet<&Vec<u32>> = model.sentences.iter().collect();
    let mut g_acc = Acc::default();
    let mut f_acc = Acc::default();
    for seed in 0..a.seeds {
        let g = st.synthesize(&model.grammar, &derive, train.len(), seed)?;
        let gaps = st.gaps(&g.pieces.iter().map(|p| p.segment).collect::<Vec<_>>());
        g_acc.add(
            &g,
            st.seam_distances(&g)?,
            gaps,
            &train,
            seg_labels.as_deref(),
        );
        if let Some(d) = &g.derivation {
            let novel = d
                .sentences
                .iter()
                .filter(|t| !training_sentences.contains(&t.yield_terminals()))
                .count() as f64
                / d.sentences.len().max(1) as f64;
            g_acc.novel.push(novel);
        }
        let f = st.synthesize_fsm(&fsm, g.pieces.len(), seed)?;
        let gaps = st.gaps(&f.pieces.iter().map(|p| p.segment).collect::<Vec<_>>());
        f_acc.add(
            &f,
            st.seam_distances(&f)?,
            gaps,
            &train,
            seg_labels.as_deref(),
        );
    }
    let t_synth = t2.elapsed().as_secs_f64();
    let feat = st.features();
    let steps: Vec<f64> = (1..feat.n_frames())
        .filter_map(|t| feat.pose_distance(t - 1, t).ok())
        .collect();
    let dl = model.description_length;
    eprintln!(
        "{} K={k}: {} segments, {} sentences, {} NT, {} rules, DL {:.0} ({:.1}+{:.1}+{:.1} s)",
        input.name,
        train.len(),
        model.sentences.len(),
        model.grammar.n_nonterminals(),
        model.grammar.n_rules(),
        dl.total_bits,
        t_sym,
        t_gram,
        t_synth
    );
    Ok(json!({
        "name": input.name,
        "paths": model.source.paths,
        "kind": model.source.kind,
        "frames": model.source.n_frames,
        "fps": model.source.fps,
        "k": k,
        "symbols": {
            "segments": train.len(),
            "f": model.symbols.quality.f,
            "r": model.symbols.quality.r,
            "e_prime": model.symbols.quality.e_prime,
            "purity": purity,
            "nmi": nmi,
            "string": model.symbols.text(),
            "symbol_run_length": mean_run_length(&train),
            "label_run_length_segments": seg_labels.as_ref().map(|l| run_len_i64(l)),
            "stats": model.symbols.stats,
        },
        "grammar": {
            "sentences": model.sentences.len(),
            "mean_sentence_len": train.len() as f64 / model.sentences.len().max(1) as f64,
            "nonterminals": model.grammar.n_nonterminals(),
            "rules": model.grammar.n_rules(),
            "dl_bits": dl.total_bits,
            "grammar_bits": dl.grammar_bits,
            "data_bits": dl.data_bits,
            "dl_single_sentence_bits": single.dl.total_bits,
            "rules_text": model.rules_text(),
        },
        "synthesis": {
            "source_frame_step_distance_mean": mean(&steps),
            "grammar": g_acc.json(),
            "fsm": f_acc.json(),
        },
        "seconds": {"symbols": t_sym, "grammar": t_gram, "synthesis": t_synth},
    }))
}

fn f(v: &Value) -> String {
    match v.as_f64() {
        Some(x) => {
            if x.abs() >= 100.0 {
                format!("{x:.0}")
            } else {
                format!("{x:.3}")
            }
        }
        None => "–".into(),
    }
}

fn markdown(rows: &[Value]) -> String {
    let mut t = Table::new([
        "motion",
        "frames @ fps",
        "K",
        "segments",
        "F",
        "purity",
        "NMI",
        "sentences",
        "NT",
        "rules",
        "DL bits (one sentence)",
        "d(t, t+1) source",
        "time sym / gram / synth s",
    ])
    .align([Left].into_iter().chain([Right; 12]));
    for r in rows {
        t.row([
            r["name"].as_str().unwrap_or("").to_string(),
            format!("{} @ {}", r["frames"], f(&r["fps"])),
            r["k"].to_string(),
            r["symbols"]["segments"].to_string(),
            f(&r["symbols"]["f"]),
            f(&r["symbols"]["purity"]),
            f(&r["symbols"]["nmi"]),
            r["grammar"]["sentences"].to_string(),
            r["grammar"]["nonterminals"].to_string(),
            r["grammar"]["rules"].to_string(),
            format!(
                "{} ({})",
                f(&r["grammar"]["dl_bits"]),
                f(&r["grammar"]["dl_single_sentence_bits"])
            ),
            f(&r["synthesis"]["source_frame_step_distance_mean"]),
            format!(
                "{:.1} / {:.1} / {:.1}",
                r["seconds"]["symbols"].as_f64().unwrap_or(0.0),
                r["seconds"]["grammar"].as_f64().unwrap_or(0.0),
                r["seconds"]["synthesis"].as_f64().unwrap_or(0.0)
            ),
        ]);
    }
    let mut s = t.markdown();
    s.push('\n');
    let mut t = Table::new([
        "motion",
        "K",
        "method",
        "segments",
        "seam mean",
        "seam p90",
        "gap mean (unblended)",
        "gap p90",
        "2-gram",
        "3-gram",
        "4-gram",
        "symbol run (source)",
        "label run (source)",
        "novel sentences",
    ])
    .align([Left, Right, Left].into_iter().chain([Right; 11]));
    for r in rows {
        for m in ["grammar", "fsm"] {
            let x = &r["synthesis"][m];
            t.row([
                r["name"].as_str().unwrap_or("").to_string(),
                r["k"].to_string(),
                m.to_string(),
                format!("{:.1}", x["segments_mean"].as_f64().unwrap_or(0.0)),
                f(&x["seam_distance"]["mean"]),
                f(&x["seam_distance"]["p90"]),
                f(&x["seam_gap_before_blending"]["mean"]),
                f(&x["seam_gap_before_blending"]["p90"]),
                f(&x["ngram_in_training"]["2"]),
                f(&x["ngram_in_training"]["3"]),
                f(&x["ngram_in_training"]["4"]),
                format!(
                    "{} ({})",
                    f(&x["symbol_run_length"]),
                    f(&r["symbols"]["symbol_run_length"])
                ),
                format!(
                    "{} ({})",
                    f(&x["label_run_length_segments"]),
                    f(&r["symbols"]["label_run_length_segments"])
                ),
                f(&x["novel_sentences"]),
            ]);
        }
    }
    s.push_str(&t.markdown());
    s
}

/// Runs the evaluation.
pub fn run(a: &EvalGrammarArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let mut rows = Vec::new();
    for d in &a.data {
        for input in inputs(d, a.frame_step)? {
            let ks = if input.features {
                &a.k_features
            } else {
                &a.k_bvh
            };
            for &k in ks {
                rows.push(eval_one(&input, k, a)?);
            }
        }
    }
    let heldout_rows = if a.no_heldout {
        Vec::new()
    } else {
        heldout::run(a)?
    };
    let report = json!({
        "heldout": heldout_rows,
        "data": a.data,
        "frame_step_bvh": a.frame_step,
        "seeds": a.seeds,
        "threads": rayon::current_num_threads(),
        "seconds_total": t0.elapsed().as_secs_f64(),
        "results": rows,
    });
    if let Some(dir) = a.out.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    mp_geom::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    let mut md = markdown(&rows);
    if !heldout_rows.is_empty() {
        md.push('\n');
        md.push_str(&heldout::markdown(&heldout_rows));
    }
    print!("{md}");
    if let Some(m) = &a.markdown {
        mp_geom::write_atomic(m, md.as_bytes())?;
    }
    eprintln!(
        "{} runs in {:.1} s; wrote {}",
        rows.len(),
        t0.elapsed().as_secs_f64(),
        a.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn purity_and_nmi() {
        let (p, n) = purity_nmi(&[0, 0, 1, 1], &[5, 5, 7, 7]);
        assert!((p - 1.0).abs() < 1e-12 && (n - 1.0).abs() < 1e-12);
        let (p, n) = purity_nmi(&[0, 1, 0, 1], &[5, 5, 7, 7]);
        assert!((p - 0.5).abs() < 1e-12 && n.abs() < 1e-12);
        assert_eq!(
            p90(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0]),
            9.0
        );
    }

    #[test]
    fn markdown_tables_layout() {
        let x = json!({"segments_mean": 4.0, "seam_distance": {"mean": 0.5, "p90": 1.0},
            "seam_gap_before_blending": {"mean": 2.0, "p90": 150.0},
            "ngram_in_training": {"2": 1.0, "3": 0.5, "4": null},
            "symbol_run_length": 1.5, "label_run_length_segments": 2.5, "novel_sentences": 0.25});
        let row = json!({"name": "walk", "frames": 100, "fps": 30.0, "k": 6,
            "symbols": {"segments": 12, "f": 0.9, "purity": 0.8, "nmi": 0.7,
                "symbol_run_length": 1.0, "label_run_length_segments": 2.0},
            "grammar": {"sentences": 3, "nonterminals": 2, "rules": 5, "dl_bits": 1234.5,
                "dl_single_sentence_bits": 99.0},
            "synthesis": {"source_frame_step_distance_mean": 0.125, "grammar": x.clone(), "fsm": x},
            "seconds": {"symbols": 1.25, "grammar": 0.5, "synthesis": 2.0}});
        let line = "| walk | 4.0 | 0.500 | 1.000 | 2.000 | 150 | 1.000 | 0.500 | – | 1.500 (1.000) | 2.500 (2.000) | 0.250 |";
        assert_eq!(
            markdown(&[row]),
            format!(
                "| motion | frames @ fps | K | segments | F | purity | NMI | sentences | NT | rules | DL bits (one sentence) | d(t, t+1) source | time sym / gram / synth s |\n\
                 |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n\
                 | walk | 100 @ 30.000 | 6 | 12 | 0.900 | 0.800 | 0.700 | 3 | 2 | 5 | 1234 (99.000) | 0.125 | 1.2 / 0.5 / 2.0 |\n\
                 \n\
                 | motion | K | method | segments | seam mean | seam p90 | gap mean (unblended) | gap p90 | 2-gram | 3-gram | 4-gram | symbol run (source) | label run (source) | novel sentences |\n\
                 |---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n\
                 {}\n{}\n",
                line.replacen("| walk | 4.0", "| walk | 6 | grammar | 4.0", 1),
                line.replacen("| walk | 4.0", "| walk | 6 | fsm | 4.0", 1)
            )
        );
    }
}

/// Fraction of the `n`-grams (windows of `n` consecutive symbols) of
/// `generated` that occur somewhere in `training` (1 when `generated` is
/// shorter than `n`).
pub fn ngram_overlap(generated: &[usize], training: &[usize], n: usize) -> f64 {
    if n == 0 || generated.len() < n {
        return 1.0;
    }
    let seen: std::collections::HashSet<&[usize]> = training.windows(n).collect();
    let w: Vec<&[usize]> = generated.windows(n).collect();
    w.iter().filter(|g| seen.contains(*g)).count() as f64 / w.len() as f64
}

/// Mean length of the runs of equal consecutive symbols (0 for an empty
/// string).
pub fn mean_run_length(symbols: &[usize]) -> f64 {
    if symbols.is_empty() {
        return 0.0;
    }
    let runs = 1 + symbols.windows(2).filter(|w| w[0] != w[1]).count();
    symbols.len() as f64 / runs as f64
}

#[cfg(test)]
mod structure_tests {
    use super::{mean_run_length, ngram_overlap};

    #[test]
    fn structure_measures() {
        assert_eq!(mean_run_length(&[1, 1, 2, 2, 2, 3]), 2.0);
        assert_eq!(mean_run_length(&[]), 0.0);
        assert_eq!(ngram_overlap(&[1, 2, 3], &[1, 2, 4], 2), 0.5);
        assert_eq!(ngram_overlap(&[1], &[1, 2], 2), 1.0);
    }
}
