//! `cargo xtask eval live --out FILE.json [--seed S] [--cases N]
//! [--confirm-periods A,B] [--min-confidence A,B]`: the online counter of
//! `mp live` ([`mp_live::OnlineCounter`] with [`LiveParams::default`]) fed
//! the keypoints of the synthetic cases of known count ([`crate::synth_reps`],
//! the validation set of `eval count --synthetic`) frame by frame, as the
//! live loop feeds it every analysed frame: the final total against the
//! truth, and for each repetition the delay from its true end to the frame on
//! which the running total reached it (the algorithm's own delay: no pose
//! model, no dropped frames). Every combination of the listed confirmation
//! margins and confidence thresholds is scored, so that they can be chosen
//! on one seed and reported on another. Only the 2D cases are fed (`mp live`
//! reads a camera).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::anyhow;
use clap::Args;
use mp_live::{LiveParams, OnlineCounter};
use rayon::prelude::*;
use serde_json::{json, Value};

use crate::synth_reps::{generate, Case, SynthOpts};
use crate::synth_sources::load_sources;
use crate::table::Table;

/// Arguments of `cargo xtask eval live`.
#[derive(Args, Debug)]
pub struct EvalLiveArgs {
    /// Report file (JSON).
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of the synthetic cases.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Cases generated (the 2D ones are fed).
    #[arg(long, default_value_t = 300)]
    pub cases: usize,
    /// Confirmation margins to score, in periods (default: the product's).
    #[arg(long, value_delimiter = ',')]
    pub confirm_periods: Vec<f64>,
    /// Confidence thresholds to score (default: the product's).
    #[arg(long, value_delimiter = ',')]
    pub min_confidence: Vec<f64>,
}

/// One case fed to the counter.
struct Fed {
    truth: usize,
    total: usize,
    /// Seconds from each true repetition's end to the frame on which the
    /// total reached it (only repetitions the total reached).
    delays: Vec<f64>,
    /// Repetitions first reported at the end of the stream.
    at_end: usize,
}

