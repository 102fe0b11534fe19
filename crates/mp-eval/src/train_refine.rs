//! `cargo xtask train-refine`: builds the refinement training set and the
//! flaw detector's training set (`crate::refine::dataset`: flawed copies of the
//! clips of subjects 1, 3, 5 for training and 7 for selection; subject 9 is
//! never read) into `.cache/refine/`, then trains the seven refinement
//! networks with PyTorch (`tools/refine/train.py`, CPU) and
//! exports them to ONNX with `manifest.json`, `parity.npz` and
//! `concepts.json` under `models/refine/`.
//!
//! The training environment is the one of `train-forecast`
//! (`.cache/venv-train`); ONNX Runtime's Python package is added to it on
//! first use to check every exported network against PyTorch.

use std::ffi::OsString;
use std::path::PathBuf;
use std::time::Instant;

use crate::refine::dataset::{build_flaw_set, build_training_set, DatasetParams, FlawSetParams};
use anyhow::{bail, Context, Result};
use clap::Args;
use mp_geom::MsrAction3D;

use crate::pyenv::{command_line, ensure_packages, run_script, training_args, training_python};

/// Arguments of `cargo xtask train-refine`.
#[derive(Args, Debug)]
pub struct TrainRefineArgs {
    /// MSR Action3D npz, or a folder of them read as one set (default: the shared odd-subjects file).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Folder of CMU BVH takes added as extra (unlabelled) motion; every `*.bvh` in it is used
    /// (default: the shared `cmu_salsa_bvh` folder when it exists).
    #[arg(long)]
    pub bvh: Option<PathBuf>,
    /// Train on MSR Action3D only (no BVH takes).
    #[arg(long)]
    pub no_bvh: bool,
    /// Training length multiplier: each network trains for this many passes
    /// over its training examples (times its own factor in train.py).
    #[arg(long, default_value_t = 100)]
    pub epochs: usize,
    /// Output folder of the ONNX files, manifest, parity data and concepts.
    #[arg(long, default_value = "models/refine")]
    pub out: PathBuf,
    /// Seed of the concepts and of the training.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Build the dataset and concepts only.
    #[arg(long)]
    pub dataset_only: bool,
    /// Flawed copies per clip in the flaw detector's training set.
    #[arg(long, default_value_t = 20)]
    pub copies: usize,
    /// Train the flaw detector in cross-validation folds over these subjects
    /// (comma separated; fold i scores subject i, chooses its epoch on the
    /// subject before it and trains on the rest) instead of the fixed split;
    /// only the flaw detector is trained.
    #[arg(long, value_delimiter = ',')]
    pub cv_subjects: Option<Vec<u32>>,
    /// The fold (its scored subject) whose flaw detector is copied into
    /// `--out` (default: the last of `--cv-subjects`).
    #[arg(long)]
    pub cv_ship: Option<u32>,
    /// Keep folds already trained for the same subjects (and the flaw set).
    #[arg(long)]
    pub cv_reuse: bool,
    /// Extra arguments passed to train.py (e.g. `--only evaluator`).
    #[arg(last = true)]
    pub extra: Vec<String>,
}

fn msr_file(data: &Option<PathBuf>) -> Result<PathBuf> {
    let p = match data {
        Some(p) => p.clone(),
        None => mp_geom::data_file(MsrAction3D::FILE).context(
            "no --data given and the shared MSR Action3D file was not found (set MP_DATA_DIR)",
        )?,
    };
    if !p.exists() {
        bail!("{}: no such file or folder", p.display());
    }
    Ok(p)
}

fn bvh_files(a: &TrainRefineArgs) -> Result<Vec<PathBuf>> {
    if a.no_bvh {
        return Ok(Vec::new());
    }
    let dir = match &a.bvh {
        Some(d) => d.clone(),
        None => match mp_geom::data_dir() {
            Some(d) if d.join("cmu_salsa_bvh").is_dir() => d.join("cmu_salsa_bvh"),
            _ => return Ok(Vec::new()),
        },
    };
    let dir = &dir;
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("bvh")))
        .collect();
    v.sort();
    if v.is_empty() {
        bail!("{}: no .bvh files", dir.display());
    }
    Ok(v)
}

