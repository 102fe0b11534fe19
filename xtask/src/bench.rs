//! `cargo xtask bench`: the workspace's criterion benches plus a timing
//! harness for synthesis at sizes criterion would take too long on; writes
//! `docs/BENCH.md`.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use mp_concrete::synthetic_track;
use mp_concrete::{Program, Scale, Segmentation, SynthParams};
use mp_eval::table::{Align::Left, Align::Right, Table};

/// Arguments of `cargo xtask bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Track lengths (frames) for the synthesis timing harness.
    #[arg(long, value_delimiter = ',', default_value = "1000,10000,100000")]
    pub sizes: Vec<usize>,
    /// Runs per size (the median is reported; sizes ≥ 100k run once).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Packages whose criterion benches run (`cargo bench -p …`).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "mp-geom,mp-concrete,mp-abstract,mp-refine"
    )]
    pub packages: Vec<String>,
    /// Skip the criterion benches (harness only).
    #[arg(long)]
    pub no_criterion: bool,
    /// Output Markdown file.
    #[arg(long, default_value = "docs/BENCH.md")]
    pub out: PathBuf,
}

/// CPU seconds used by this process so far (user + system, Linux `/proc`), if known.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // fields after the command name in parentheses; utime and stime are the 14th and 15th fields
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ut: f64 = f.get(11)?.parse().ok()?;
    let st: f64 = f.get(12)?.parse().ok()?;
    Some((ut + st) / 100.0)
}

/// The default procedural performer (COCO-17, 567 frames) repeated `reps` times.
fn repeated_performer(reps: usize) -> anyhow::Result<mp_geom::Track> {
    let tr = mp_geom::perform(&mp_geom::PerformerParams::default())?.track_2d;
    let pos: Vec<_> = (0..reps).map(|_| tr.positions()).collect();
    let conf: Vec<_> = (0..reps).map(|_| tr.confidence()).collect();
    Ok(mp_geom::Track::new(
        ndarray::concatenate(ndarray::Axis(0), &pos)?,
        Some(ndarray::concatenate(ndarray::Axis(0), &conf)?),
        tr.fps(),
        tr.units(),
        tr.skeleton().clone(),
    )?)
}

/// The 17-joint performer at 10,206 frames (`SynthParams::paper()`: scale from
/// the track, λ = 1600; and the analysis default that `mp fit` and `mp run`
/// use, the spread λ with the Euclidean refit), and the exhaustive reference
/// DP against the search at 1,134 frames.
fn harness_performer(md: &mut String) -> anyhow::Result<()> {
    let analysis = mp_pipeline::Params::default().analysis.synth;
    // (track repetitions, parameters, their label, the exhaustive reference too)
    let runs = [
        (2usize, SynthParams::paper(), "`paper()`", true),
        (18, SynthParams::paper(), "`paper()`", false),
        (18, analysis, "analysis", false),
    ];
    writeln!(
        md,
        "\nThe procedural performer (`mp_geom::performer`, COCO-17, 2D) repeated to T frames, with `SynthParams::paper()` (fixed λ = 1600) and with the analysis default that `mp fit` and `mp run` use (`mp_pipeline::Params::default()`: λ from the local spread held for one second, the Euclidean C0 refit); `search` is `mp_concrete::Program::synthesize` (exact branch and bound), `exhaustive` the reference `mp_concrete::Segmentation::exhaustive` (every candidate fitted into the `T × W` cost table), one run each:\n"
    )?;
    let mut table = Table::new([
        "track",
        "parameters",
        "method",
        "wall (s)",
        "CPU (s)",
        "segments",
        "cost",
    ])
    .align([Left, Left, Left, Right, Right, Right, Right]);
    for (reps, params, label, exhaustive) in &runs {
        let track = repeated_performer(*reps)?;
        let c0 = cpu_seconds();
        let t0 = Instant::now();
        let syn = Program::synthesize_detailed(&track, params)?;
        let (wall, cpu) = (
            t0.elapsed().as_secs_f64(),
            cpu_seconds().zip(c0).map(|(a, b)| a - b),
        );
        let cpu = cpu.map_or("–".into(), |c| format!("{c:.2}"));
        table.row([
            format!("performer ×{reps} ({} frames, 17 joints)", track.n_frames()),
            label.to_string(),
            "search".to_string(),
            format!("{wall:.3}"),
            cpu,
            syn.program.n_segments().to_string(),
            format!("{:.1}", syn.segmentation.cost),
        ]);
        eprintln!("performer ×{reps} ({label}): search {wall:.3} s");
        if *exhaustive {
            let c0 = cpu_seconds();
            let t0 = Instant::now();
            let s = Segmentation::exhaustive(&track, params)?;
            let (wall, cpu) = (
                t0.elapsed().as_secs_f64(),
                cpu_seconds().zip(c0).map(|(a, b)| a - b),
            );
            let cpu = cpu.map_or("–".into(), |c| format!("{c:.2}"));
            table.row([
                format!("performer ×{reps} ({} frames, 17 joints)", track.n_frames()),
                label.to_string(),
                "exhaustive".to_string(),
                format!("{wall:.3}"),
                cpu,
                s.n_segments().to_string(),
                format!("{:.1}", s.cost),
            ]);
            eprintln!("performer ×{reps}: exhaustive {wall:.3} s");
        }
    }
    md.push_str(&table.markdown());
    writeln!(
        md,
        "\nThe search's work on the same tracks (`mp_concrete::Segmentation::search_with_stats`; counts, the same on every machine): candidates (start, end) visited, dropped on `E[k] + λ`, dropped by the O(1) bounds, survivors, survivors dropped on the single-precision pass and the frames it read, exact joint evaluations per survivor and the frames they read, exact circle fits and their frames:\n"
    )?;
    let mut table = Table::new([
        "track",
        "parameters",
        "candidates",
        "dropped on λ",
        "dropped by bounds",
        "survivors",
        "dropped in single precision",
        "single-precision frames",
        "exact joints / survivor",
        "exact frames",
        "circle fits",
        "circle frames",
    ])
    .align([Left, Left].into_iter().chain([Right; 10]));
    for (reps, params, label, _) in &runs {
        let track = repeated_performer(*reps)?;
        let (_, st) = Segmentation::search_with_stats(&track, params)?;
        table.row([
            format!("performer ×{reps} ({} frames)", track.n_frames()),
            label.to_string(),
            st.candidates.to_string(),
            st.pruned_lambda.to_string(),
            st.pruned_bounds.to_string(),
            st.survivors.to_string(),
            st.dropped_coarse.to_string(),
            st.coarse_frames.to_string(),
            format!("{:.1}", st.joints_per_survivor()),
            st.exact_frames.to_string(),
            st.circle_fits.to_string(),
            st.circle_frames.to_string(),
        ]);
    }
    md.push_str(&table.markdown());
    Ok(())
}

