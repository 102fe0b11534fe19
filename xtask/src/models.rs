//! `cargo xtask models [--out DIR] [--convert]`: puts the ONNX pose models in
//! `<workspace>/.cache/models/`.
//!
//! Without `--convert`, converted models already on this machine are used
//! (`MP_MODEL_DIR`, then `../shared/models`) and hard-linked or copied.
//! Whatever is still missing (or everything, with `--convert`) is converted
//! from registry packages:
//!
//! * PyPI `mediapipe==0.10.21` wheel: `pose_detection.tflite`, `pose_landmark_full.tflite`;
//! * npm `@mediapipe/pose@0.5.1675469404`: `pose_landmark_lite.tflite` (and `_heavy` with `--heavy`);
//! * the detector's sparse fp16 weights are densified first (`tools/densify_tflite.py`);
//! * `tf2onnx==1.17.0` + `tensorflow-cpu==2.20.0` in `.cache/venv-models`, opset 17;
//! * each ONNX file is checked against its TFLite original on a real photo
//!   (`tools/verify_onnx_vs_tflite.py`);
//! * each landmark model is also written without its segmentation-mask head
//!   (`<name>_nomask.onnx`, `tools/cut_mask.py` with PyPI's `onnx` in
//!   `.cache/venv-onnx`), the file the estimators open: the same values in
//!   about half the time.
//!
//! MoveNet SinglePose Lightning is not published in any package registry
//! (TensorFlow.js' `@tensorflow-models/pose-detection` downloads it from TF
//! Hub at run time), so it is taken from an existing converted file, or
//! converted from a `.tflite` given with `--movenet-tflite`.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

use crate::setup::{extract_zip_member, workspace_dir};

const MEDIAPIPE_WHEEL_SPEC: &str = "mediapipe==0.10.21";
const MEDIAPIPE_NPM_SPEC: &str = "@mediapipe/pose@0.5.1675469404";
const NPM_TGZ: &str = "mediapipe-pose-0.5.1675469404.tgz";
const PY_TOOLS: [&str; 4] = [
    "tf2onnx==1.17.0",
    "tensorflow-cpu==2.20.0",
    "onnxruntime==1.31.1",
    "pillow",
];
const OPSET: &str = "17";

#[derive(clap::Args, Debug, Default)]
pub struct ModelsArgs {
    /// Output folder (default: WORKSPACE/.cache/models).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Convert from the registry packages even when converted models exist.
    #[arg(long)]
    pub convert: bool,
    /// Also convert `pose_landmark_heavy` (55 MB ONNX).
    #[arg(long)]
    pub heavy: bool,
    /// A MoveNet SinglePose Lightning int8 `.tflite` to convert.
    #[arg(long)]
    pub movenet_tflite: Option<PathBuf>,
    /// Photo used to check each conversion (default: shared COCO sample 000000000785.jpg).
    #[arg(long)]
    pub verify_image: Option<PathBuf>,
}

struct Conversion {
    onnx: &'static str,
    /// (where the tflite comes from, path inside the package)
    source: Source,
    densify: bool,
}

enum Source {
    Wheel(&'static str),
    Npm(&'static str),
}

const CONVERSIONS: [Conversion; 4] = [
    Conversion {
        onnx: "pose_detection.onnx",
        source: Source::Wheel("mediapipe/modules/pose_detection/pose_detection.tflite"),
        densify: true,
    },
    Conversion {
        onnx: "pose_landmark_full.onnx",
        source: Source::Wheel("mediapipe/modules/pose_landmark/pose_landmark_full.tflite"),
        densify: false,
    },
    Conversion {
        onnx: "pose_landmark_lite.onnx",
        source: Source::Npm("package/pose_landmark_lite.tflite"),
        densify: false,
    },
    Conversion {
        onnx: "pose_landmark_heavy.onnx",
        source: Source::Npm("package/pose_landmark_heavy.tflite"),
        densify: false,
    },
];

const MOVENET_ONNX: &str = "movenet_singlepose_lightning_int8.onnx";

fn existing_model_dirs(out: &Path) -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Ok(p) = std::env::var("MP_MODEL_DIR") {
        if !p.is_empty() {
            dirs.push(PathBuf::from(p));
        }
    }
    if let Some(shared) = mp_geom::shared_dir() {
        dirs.push(shared.join("models"));
    }
    let out_c = out.canonicalize().unwrap_or_else(|_| out.to_path_buf());
    dirs.retain(|d| d.canonicalize().map(|c| c != out_c).unwrap_or(true));
    dirs
}

fn link_or_copy(src: &Path, dst: &Path) -> Result<()> {
    let tmp = dst.with_extension("part");
    let _ = std::fs::remove_file(&tmp);
    if std::fs::hard_link(src, &tmp).is_err() {
        std::fs::copy(src, &tmp)
            .with_context(|| format!("copying {} to {}", src.display(), tmp.display()))?;
    }
    std::fs::rename(&tmp, dst).with_context(|| format!("moving {} into place", dst.display()))?;
    Ok(())
}

pub fn run(args: &ModelsArgs) -> Result<()> {
    let root = workspace_dir()?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| root.join(".cache/models"));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;