fn feed(c: &Case, params: &LiveParams) -> anyhow::Result<Fed> {
    let track = &c.track;
    let (n, j, _) = track.positions().dim();
    let fps = track.fps();
    let mut counter = OnlineCounter::new(fps, track.skeleton().clone(), params);
    let mut reached = Vec::new();
    for f in 0..n {
        let pts: Vec<[f64; 2]> = (0..j)
            .map(|q| [track.positions()[[f, q, 0]], track.positions()[[f, q, 1]]])
            .collect();
        let conf: Vec<f64> = (0..j).map(|q| track.confidence()[[f, q]]).collect();
        counter.push(f, pts, conf);
        for _ in counter.update(params)? {
            reached.push(f);
        }
    }
    let at_end = counter.finish(params)?.len();
    reached.extend(std::iter::repeat_n(n, at_end));
    let delays = reached
        .iter()
        .take(c.truth)
        .enumerate()
        .map(|(k, &f)| (f as f64 - c.boundaries[k + 1] as f64) / fps)
        .collect();
    Ok(Fed {
        truth: c.truth,
        total: reached.len(),
        delays,
        at_end,
    })
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// The figures of one setting over the cases with two or more repetitions.
fn figures(fed: &[Fed]) -> Value {
    let rep: Vec<&Fed> = fed.iter().filter(|f| f.truth >= 2).collect();
    let k = rep.len().max(1) as f64;
    let err = |f: &&Fed| (f.total as f64 - f.truth as f64).abs() / f.truth as f64;
    let mae = rep.iter().map(err).sum::<f64>() / k;
    let obo = rep
        .iter()
        .filter(|f| f.total.abs_diff(f.truth) <= 1)
        .count() as f64
        / k;
    let mut delays: Vec<f64> = rep.iter().flat_map(|f| f.delays.iter().copied()).collect();
    delays.sort_by(f64::total_cmp);
    let reps: usize = rep.iter().map(|f| f.total).sum();
    let at_end: usize = rep.iter().map(|f| f.at_end).sum();
    json!({
        "cases": rep.len(), "mae": mae, "obo": obo,
        "delay_median_s": quantile(&delays, 0.5), "delay_p90_s": quantile(&delays, 0.9),
        "repetitions_reached": delays.len(),
        "reported_at_end_share": at_end as f64 / reps.max(1) as f64,
        "truth_0_counted_0": fed.iter().filter(|f| f.truth == 0 && f.total == 0).count(),
        "truth_0_cases": fed.iter().filter(|f| f.truth == 0).count(),
    })
}

/// Runs the evaluation (see the module docs).
pub fn run(a: &EvalLiveArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let data = mp_geom::data_dir().ok_or_else(|| {
        anyhow!("the shared data folder was not found: set MP_DATA_DIR to it, or put `shared/data` beside the workspace")
    })?;
    let sources = load_sources(&data)?;
    let cases: Vec<Case> = generate(&sources, a.cases, a.seed, &SynthOpts::default())
        .into_iter()
        .filter(|c| c.track.dims() == 2)
        .collect();
    eprintln!("{} 2D cases of {} (seed {})", cases.len(), a.cases, a.seed);
    let base = LiveParams::default();
    let confirms = if a.confirm_periods.is_empty() {
        vec![base.confirm_periods]
    } else {
        a.confirm_periods.clone()
    };
    let mins = if a.min_confidence.is_empty() {
        vec![base.min_confidence]
    } else {
        a.min_confidence.clone()
    };
    let mut table = Table::new([
        "confirm (periods)",
        "min confidence",
        "MAE",
        "OBO",
        "median delay (s)",
        "p90 delay (s)",
        "reported at the end",
    ]);
    let mut settings = Vec::new();
    for &cp in &confirms {
        for &mc in &mins {
            let params = LiveParams {
                confirm_periods: cp,
                min_confidence: mc,
                ..base.clone()
            };
            params.validate()?;
            let fed: Vec<Fed> = cases
                .par_iter()
                .map(|c| feed(c, &params))
                .collect::<anyhow::Result<_>>()?;
            let fig = figures(&fed);
            let num = |k: &str| fig[k].as_f64().unwrap_or(f64::NAN);
            table.row(vec![
                format!("{cp}"),
                format!("{mc}"),
                format!("{:.3}", num("mae")),
                format!("{:.3}", num("obo")),
                format!("{:.2}", num("delay_median_s")),
                format!("{:.2}", num("delay_p90_s")),
                format!("{:.0} %", 100.0 * num("reported_at_end_share")),
            ]);
            settings.push(json!({"confirm_periods": cp, "min_confidence": mc, "figures": fig}));
            eprintln!("confirm {cp}, min confidence {mc}: done");
        }
    }
    println!("{}", table.markdown());
    // What no counter can beat: a repetition is known to be one only once
    // the motion has repeated, so the first is reached at the end of the
    // second at the earliest (and every later one at its own end).
    let mut bound: Vec<f64> = cases
        .iter()
        .filter(|c| c.truth >= 2)
        .flat_map(|c| {
            let fps = c.track.fps();
            (0..c.truth)
                .map(move |k| (c.boundaries[2] as f64 - c.boundaries[k + 1] as f64).max(0.0) / fps)
        })
        .collect();
    bound.sort_by(f64::total_cmp);
    let second_end = json!({
        "delay_median_s": quantile(&bound, 0.5),
        "delay_p90_s": quantile(&bound, 0.9),
        "share_over_2s": bound.iter().filter(|&&d| d > 2.0).count() as f64 / bound.len().max(1) as f64,
    });
    println!(
        "Least delay of any counter that needs two cycles: median {:.2} s, p90 {:.2} s, {:.1} % of the repetitions over 2 s",
        second_end["delay_median_s"].as_f64().unwrap_or(f64::NAN),
        second_end["delay_p90_s"].as_f64().unwrap_or(f64::NAN),
        100.0 * second_end["share_over_2s"].as_f64().unwrap_or(f64::NAN),
    );
    let report = json!({
        "kind": "live_counter_synthetic",
        "method": "mp_live::OnlineCounter with LiveParams::default() but the listed settings, fed each 2D synthetic case's keypoints frame by frame; delay = frame on which the total reached repetition k minus its true end, in seconds",
        "seed": a.seed, "cases_generated": a.cases, "cases_fed": cases.len(),
        "product": {"confirm_periods": base.confirm_periods, "min_confidence": base.min_confidence},
        "settings": settings,
        "least_delay_two_cycles": second_end,
        "runtime_s": t0.elapsed().as_secs_f64(),
    });
    crate::write_file(&a.out, &serde_json::to_string_pretty(&report)?)?;
    eprintln!("written to {}", a.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_pool_the_delays_of_the_repeating_cases() {
        let fed = [
            Fed {
                truth: 3,
                total: 3,
                delays: vec![0.5, 1.0, 2.0],
                at_end: 1,
            },
            Fed {
                truth: 4,
                total: 2,
                delays: vec![0.25, -0.5],
                at_end: 0,
            },
            Fed {
                truth: 0,
                total: 0,
                delays: vec![],
                at_end: 0,
            },
        ];
        let f = figures(&fed);
        assert_eq!(f["cases"], 2);
        assert!((f["mae"].as_f64().unwrap() - 0.25).abs() < 1e-12);
        assert!((f["obo"].as_f64().unwrap() - 0.5).abs() < 1e-12);
        // Delays sorted: −0.5, 0.25, 0.5, 1.0, 2.0.
        assert_eq!(f["delay_median_s"], 0.5);
        assert_eq!(f["delay_p90_s"], 2.0);
        assert_eq!(f["repetitions_reached"], 5);
        assert!((f["reported_at_end_share"].as_f64().unwrap() - 0.2).abs() < 1e-12);
        assert_eq!(f["truth_0_counted_0"], 1);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
