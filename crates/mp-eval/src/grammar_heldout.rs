//! Held-out part of `cargo xtask eval grammar`: does the grammar generalise?
//!
//! For every group of takes (the three CMU salsa takes of a dancer; the
//! three CMU exercise recordings) and every rotation, symbols and a grammar
//! are learned on all takes but one (joined in name order) with the same
//! library calls and defaults as `mp grammar symbols` / `mp grammar learn`;
//! the held-out take is labelled with the learned symbols
//! (`SymbolsFile::assign`, as `mp grammar symbols --model`) and its symbol
//! string scored (`GrammarModel::score`, as `mp grammar score`): code length
//! in bits per symbol under the grammar (with escapes), the first-order FSM
//! and the unigram model of the training string, all with the default
//! smoothing. The training string's own code lengths (in-sample) are
//! reported beside them.

use std::path::Path;
use std::time::Instant;

use crate::grammar::ngram_overlap;
use anyhow::Context;
use mp_geom::CmuFeatures;
use mp_grammar::PoseDistanceParams;
use mp_grammar::ScoreParams;
use mp_grammar::{bvh_files, concat_tracks, read_motions, Motion};
use mp_grammar::{find_symbols, learn_grammar};
use serde_json::{json, Value};

use crate::grammar::{symbol_params, EvalGrammarArgs};
use crate::table::{Align::Left, Align::Right, Table};

/// A group of takes: one is held out at a time.
struct Group {
    name: String,
    takes: Vec<(String, Motion)>,
    features: bool,
}

fn stem(p: &Path) -> String {
    p.file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("?")
        .to_string()
}

fn groups(path: &Path, frame_step: usize) -> anyhow::Result<Vec<Group>> {
    let files = crate::grammar::feature_files(path)?;
    if !files.is_empty() {
        let mut takes = Vec::new();
        for f in files {
            let c = CmuFeatures::open(&f)?;
            takes.push((
                stem(&f).trim_end_matches("_features10fps.npz").to_string(),
                Motion {
                    track: c.track,
                    bvh: None,
                    paths: vec![f.clone()],
                    frame_step: 1,
                },
            ));
        }
        return Ok(vec![Group {
            name: "cmu exercise".into(),
            takes,
            features: true,
        }]);
    }
    if !path.is_dir() {
        return Ok(Vec::new());
    }
    let mut out: Vec<Group> = Vec::new();
    for f in bvh_files(path)? {
        let dancer = stem(&f).split('_').next().unwrap_or("").to_string();
        let take = stem(&f).trim_end_matches(".bvh").to_string();
        let m = read_motions(std::slice::from_ref(&f), frame_step)?;
        match out.iter_mut().find(|g| g.name == format!("salsa {dancer}")) {
            Some(g) => g.takes.push((take, m)),
            None => out.push(Group {
                name: format!("salsa {dancer}"),
                takes: vec![(take, m)],
                features: false,
            }),
        }
    }
    Ok(out)
}

/// The takes other than `held`, joined.
fn training_motion(g: &Group, held: usize) -> anyhow::Result<Motion> {
    let parts: Vec<&Motion> = g
        .takes
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != held)
        .map(|(_, (_, m))| m)
        .collect();
    let tracks: Vec<_> = parts.iter().map(|m| m.track.clone()).collect();
    Ok(Motion {
        track: concat_tracks(&tracks)?,
        bvh: None,
        paths: parts.iter().flat_map(|m| m.paths.clone()).collect(),
        frame_step: parts.first().map_or(1, |m| m.frame_step),
    })
}

