//! `cargo xtask eval concrete --compare-continuity`: the product's programs
//! with independently fitted segments and with shared boundary poses (C0),
//! per action.

use std::collections::BTreeMap;
use std::time::Instant;

use anyhow::Context;
use indicatif::ProgressBar;
use mp_concrete::{Continuity, ProgramStats};
use mp_geom::PennAction;
use rayon::prelude::*;
use serde_json::{json, Value};

use super::{fit, mean, num, EvalConcreteArgs};
use crate::table::{Align::Left, Align::Right, Table};

/// One clip under one continuity: its action, the program's stats, and the factor to 512-px pixels.
type ContinuityRow = (String, ProgramStats, f64);

fn continuity_clip(
    pa: &PennAction,
    i: usize,
    params: &mp_pipeline::Params,
) -> anyhow::Result<ContinuityRow> {
    let info = pa.clip_info(i)?;
    let track = pa.clip(i)?;
    let frame_px = info.height_px.max(info.width_px) as f64;
    let program = fit(&track, frame_px, params)?;
    Ok((
        info.action.clone(),
        program.stats(&track)?,
        512.0 / frame_px,
    ))
}

/// `--compare-continuity`: the product's programs with and without shared boundary poses.
pub(super) fn compare_continuity(
    a: &EvalConcreteArgs,
    pa: &PennAction,
    clips: &[usize],
    path: &std::path::Path,
    base: &mp_pipeline::Params,
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let modes = [Continuity::None, Continuity::C0];
    let work: Vec<(usize, usize)> = (0..modes.len())
        .flat_map(|m| clips.iter().map(move |&c| (m, c)))
        .collect();
    let bar = ProgressBar::new(work.len() as u64);
    let results: Vec<(usize, anyhow::Result<ContinuityRow>)> = work
        .par_iter()
        .map(|&(m, c)| {
            let mut p = base.clone();
            p.analysis.synth.continuity = modes[m];
            let r = continuity_clip(pa, c, &p);
            bar.inc(1);
            (m, r)
        })
        .collect();
    bar.finish();
    let wall = t0.elapsed().as_secs_f64();
    let mut failed = 0usize;
    // (mode, action) → per-clip rows
    let mut rows: BTreeMap<(usize, String), Vec<(ProgramStats, f64)>> = BTreeMap::new();
    for (m, r) in results {
        match r {
            Ok((act, st, to512)) => {
                rows.entry((m, "overall".into()))
                    .or_default()
                    .push((st.clone(), to512));
                rows.entry((m, act)).or_default().push((st, to512));
            }
            Err(_) => failed += 1,
        }
    }
    let summarise = |rs: &[(ProgramStats, f64)]| -> Value {
        let prog: usize = rs.iter().map(|r| r.0.params_program).sum();
        let numbers: usize = rs.iter().map(|r| r.0.numbers_program).sum();
        let raw: usize = rs.iter().map(|r| r.0.params_raw).sum();
        let ratio = |x: usize| {
            if raw > 0 {
                x as f64 / raw as f64
            } else {
                f64::NAN
            }
        };
        json!({
            "clips": rs.len(),
            "kd_px_512": mean(rs.iter().map(|r| r.0.kd * r.1)),
            "params_ratio": ratio(prog),
            "numbers_ratio": ratio(numbers),
            "max_jump_raw_px_512": mean(rs.iter().map(|r| r.0.max_jump_raw * r.1)),
            "max_jump_program_px_512": mean(rs.iter().map(|r| r.0.max_jump_program * r.1)),
            "clips_program_jump_above_raw": rs.iter().filter(|r| r.0.max_jump_program > r.0.max_jump_raw).count(),
        })
    };
    let mut by_action = serde_json::Map::new();
    let mut table = Table::new([
        "action",
        "clips",
        "continuity",
        "KD px@512",
        "params ratio (numbers written)",
        "max jump raw / program (px@512)",
        "clips with program jump > raw",
    ])
    .align([Left, Right, Left, Right, Right, Right, Right]);
    let mut names: Vec<String> = rows.keys().map(|k| k.1.clone()).collect();
    names.sort();
    names.dedup();
    names.retain(|n| n != "overall");
    names.push("overall".into());
    for name in &names {
        let mut entry = serde_json::Map::new();
        for (m, mode) in modes.iter().enumerate() {
            let Some(rs) = rows.get(&(m, name.clone())) else {
                continue;
            };
            let v = summarise(rs);
            table.row([
                name.clone(),
                num(&v, &["clips"]).to_string(),
                mode.to_string(),
                format!("{:.2}", num(&v, &["kd_px_512"])),
                format!(
                    "{:.3} ({:.3})",
                    num(&v, &["params_ratio"]),
                    num(&v, &["numbers_ratio"])
                ),
                format!(
                    "{:.1} / {:.1}",
                    num(&v, &["max_jump_raw_px_512"]),
                    num(&v, &["max_jump_program_px_512"])
                ),
                num(&v, &["clips_program_jump_above_raw"]).to_string(),
            ]);
            entry.insert(mode.to_string(), v);
        }
        by_action.insert(name.clone(), Value::Object(entry));
    }
    let md = table.markdown();
    let report = json!({
        "data": path.display().to_string(),
        "split": format!("{:?}", a.split),
        "what": "the product's programs (mp_pipeline::concrete_program, Params::default() with the options given) with independently fitted segments and with shared boundary poses (C0); KD and max adjacent-frame jump in px at 512 px (means over clips), parameter ratio Σ program / Σ raw",
        "params": serde_json::to_value(&base.analysis.synth)?,
        "by_action": by_action,
        "failed": failed,
        "wall_seconds": wall,
        "threads": rayon::current_num_threads(),
    });
    mp_geom::write_atomic(&a.out, serde_json::to_string_pretty(&report)?.as_bytes())
        .with_context(|| format!("writing {}", a.out.display()))?;
    println!("{md}");
    if let Some(m) = &a.markdown {
        std::fs::write(m, &md).with_context(|| format!("writing {}", m.display()))?;
    }
    eprintln!(
        "{} clips × 2 ({failed} failed) in {wall:.1} s → {}",
        clips.len(),
        a.out.display()
    );
    Ok(())
}