    let mut wanted: Vec<&Conversion> = CONVERSIONS
        .iter()
        .filter(|c| args.heavy || c.onnx != "pose_landmark_heavy.onnx")
        .collect();
    let mut want_movenet = true;

    let dirs = existing_model_dirs(&out);
    let take = |name: &str| -> Result<bool> {
        if out.join(name).is_file() {
            println!("models: {name} already in {}", out.display());
            return Ok(true);
        }
        for d in &dirs {
            let src = d.join(name);
            if src.is_file() {
                link_or_copy(&src, &out.join(name))?;
                println!("models: {name} taken from {}", d.display());
                return Ok(true);
            }
        }
        Ok(false)
    };
    if !args.convert {
        let mut still = Vec::new();
        for c in wanted {
            if !take(c.onnx)? {
                still.push(c);
            }
        }
        wanted = still;
    }
    // MoveNet has no registry source: without a .tflite to convert, use an existing file.
    if args.movenet_tflite.is_none() && take(MOVENET_ONNX)? {
        want_movenet = false;
    }

    if !wanted.is_empty() || (want_movenet && args.movenet_tflite.is_some()) {
        convert(&root, &out, &wanted, args)?;
    }
    cut_masks(&root, &out)?;
    if want_movenet && args.movenet_tflite.is_none() && !out.join(MOVENET_ONNX).is_file() {
        eprintln!(
            "models: note: {MOVENET_ONNX} is missing. No package registry ships MoveNet's weights \
             (npm @tensorflow-models/pose-detection loads them from TF Hub at run time); put a \
             converted file in MP_MODEL_DIR, or pass --movenet-tflite FILE (the Apache-2.0 TF Hub \
             `movenet/singlepose/lightning/tflite/int8/4` model). `--model movenet` is unavailable until then."
        );
    }
    println!("models: ready in {}", out.display());
    Ok(())
}

/// The one package `tools/cut_mask.py` needs.
const ONNX_PACKAGE: &str = "onnx==1.23.2";

/// Each landmark model in `out` without its segmentation-mask head
/// (`<name>_nomask.onnx`, `tools/cut_mask.py`), which the estimators open
/// instead: the same values in about half the time.
fn cut_masks(root: &Path, out: &Path) -> Result<()> {
    use mp_pose::ModelFile;
    let todo: Vec<(PathBuf, PathBuf)> = [
        ModelFile::LandmarkFull,
        ModelFile::LandmarkLite,
        ModelFile::LandmarkHeavy,
    ]
    .into_iter()
    .filter_map(|m| {
        let cut = out.join(m.without_mask()?);
        let src = out.join(m.file_name());
        (src.is_file() && !cut.is_file()).then_some((src, cut))
    })
    .collect();
    if todo.is_empty() {
        return Ok(());
    }
    let python = mp_eval::pyenv::venv(root, ".cache/venv-onnx", "models")?;
    mp_eval::pyenv::ensure_packages(&python, "onnx", &[ONNX_PACKAGE], "models", "")?;
    for (src, cut) in todo {
        println!("models: cutting the mask head off {}", file_name_of(&src));
        mp_eval::pyenv::run_script(
            &python,
            root,
            "tools/cut_mask.py",
            &[src.clone().into_os_string(), cut.into_os_string()],
        )?;
    }
    Ok(())
}

fn file_name_of(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn run_cmd(cmd: &mut Command, what: &str) -> Result<()> {
    let out = cmd.output().with_context(|| format!("starting {what}"))?;
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = stderr.lines().rev().take(15).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        bail!("{what} failed ({}):\n{}", out.status, tail.join("\n"));
    }
    Ok(())
}

fn venv_python(root: &Path) -> Result<PathBuf> {
    let venv = root.join(".cache/venv-models");
    let python = mp_eval::pyenv::venv(root, ".cache/venv-models", "models")?;
    let marker = venv.join(".mp-tools-installed");
    if !marker.is_file() {
        println!(
            "models: installing {} into {} (about 700 MB, a few minutes)",
            PY_TOOLS.join(" "),
            venv.display()
        );
        run_cmd(
            Command::new(&python)
                .args(["-m", "pip", "install", "-q"])
                .args(PY_TOOLS),
            "pip install (conversion tools)",
        )?;
        crate::write_file(&marker, PY_TOOLS.join("\n"))?;
    }
    Ok(python)
}

fn default_verify_image() -> Option<PathBuf> {
    mp_geom::data_file("coco_sample/000000000785.jpg")
}