fn one(g: &Group, held: usize, k: usize, a: &EvalGrammarArgs) -> anyhow::Result<Value> {
    let t0 = Instant::now();
    let train = training_motion(g, held)?;
    let (held_name, test) = &g.takes[held];
    let sym = find_symbols(
        &train,
        &PoseDistanceParams::default(),
        &symbol_params(g.features, k, a.seed),
    )
    .with_context(|| format!("{}: symbols without {held_name}, K = {k}", g.name))?;
    let mut pp = mp_grammar::PartitionParams {
        seed: a.seed,
        ..Default::default()
    };
    pp.abl.seed = a.seed;
    let model = learn_grammar(&sym, &pp)?;
    let assigned = sym.assign(&train, test)?;
    let string = assigned.string();
    let sp = ScoreParams::default();
    let s = model.score(&string, &sp)?;
    let train_string = sym.string();
    let s_in = model.score(&train_string, &sp)?;
    let held_usize: Vec<usize> = string.iter().map(|&x| x as usize).collect();
    let train_usize: Vec<usize> = train_string.iter().map(|&x| x as usize).collect();
    let seen = |n: usize| ngram_overlap(&held_usize, &train_usize, n);
    Ok(json!({
        "group": g.name,
        "held_out": held_name,
        "k": k,
        "train_frames": train.track.n_frames(),
        "held_out_frames": test.track.n_frames(),
        "train_segments": train_string.len(),
        "held_out_segments": string.len(),
        "held_out_string": assigned.text,
        "held_out_e_prime": assigned.symbols.quality.e_prime,
        "held_out_ngrams_in_training": {"2": seen(2), "3": seen(3)},
        "sentences": model.sentences.len(),
        "nonterminals": model.grammar.n_nonterminals(),
        "rules": model.grammar.n_rules(),
        "held_out_score": s,
        "held_out_parse": s.parse_text(&model.grammar),
        "in_sample_score": s_in,
        "seconds": t0.elapsed().as_secs_f64(),
    }))
}

/// Runs every rotation of every group found under `a.data`.
pub fn run(a: &EvalGrammarArgs) -> anyhow::Result<Vec<Value>> {
    let mut rows = Vec::new();
    for d in &a.data {
        for g in groups(d, a.frame_step)? {
            if g.takes.len() < 2 {
                continue;
            }
            let ks = if g.features { &a.k_features } else { &a.k_bvh };
            for &k in ks {
                for held in 0..g.takes.len() {
                    let r = one(&g, held, k, a)?;
                    eprintln!(
                        "{} without {}, K = {k}: grammar {:.3}, FSM {:.3}, unigram {:.3} bits/symbol",
                        g.name,
                        r["held_out"].as_str().unwrap_or(""),
                        r["held_out_score"]["grammar"]["bits_per_symbol"]
                            .as_f64()
                            .unwrap_or(f64::NAN),
                        r["held_out_score"]["fsm"]["bits_per_symbol"]
                            .as_f64()
                            .unwrap_or(f64::NAN),
                        r["held_out_score"]["unigram"]["bits_per_symbol"]
                            .as_f64()
                            .unwrap_or(f64::NAN),
                    );
                    rows.push(r);
                }
            }
        }
    }
    Ok(rows)
}

fn bps(v: &Value, which: &str, model: &str) -> f64 {
    v[which][model]["bits_per_symbol"]
        .as_f64()
        .unwrap_or(f64::NAN)
}

