//! `cargo xtask train-refine --cv-subjects 1,3,5,7,9 -- --only flaw_detector`:
//! the flaw detector trained in cross-validation folds over the subjects.
//!
//! One flaw set holds flawed copies of every clip of the named subjects (and
//! the mocap windows); fold `i` scores subject `S[i]`, chooses its epoch on
//! `S[i − 1]` and trains on the rest (`crate::refine::cv::folds`). Each
//! fold's network is written with a copy of the other six networks into
//! `.cache/refine/cv/test<S>/`; the folds are then evaluated by
//! `cargo xtask eval refine --cv`, and the fold named by `--cv-ship` (default:
//! the last subject) is copied into the model folder.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::refine::cv::{fold_dir, folds};
use crate::refine::dataset::{build_flaw_set, FlawSetParams};
use anyhow::{bail, Context, Result};
use mp_geom::MsrAction3D;

use crate::pyenv::{command_line, run_script, training_args};
use crate::train_refine::TrainRefineArgs;

/// The folder of the fold folders.
pub fn cv_base(root: &Path) -> PathBuf {
    root.join(".cache/refine/cv")
}

/// Files of a model folder copied into every fold folder (the fold replaces
/// `flaw_detector.onnx` and updates `manifest.json` and `parity.npz`).
fn copy_models(from: &Path, to: &Path) -> Result<()> {
    std::fs::create_dir_all(to).with_context(|| format!("creating {}", to.display()))?;
    for e in std::fs::read_dir(from).with_context(|| format!("reading {}", from.display()))? {
        let p = e?.path();
        if p.is_file() {
            let name = p.file_name().context("file name")?;
            std::fs::copy(&p, to.join(name))
                .with_context(|| format!("copying {} to {}", p.display(), to.display()))?;
        }
    }
    Ok(())
}

/// Trains the folds (see the module docs) and ships one of them.
#[allow(clippy::too_many_arguments)]
pub fn run_cv(
    a: &TrainRefineArgs,
    subjects: &[u32],
    root: &Path,
    msr: &MsrAction3D,
    bvh: &[PathBuf],
    ds_path: &Path,
    out: &Path,
    python: &Path,
    base_command: String,
) -> Result<()> {
    let plan = folds(subjects)?;
    let present = crate::refine::split::subjects_of(msr);
    if let Some(s) = subjects.iter().find(|s| !present.contains(s)) {
        bail!("--cv-subjects: the data hold no clips of subject {s} (they hold {present:?})");
    }
    let ship = a
        .cv_ship
        .unwrap_or(*subjects.last().context("no subjects")?);
    if !subjects.contains(&ship) {
        bail!("--cv-ship {ship} is not one of --cv-subjects {subjects:?}");
    }
    let cache = root.join(".cache/refine");
    let t0 = Instant::now();
    let fparams = FlawSetParams {
        train_subjects: subjects.to_vec(),
        select_subjects: Vec::new(),
        copies_per_clip: a.copies,
        seed: a.seed,
        ..FlawSetParams::default()
    };
    let flaw_path = cache.join("flaw_dataset_cv.npz");
    if a.cv_reuse && flaw_path.is_file() {
        println!("train-refine: reusing {}", flaw_path.display());
    } else {
        let set = build_flaw_set(msr, bvh, &fparams)?;
        set.write_npz(&flaw_path)?;
        println!(
            "train-refine: cross-validation flaw set {}: {} rows (subjects {:?} + {} mocap rows, {} copies per clip), {:.1} s",
            flaw_path.display(),
            set.len(),
            subjects,
            set.subject.iter().filter(|&&s| s < 0).count(),
            a.copies,
            t0.elapsed().as_secs_f64()
        );
    }
    let list = |v: &[u32]| v.iter().map(u32::to_string).collect::<Vec<_>>().join(",");
    for f in &plan {
        let dir = fold_dir(&cv_base(root), f.test);
        let done = dir.join("manifest.json");
        if a.cv_reuse && fold_matches(&done, f) {
            println!(
                "train-refine: fold test {} already trained ({})",
                f.test,
                dir.display()
            );
            continue;
        }
        copy_models(out, &dir)?;
        let command = command_line(
            format!(
                "{base_command} --cv-subjects {} --copies {} (fold: train {:?}, select {:?}, test {})",
                list(subjects),
                a.copies,
                f.train,
                f.select,
                f.test
            ),
            &a.extra,
        );
        let mut args: Vec<OsString> = vec![
            "--dataset".into(),
            ds_path.as_os_str().to_owned(),
            "--flaw-dataset".into(),
            flaw_path.clone().into_os_string(),
            "--out".into(),
            dir.clone().into_os_string(),
        ];
        args.extend(training_args(a.epochs, a.seed, command, &a.extra));
        args.extend(
            [
                "--only".to_string(),
                "flaw_detector".into(),
                "--flaw-train-subjects".into(),
                list(&f.train),
                "--flaw-select-subjects".into(),
                f.select.to_string(),
            ]
            .map(OsString::from),
        );
        let tf = Instant::now();
        println!(
            "train-refine: fold test {}: train {:?}, select {}",
            f.test, f.train, f.select
        );
        run_script(python, root, "tools/refine/train.py", &args)?;
        println!(
            "train-refine: fold test {} trained in {:.0} s",
            f.test,
            tf.elapsed().as_secs_f64()
        );
    }
    let src = fold_dir(&cv_base(root), ship);
    for name in ["flaw_detector.onnx", "manifest.json", "parity.npz"] {
        std::fs::copy(src.join(name), out.join(name))
            .with_context(|| format!("copying {} into {}", name, out.display()))?;
    }
    println!(
        "train-refine: shipped the flaw detector of fold test {ship} ({}) into {}; {:.0} s in all",
        src.display(),
        out.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Whether the manifest in a fold folder records the fold's subjects.
fn fold_matches(manifest: &Path, f: &crate::refine::cv::Fold) -> bool {
    let Ok(text) = std::fs::read_to_string(manifest) else {
        return false;
    };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
        return false;
    };
    let t = &v["networks"]["flaw_detector"]["training"];
    let ints = |k: &str| -> Vec<u64> {
        t[k].as_array()
            .map(|a| a.iter().filter_map(|x| x.as_u64()).collect())
            .unwrap_or_default()
    };
    ints("train_subjects") == f.train.iter().map(|&s| u64::from(s)).collect::<Vec<_>>()
        && ints("select_subjects") == vec![u64::from(f.select)]
}