fn harness(a: &BenchArgs, md: &mut String) -> anyhow::Result<()> {
    let params = SynthParams {
        scale: Scale::UnitScale { unit_scale: 1.0 },
        ..SynthParams::paper()
    };
    writeln!(
        md,
        "## Synthesis timing harness\n\nFull `mp_concrete::Program::synthesize` (default parameters: fixed λ = 1600, W = 60, \
         stationary/line/circle, Euclidean error; exact branch-and-bound segmentation, sequential, then the chosen \
         segments fitted on the rayon pool) of a seeded synthetic 13-joint 2D track \
         (`mp_concrete::synthetic_track(T, 7)`), release build, {} rayon threads. \
         CPU = user + system seconds of the process (other jobs sharing the machine inflate wall time, not CPU time).\n",
        rayon::current_num_threads()
    )?;
    let mut table = Table::new([
        "frames T",
        "runs",
        "median time (s)",
        "median CPU (s)",
        "frames / s",
        "segments",
    ])
    .align([Right; 6]);
    let mut times: Vec<(usize, f64)> = Vec::new();
    let mut cpu_times: Vec<(usize, f64)> = Vec::new();
    for &n in &a.sizes {
        let track = synthetic_track(n, 7)?;
        let runs = if n >= 100_000 { 1 } else { a.runs.max(1) };
        let mut ts = Vec::with_capacity(runs);
        let mut cs = Vec::with_capacity(runs);
        let mut segs = 0;
        for _ in 0..runs {
            let c0 = cpu_seconds();
            let t0 = Instant::now();
            let p = Program::synthesize(&track, &params)?;
            ts.push(t0.elapsed().as_secs_f64());
            if let (Some(a), Some(b)) = (cpu_seconds(), c0) {
                cs.push(a - b);
            }
            segs = p.n_segments();
        }
        ts.sort_by(f64::total_cmp);
        cs.sort_by(f64::total_cmp);
        let med = ts[ts.len() / 2];
        let cpu = cs
            .get(cs.len() / 2)
            .map_or("–".into(), |c| format!("{c:.2}"));
        eprintln!("T = {n}: {med:.3} s ({runs} runs), {segs} segments");
        table.row([
            n.to_string(),
            runs.to_string(),
            format!("{med:.3}"),
            cpu,
            format!("{:.0}", n as f64 / med),
            segs.to_string(),
        ]);
        times.push((n, med));
        if let Some(c) = cs.get(cs.len() / 2) {
            cpu_times.push((n, *c));
        }
    }
    md.push_str(&table.markdown());
    let get = |n: usize| times.iter().find(|(m, _)| *m == n).map(|(_, t)| *t);
    if let (Some(a10), Some(a100)) = (get(10_000), get(100_000)) {
        writeln!(
            md,
            "\nScaling time(100k) / time(10k) = **{:.2}** (linear = 10).",
            a100 / a10
        )?;
    }
    if let (Some(a1), Some(a10)) = (get(1_000), get(10_000)) {
        writeln!(md, "Scaling time(10k) / time(1k) = **{:.2}**.", a10 / a1)?;
    }
    let cpu = |n: usize| cpu_times.iter().find(|(m, _)| *m == n).map(|(_, t)| *t);
    if let (Some(a10), Some(a100)) = (cpu(10_000), cpu(100_000)) {
        writeln!(
            md,
            "Scaling in CPU time: cpu(100k) / cpu(10k) = **{:.2}**.",
            a100 / a10
        )?;
    }
    harness_performer(md)?;
    Ok(())
}

