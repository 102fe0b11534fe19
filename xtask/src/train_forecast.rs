//! `cargo xtask train-forecast`: trains the forecasting models with PyTorch
//! (`tools/forecast/train.py`) and exports them to ONNX under `models/forecast/<dataset>/`.
//!
//! The virtual environment `.cache/venv-train` is created on first use with a
//! plain `pip install torch numpy onnx` from PyPI (the CPU-only index is not a
//! registry we may use; PyPI's torch imports only with its `nvidia-*`
//! dependencies installed, ~6–7 GB, and trains on the CPU). Training threads do
//! not busy-wait (`OMP_WAIT_POLICY=PASSIVE`): on a busy 2-core machine a
//! spinning OpenMP pool made steps 5–10× slower.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};
use clap::Args;

/// Arguments of `cargo xtask train-forecast`.
#[derive(Args, Debug)]
pub struct TrainForecastArgs {
    /// Penn Action or MSR Action3D npz (default: the shared Penn Action train split).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Curriculum epochs (the latent model also pre-trains with teacher forcing first).
    #[arg(long, default_value_t = 8)]
    pub epochs: usize,
    /// Output folder; the models go to OUT/<dataset>/.
    #[arg(long, default_value = "models/forecast")]
    pub out: PathBuf,
    /// Training seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Extra arguments passed to train.py (e.g. `--channels 96`).
    #[arg(last = true)]
    pub extra: Vec<String>,
}

const PACKAGES: [&str; 3] = ["torch", "numpy", "onnx"];

pub(crate) fn venv_python(root: &Path) -> Result<PathBuf> {
    let venv = root.join(".cache/venv-train");
    let python = venv.join("bin/python");
    if !python.is_file() {
        println!("train-forecast: creating {}", venv.display());
        let st = Command::new("python3")
            .args(["-m", "venv"])
            .arg(&venv)
            .status()
            .context("starting python3 -m venv")?;
        if !st.success() {
            bail!("python3 -m venv {} failed", venv.display());
        }
    }
    let ok = Command::new(&python)
        .args(["-c", "import torch, numpy, onnx"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !ok {
        println!(
            "train-forecast: pip install {} into {} (PyPI's torch brings its nvidia-* wheels: ~7 GB, several minutes)",
            PACKAGES.join(" "),
            venv.display()
        );
        let st = Command::new(&python)
            .args(["-m", "pip", "install", "-q"])
            .args(PACKAGES)
            .status()
            .context("starting pip")?;
        if !st.success() {
            bail!("pip install {} failed", PACKAGES.join(" "));
        }
    }
    Ok(python)
}

pub fn run(a: &TrainForecastArgs) -> Result<()> {
    let root = crate::setup::workspace_root();
    let data = match &a.data {
        Some(p) => p.clone(),
        None => mp_geom::paths::data_file("penn_action/penn_action_train.npz").context(
            "no --data given and the shared Penn Action train split was not found (set MP_DATA_DIR)",
        )?,
    };
    if !data.is_file() {
        bail!("{}: no such file", data.display());
    }
    let python = venv_python(&root)?;
    let out = if a.out.is_absolute() {
        a.out.clone()
    } else {
        root.join(&a.out)
    };
    let command = format!(
        "cargo xtask train-forecast --data {} --epochs {} --seed {} --out {}{}",
        data.display(),
        a.epochs,
        a.seed,
        a.out.display(),
        if a.extra.is_empty() {
            String::new()
        } else {
            format!(" -- {}", a.extra.join(" "))
        }
    );
    println!("train-forecast: {command}");
    let st = Command::new(&python)
        .arg(root.join("tools/forecast/train.py"))
        .arg("--data")
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .arg("--fixture-dir")
        .arg(root.join("testdata/forecast"))
        .args([
            "--epochs",
            &a.epochs.to_string(),
            "--seed",
            &a.seed.to_string(),
        ])
        .args(["--command", &command])
        .args(&a.extra)
        .env("OMP_WAIT_POLICY", "PASSIVE")
        .current_dir(&root)
        .status()
        .context("starting tools/forecast/train.py")?;
    if !st.success() {
        bail!("tools/forecast/train.py failed ({st})");
    }
    println!("train-forecast: models written under {}", out.display());
    Ok(())
}
