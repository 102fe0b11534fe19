//! Python virtual environments of the xtask tools, and running their scripts.
//!
//! Environments live under `.cache/` and are created with `python3 -m venv`
//! on first use; packages come from PyPI. Scripts run with passive OpenMP
//! threads (`OMP_WAIT_POLICY=PASSIVE`): on a busy 2-core machine a spinning
//! OpenMP pool made training steps 5–10× slower.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

/// The training environment's packages (`train-forecast`, `train-refine`).
const TRAINING_PACKAGES: [&str; 3] = ["torch", "numpy", "onnx"];

/// `python` of the environment `root/rel`, created on first use.
pub fn venv(root: &Path, rel: &str, who: &str) -> Result<PathBuf> {
    let venv = root.join(rel);
    let python = venv.join("bin/python");
    if !python.is_file() {
        println!("{who}: creating {}", venv.display());
        let st = Command::new("python3")
            .args(["-m", "venv"])
            .arg(&venv)
            .status()
            .context("starting python3 -m venv")?;
        if !st.success() {
            bail!("python3 -m venv {} failed", venv.display());
        }
    }
    Ok(python)
}

/// Installs `packages` into `python`'s environment unless `import <modules>` works.
pub fn ensure_packages(
    python: &Path,
    modules: &str,
    packages: &[&str],
    who: &str,
    note: &str,
) -> Result<()> {
    let ok = Command::new(python)
        .args(["-c", &format!("import {modules}")])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if ok {
        return Ok(());
    }
    println!("{who}: pip install {}{note}", packages.join(" "));
    let st = Command::new(python)
        .args(["-m", "pip", "install", "-q"])
        .args(packages)
        .status()
        .context("starting pip")?;
    if !st.success() {
        bail!("pip install {} failed", packages.join(" "));
    }
    Ok(())
}

/// `python` of `.cache/venv-train` with PyTorch, NumPy and ONNX. PyPI's torch
/// (the CPU-only index is not a registry we may use) imports only with its
/// `nvidia-*` dependencies installed (~6–7 GB) and trains on the CPU.
pub fn training_python(root: &Path, who: &str) -> Result<PathBuf> {
    let python = venv(root, ".cache/venv-train", who)?;
    ensure_packages(
        &python,
        "torch, numpy, onnx",
        &TRAINING_PACKAGES,
        who,
        " (PyPI's torch brings its nvidia-* wheels: ~7 GB, several minutes)",
    )?;
    Ok(python)
}

/// Runs `python root/script args…` in `root`; fails when the script does.
pub fn run_script(python: &Path, root: &Path, script: &str, args: &[OsString]) -> Result<()> {
    let st = Command::new(python)
        .arg(root.join(script))
        .args(args)
        .env("OMP_WAIT_POLICY", "PASSIVE")
        .current_dir(root)
        .status()
        .with_context(|| format!("starting {script}"))?;
    if !st.success() {
        bail!("{script} failed ({st})");
    }
    Ok(())
}

/// The command recorded in a manifest: `base`, then ` -- extra…` when there are extra arguments.
pub fn command_line(base: String, extra: &[String]) -> String {
    if extra.is_empty() {
        base
    } else {
        format!("{base} -- {}", extra.join(" "))
    }
}

/// The arguments every training script takes after its own: `--epochs`,
/// `--seed`, `--command` (recorded in the manifest), then the user's extra ones.
pub fn training_args(epochs: usize, seed: u64, command: String, extra: &[String]) -> Vec<OsString> {
    let mut v: Vec<OsString> = vec![
        "--epochs".into(),
        epochs.to_string().into(),
        "--seed".into(),
        seed.to_string().into(),
        "--command".into(),
        command.into(),
    ];
    v.extend(extra.iter().map(OsString::from));
    v
}
