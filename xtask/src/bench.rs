//! `cargo xtask bench`: the workspace's criterion benches plus a timing
//! harness for synthesis at sizes criterion would take too long on; writes
//! `docs/BENCH.md`.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use mp_concrete::synthetic::synthetic_track;
use mp_concrete::{synthesize, Scale, SynthParams};

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

fn workspace_root() -> PathBuf {
    // xtask lives in <root>/xtask.
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("."))
}

fn harness(a: &BenchArgs, md: &mut String) -> anyhow::Result<()> {
    let params = SynthParams {
        scale: Scale::UnitScale { unit_scale: 1.0 },
        ..SynthParams::default()
    };
    writeln!(
        md,
        "## Synthesis timing harness\n\nFull `mp_concrete::synthesize` (default parameters: fixed λ = 1600, W = 60, \
         stationary/line/circle) of a seeded synthetic 13-joint 2D track \
         (`mp_concrete::synthetic::synthetic_track(T, 7)`), release build, {} rayon threads.\n",
        rayon::current_num_threads()
    )?;
    writeln!(
        md,
        "| frames T | runs | median time (s) | frames / s | segments |"
    )?;
    writeln!(md, "|---:|---:|---:|---:|---:|")?;
    let mut times: Vec<(usize, f64)> = Vec::new();
    for &n in &a.sizes {
        let track = synthetic_track(n, 7)?;
        let runs = if n >= 100_000 { 1 } else { a.runs.max(1) };
        let mut ts = Vec::with_capacity(runs);
        let mut segs = 0;
        for _ in 0..runs {
            let t0 = Instant::now();
            let p = synthesize(&track, &params)?;
            ts.push(t0.elapsed().as_secs_f64());
            segs = p.n_segments();
        }
        ts.sort_by(f64::total_cmp);
        let med = ts[ts.len() / 2];
        eprintln!("T = {n}: {med:.3} s ({runs} runs), {segs} segments");
        writeln!(
            md,
            "| {n} | {runs} | {med:.3} | {:.0} | {segs} |",
            n as f64 / med
        )?;
        times.push((n, med));
    }
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
    Ok(())
}

/// Parses criterion's report (`name\n   time:   [a b c]` or `name   time:   [a b c]`) into rows.
fn parse_criterion(stdout: &str, md: &mut String) -> std::fmt::Result {
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
            writeln!(md, "| `{name}` | {value} |")?;
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
    Ok(())
}

fn criterion(a: &BenchArgs, md: &mut String) -> anyhow::Result<bool> {
    writeln!(
        md,
        "\n## Criterion benches\n\n`cargo bench -p <package>` (criterion; time is [lower bound, estimate, upper bound] of the mean).\n"
    )?;
    let mut all_ok = true;
    for p in &a.packages {
        let mut cmd = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
        cmd.current_dir(workspace_root()).args(["bench", "-p", p]);
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
        writeln!(md, "| bench | time |")?;
        writeln!(md, "|---|---|")?;
        parse_criterion(&stdout, md)?;
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
        workspace_root().join(&a.out)
    };
    crate::write_file(&out, &md).with_context(|| format!("writing {}", out.display()))?;
    println!("{md}");
    eprintln!("wrote {}", out.display());
    if !ok {
        anyhow::bail!("some criterion benches failed (see {})", out.display());
    }
    Ok(())
}