fn convert(root: &Path, out: &Path, wanted: &[&Conversion], args: &ModelsArgs) -> Result<()> {
    let python = venv_python(root)?;
    let src = root.join(".cache/models-src");
    std::fs::create_dir_all(&src)?;
    let tools = root.join("tools");
    let verify_image = args.verify_image.clone().or_else(default_verify_image);
    if verify_image.is_none() {
        eprintln!("models: warning: no photo to verify the conversions (give --verify-image FILE)");
    }

    let need_wheel = wanted.iter().any(|c| matches!(c.source, Source::Wheel(_)));
    let need_npm = wanted.iter().any(|c| matches!(c.source, Source::Npm(_)));
    let wheel = if need_wheel {
        let found = find_prefixed(&src, "mediapipe-0.10.21-", ".whl")?;
        Some(match found {
            Some(w) => w,
            None => {
                println!(
                    "models: downloading {MEDIAPIPE_WHEEL_SPEC} (PyPI wheel, no dependencies)"
                );
                crate::setup::pip_download(&src, MEDIAPIPE_WHEEL_SPEC)?;
                find_prefixed(&src, "mediapipe-0.10.21-", ".whl")?
                    .context("the mediapipe wheel did not arrive")?
            }
        })
    } else {
        None
    };
    let tgz = src.join(NPM_TGZ);
    if need_npm && !tgz.is_file() {
        println!("models: downloading {MEDIAPIPE_NPM_SPEC} (npm pack)");
        run_cmd(
            Command::new("npm")
                .arg("pack")
                .arg(MEDIAPIPE_NPM_SPEC)
                .current_dir(&src),
            "npm pack",
        )?;
    }

    for c in wanted {
        let tflite = match c.source {
            Source::Wheel(member) => {
                let dest = src.join(file_name(member));
                if !dest.is_file() {
                    extract_zip_member(wheel.as_deref().context("wheel")?, member, &dest)?;
                }
                dest
            }
            Source::Npm(member) => {
                let dest = src.join(file_name(member));
                if !dest.is_file() {
                    let dir = src.join("npm");
                    std::fs::create_dir_all(&dir)?;
                    run_cmd(
                        Command::new("tar")
                            .arg("xzf")
                            .arg(&tgz)
                            .arg("-C")
                            .arg(&dir)
                            .arg(member),
                        "tar (npm package)",
                    )?;
                    std::fs::rename(dir.join(member), &dest)?;
                }
                dest
            }
        };
        let input = if c.densify {
            let dense = tflite.with_file_name(format!(
                "{}_dense.tflite",
                tflite
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or("model")
            ));
            println!("models: densifying {}", tflite.display());
            run_cmd(
                Command::new(&python)
                    .arg(tools.join("densify_tflite.py"))
                    .arg(&tflite)
                    .arg(&dense)
                    .env("TF_CPP_MIN_LOG_LEVEL", "2"),
                "densify_tflite.py",
            )?;
            dense
        } else {
            tflite.clone()
        };
        convert_one(
            &python,
            &input,
            &tflite,
            &out.join(c.onnx),
            verify_image.as_deref(),
            &tools,
        )?;
    }
    if let Some(mv) = &args.movenet_tflite {
        convert_one(
            &python,
            mv,
            mv,
            &out.join(MOVENET_ONNX),
            verify_image.as_deref(),
            &tools,
        )?;
    }
    Ok(())
}

fn convert_one(
    python: &Path,
    input: &Path,
    original: &Path,
    dest: &Path,
    verify_image: Option<&Path>,
    tools: &Path,
) -> Result<()> {
    let tmp = dest.with_extension("part.onnx");
    println!(
        "models: converting {} -> {}",
        input.display(),
        dest.display()
    );
    run_cmd(
        Command::new(python)
            .args(["-m", "tf2onnx.convert", "--tflite"])
            .arg(input)
            .arg("--output")
            .arg(&tmp)
            .args(["--opset", OPSET])
            .env("TF_CPP_MIN_LOG_LEVEL", "2"),
        "tf2onnx",
    )?;
    if let Some(img) = verify_image {
        let out = Command::new(python)
            .arg(tools.join("verify_onnx_vs_tflite.py"))
            .arg(img)
            .arg(original)
            .arg(&tmp)
            .env("TF_CPP_MIN_LOG_LEVEL", "2")
            .output()
            .context("starting verify_onnx_vs_tflite.py")?;
        let report = String::from_utf8_lossy(&out.stdout);
        let line = report.lines().last().unwrap_or("").to_string();
        if !out.status.success() {
            bail!(
                "{} does not reproduce {}: {line}\n{}",
                tmp.display(),
                original.display(),
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
            );
        }
        println!(
            "models: verified against the TFLite original: {}",
            summarize(&line)
        );
    }
    std::fs::rename(&tmp, dest).with_context(|| format!("moving {} into place", dest.display()))?;
    Ok(())
}

fn summarize(json_line: &str) -> String {
    let Ok(v) = serde_json::from_str::<serde_json::Value>(json_line) else {
        return json_line.to_string();
    };
    let parts: Vec<String> = v["outputs"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|o| {
                    format!(
                        "out{} max|Δ|={:.2e}",
                        o["index"],
                        o["max_abs_diff"].as_f64().unwrap_or(f64::NAN)
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    parts.join(", ")
}

fn file_name(member: &str) -> String {
    member.rsplit('/').next().unwrap_or(member).to_string()
}

fn find_prefixed(dir: &Path, prefix: &str, suffix: &str) -> Result<Option<PathBuf>> {
    let mut found = None;
    for e in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let p = e?.path();
        let n = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if n.starts_with(prefix) && n.ends_with(suffix) {
            found = Some(p);
        }
    }
    Ok(found)
}
