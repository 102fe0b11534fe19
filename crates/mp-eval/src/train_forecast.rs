//! `cargo xtask train-forecast`: trains the forecasting models with PyTorch
//! (`tools/forecast/train.py`) and exports them to ONNX under `models/forecast/<dataset>/`.
//!
//! The training environment is `.cache/venv-train` ([`crate::pyenv::training_python`]).
//! The ONNX parity fixture (`<dataset>_parity.json`) goes to `testdata/forecast/`
//! when the models go to the committed `models/forecast/`, and next to the models otherwise,
//! so that an experiment never replaces the fixture of the committed models.

use std::ffi::OsString;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;

use crate::pyenv::{command_line, run_script, training_args, training_python};

/// Arguments of `cargo xtask train-forecast`.
#[derive(Args, Debug)]
pub struct TrainForecastArgs {
    /// Penn Action or MSR Action3D npz (default: the shared Penn Action train split).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Curriculum epochs (the latent model also pre-trains with teacher forcing first).
    #[arg(long, default_value_t = 8)]
    pub epochs: usize,
    /// Output folder; the models go to OUT/DATASET/.
    #[arg(long, default_value = "models/forecast")]
    pub out: PathBuf,
    /// Training seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Extra arguments passed to train.py (e.g. `--channels 96`).
    #[arg(last = true)]
    pub extra: Vec<String>,
}

pub fn run(a: &TrainForecastArgs) -> Result<()> {
    let root = crate::workspace_dir()?;
    let data = match &a.data {
        Some(p) => p.clone(),
        None => mp_geom::data_file("penn_action/penn_action_train.npz").context(
            "no --data given and the shared Penn Action train split was not found (set MP_DATA_DIR)",
        )?,
    };
    if !data.is_file() {
        bail!("{}: no such file", data.display());
    }
    let python = training_python(&root, "train-forecast")?;
    let out = if a.out.is_absolute() {
        a.out.clone()
    } else {
        root.join(&a.out)
    };
    let committed = root.join("models/forecast");
    let fixture_dir = if out == committed {
        root.join("testdata/forecast")
    } else {
        out.clone()
    };
    let command = command_line(
        format!(
            "cargo xtask train-forecast --data {} --epochs {} --seed {} --out {}",
            data.display(),
            a.epochs,
            a.seed,
            a.out.display(),
        ),
        &a.extra,
    );
    println!("train-forecast: {command}");
    let mut args: Vec<OsString> = vec![
        "--data".into(),
        data.into_os_string(),
        "--out".into(),
        out.clone().into_os_string(),
        "--fixture-dir".into(),
        fixture_dir.clone().into_os_string(),
    ];
    args.extend(training_args(a.epochs, a.seed, command, &a.extra));
    run_script(&python, &root, "tools/forecast/train.py", &args)?;
    println!(
        "train-forecast: models written under {}, parity fixture under {}",
        out.display(),
        fixture_dir.display()
    );
    Ok(())
}