/// Parses criterion's report (`name\n   time:   [a b c]` or `name   time:   [a b c]`) into rows
/// (bench, time) of `table`.
fn parse_criterion(stdout: &str, table: &mut Table) {
    let mut last_name = String::new();
    for line in stdout.lines() {
        let trimmed = line.trim();
        if let Some(pos) = trimmed.find("time:") {
            let name = trimmed[..pos].trim();
            let name = if name.is_empty() {
                last_name.clone()
            } else {
                name.to_string()
            };
            let value = trimmed[pos + 5..].trim();
            table.row([format!("`{name}`"), value.to_string()]);
        } else if !trimmed.is_empty()
            && !line.starts_with(' ')
            && !trimmed.starts_with("Benchmarking")
            && !trimmed.starts_with("Found")
            && !trimmed.starts_with("Running")
            && !trimmed.starts_with("Gnuplot")
        {
            last_name = trimmed.to_string();
        }
    }
}

fn criterion(a: &BenchArgs, md: &mut String) -> anyhow::Result<bool> {
    writeln!(
        md,
        "\n## Criterion benches\n\n`cargo bench -p <package>` (criterion; time is [lower bound, estimate, upper bound] of the mean).\n"
    )?;
    let mut all_ok = true;
    for p in &a.packages {
        let mut cmd = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
        cmd.current_dir(crate::setup::workspace_dir()?)
            .args(["bench", "-p", p]);
        eprintln!("running {cmd:?}");
        let out = cmd.output().context("running cargo bench")?;
        let stdout = String::from_utf8_lossy(&out.stdout);
        writeln!(md, "### `{p}`\n")?;
        if !out.status.success() {
            all_ok = false;
            let stderr = String::from_utf8_lossy(&out.stderr);
            let tail: Vec<&str> = stderr.lines().rev().take(15).collect();
            let tail: Vec<&str> = tail.into_iter().rev().collect();
            writeln!(
                md,
                "`cargo bench -p {p}` failed:\n\n```text\n{}\n```\n",
                tail.join("\n")
            )?;
            continue;
        }
        let mut table = Table::new(["bench", "time"]);
        parse_criterion(&stdout, &mut table);
        md.push_str(&table.markdown());
        writeln!(md)?;
    }
    Ok(all_ok)
}

/// Runs the benches and writes the Markdown report.
pub fn run(a: &BenchArgs) -> anyhow::Result<()> {
    let mut md = String::from(
        "# Benchmarks\n\nGenerated by `cargo xtask bench`. Machine: the project's reference machine \
         (2 cores, no GPU) unless stated otherwise.\n\n",
    );
    harness(a, &mut md)?;
    let ok = a.no_criterion || criterion(a, &mut md)?;
    let out = if a.out.is_absolute() {
        a.out.clone()
    } else {
        crate::setup::workspace_dir()?.join(&a.out)
    };
    crate::write_file(&out, &md).with_context(|| format!("writing {}", out.display()))?;
    println!("{md}");
    eprintln!("wrote {}", out.display());
    if !ok {
        anyhow::bail!("some criterion benches failed (see {})", out.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn criterion_rows() {
        let stdout = "Benchmarking a/b\nfit/line\n                        time:   [1.0 ms 1.1 ms 1.2 ms]\nsolo   time:   [2 µs 3 µs 4 µs]\n";
        let mut table = Table::new(["bench", "time"]);
        parse_criterion(stdout, &mut table);
        assert_eq!(
            table.markdown(),
            "| bench | time |\n|---|---|\n| `fit/line` | [1.0 ms 1.1 ms 1.2 ms] |\n| `solo` | [2 µs 3 µs 4 µs] |\n"
        );
    }
}