/// The held-out tables as Markdown: one row per rotation, then the means
/// per group and K.
pub fn markdown(rows: &[Value]) -> String {
    let mut t = Table::new([
        "data",
        "held out",
        "K",
        "train / held-out segments",
        "2- / 3-grams seen",
        "sentences",
        "NT",
        "rules",
        "grammar",
        "FSM",
        "unigram",
        "in sentences",
        "in-sample grammar / FSM",
    ])
    .align([Left, Left].into_iter().chain([Right; 11]));
    for r in rows {
        let n = r["held_out_segments"].as_f64().unwrap_or(0.0);
        let inside = r["held_out_score"]["symbols_in_sentences"]
            .as_f64()
            .unwrap_or(0.0);
        t.row([
            r["group"].as_str().unwrap_or("").to_string(),
            r["held_out"].as_str().unwrap_or("").to_string(),
            r["k"].to_string(),
            format!("{} / {}", r["train_segments"], r["held_out_segments"]),
            format!(
                "{:.2} / {:.2}",
                r["held_out_ngrams_in_training"]["2"]
                    .as_f64()
                    .unwrap_or(f64::NAN),
                r["held_out_ngrams_in_training"]["3"]
                    .as_f64()
                    .unwrap_or(f64::NAN)
            ),
            r["sentences"].to_string(),
            r["nonterminals"].to_string(),
            r["rules"].to_string(),
            format!("{:.3}", bps(r, "held_out_score", "grammar")),
            format!("{:.3}", bps(r, "held_out_score", "fsm")),
            format!("{:.3}", bps(r, "held_out_score", "unigram")),
            format!("{:.0} %", 100.0 * inside / n.max(1.0)),
            format!(
                "{:.3} / {:.3}",
                bps(r, "in_sample_score", "grammar"),
                bps(r, "in_sample_score", "fsm")
            ),
        ]);
    }
    let mut s = t.markdown();
    s.push('\n');
    let mut t = Table::new([
        "data",
        "K",
        "rotations",
        "grammar (mean)",
        "FSM (mean)",
        "unigram (mean)",
        "grammar < FSM",
    ])
    .align([Left, Right, Right, Right, Right, Right, Right]);
    let mut keys: Vec<(String, u64)> = Vec::new();
    for r in rows {
        let key = (
            r["group"].as_str().unwrap_or("").to_string(),
            r["k"].as_u64().unwrap_or(0),
        );
        if !keys.contains(&key) {
            keys.push(key);
        }
    }
    for (g, k) in keys {
        let sel: Vec<&Value> = rows
            .iter()
            .filter(|r| r["group"].as_str() == Some(&g) && r["k"].as_u64() == Some(k))
            .collect();
        let m = |model: &str| {
            sel.iter()
                .map(|r| bps(r, "held_out_score", model))
                .sum::<f64>()
                / sel.len().max(1) as f64
        };
        let wins = sel
            .iter()
            .filter(|r| bps(r, "held_out_score", "grammar") < bps(r, "held_out_score", "fsm"))
            .count();
        t.row([
            g.clone(),
            k.to_string(),
            sel.len().to_string(),
            format!("{:.3}", m("grammar")),
            format!("{:.3}", m("fsm")),
            format!("{:.3}", m("unigram")),
            format!("{wins} of {}", sel.len()),
        ]);
    }
    s.push_str(&t.markdown());
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_tables_layout() {
        let row = json!({"group": "cmu", "held_out": "t1", "k": 4, "train_segments": 10,
            "held_out_segments": 5, "held_out_ngrams_in_training": {"2": 0.5, "3": 0.25},
            "sentences": 3, "nonterminals": 2, "rules": 6,
            "held_out_score": {"grammar": {"bits_per_symbol": 1.5}, "fsm": {"bits_per_symbol": 2.0},
                "unigram": {"bits_per_symbol": 3.0}, "symbols_in_sentences": 4},
            "in_sample_score": {"grammar": {"bits_per_symbol": 1.0}, "fsm": {"bits_per_symbol": 1.25}}});
        assert_eq!(
            markdown(&[row]),
            "| data | held out | K | train / held-out segments | 2- / 3-grams seen | sentences | NT | rules | grammar | FSM | unigram | in sentences | in-sample grammar / FSM |\n\
             |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n\
             | cmu | t1 | 4 | 10 / 5 | 0.50 / 0.25 | 3 | 2 | 6 | 1.500 | 2.000 | 3.000 | 80 % | 1.000 / 1.250 |\n\
             \n\
             | data | K | rotations | grammar (mean) | FSM (mean) | unigram (mean) | grammar < FSM |\n\
             |---|---:|---:|---:|---:|---:|---:|\n\
             | cmu | 4 | 1 | 1.500 | 2.000 | 3.000 | 1 of 1 |\n"
        );
    }
}