pub fn run(a: &TrainRefineArgs) -> Result<()> {
    let root = crate::workspace_dir()?;
    let msr_path = msr_file(&a.data)?;
    let bvh = bvh_files(a)?;
    let out = if a.out.is_absolute() {
        a.out.clone()
    } else {
        root.join(&a.out)
    };
    let cache = root.join(".cache/refine");
    std::fs::create_dir_all(&cache).with_context(|| format!("creating {}", cache.display()))?;
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;

    let t0 = Instant::now();
    let msr = MsrAction3D::open_path(&msr_path)
        .with_context(|| format!("reading {}", msr_path.display()))?;
    let params = DatasetParams {
        seed: a.seed,
        ..DatasetParams::default()
    };
    let set = build_training_set(&msr, &bvh, &params)?;
    let ds_path = cache.join("refine_dataset.npz");
    set.write_npz(&ds_path)?;
    if let Some(subjects) = &a.cv_subjects {
        let python = training_python(&root, "train-refine")?;
        ensure_packages(&python, "onnxruntime", &["onnxruntime"], "train-refine", "")?;
        let base = format!(
            "cargo xtask train-refine --data {} --epochs {} --seed {} --out {}",
            a.data
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| msr_path.display().to_string()),
            a.epochs,
            a.seed,
            a.out.display()
        );
        return crate::train_refine_cv::run_cv(
            a, subjects, &root, &msr, &bvh, &ds_path, &out, &python, base,
        );
    }
    crate::write_file(out.join("concepts.json"), set.concepts.to_json()?)
        .with_context(|| format!("writing {}", out.join("concepts.json").display()))?;
    let t1 = Instant::now();
    let fparams = FlawSetParams {
        seed: a.seed,
        copies_per_clip: a.copies,
        ..FlawSetParams::default()
    };
    let flaw_set = build_flaw_set(&msr, &bvh, &fparams)?;
    let flaw_path = cache.join("flaw_dataset.npz");
    flaw_set.write_npz(&flaw_path)?;
    let n_flawed_cells: usize = flaw_set.mask.iter().map(|&v| usize::from(v)).sum();
    println!(
        "train-refine: flaw set {}: {} clips ({} selection, subjects {:?}; training subjects {:?} + mocap), {:.1} % flawed cells, {:.1} s",
        flaw_path.display(),
        flaw_set.len(),
        flaw_set.split.iter().filter(|&&s| s == 1).count(),
        fparams.select_subjects,
        fparams.train_subjects,
        100.0 * n_flawed_cells as f64 / flaw_set.mask.len().max(1) as f64,
        t1.elapsed().as_secs_f64()
    );
    let n_val = set.split.iter().filter(|&&s| s == 1).count();
    let n_mocap = set.action.iter().filter(|&&x| x < 0).count();
    let n_anchor: i64 = set.anchor.sum();
    println!(
        "train-refine: {} BVH takes; {} clips ({} validation, {} mocap windows), {} anchors, dataset {} and concepts {} in {:.1} s",
        bvh.len(),
        set.len(),
        n_val,
        n_mocap,
        n_anchor,
        ds_path.display(),
        out.join("concepts.json").display(),
        t0.elapsed().as_secs_f64()
    );
    if a.dataset_only {
        return Ok(());
    }

    let python = training_python(&root, "train-refine")?;
    ensure_packages(&python, "onnxruntime", &["onnxruntime"], "train-refine", "")?;
    let command = command_line(
        format!(
            "cargo xtask train-refine --data {}{} --epochs {} --seed {} --out {}",
            a.data
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| msr_path.display().to_string()),
            match (&a.bvh, a.no_bvh) {
                (_, true) => " --no-bvh".to_string(),
                (Some(p), false) => format!(" --bvh {}", p.display()),
                (None, false) => String::new(),
            },
            a.epochs,
            a.seed,
            a.out.display(),
        ),
        &a.extra,
    );
    println!("train-refine: {command}");
    let mut args: Vec<OsString> = vec![
        "--dataset".into(),
        ds_path.into_os_string(),
        "--flaw-dataset".into(),
        flaw_path.into_os_string(),
        "--out".into(),
        out.clone().into_os_string(),
    ];
    args.extend(training_args(a.epochs, a.seed, command, &a.extra));
    run_script(&python, &root, "tools/refine/train.py", &args)?;
    println!("train-refine: networks written under {}", out.display());
    Ok(())
}
