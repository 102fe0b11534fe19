//! `cargo xtask setup`: installs ONNX Runtime's shared library into
//! `<workspace>/.cache/onnxruntime/lib/` from PyPI's `onnxruntime` wheel, and
//! the pose models into `.cache/models/` (see `models.rs`). Idempotent.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

/// The ONNX Runtime release the `ort` crate is built against (API level 31).
pub const ORT_VERSION: &str = "1.31.1";

#[derive(clap::Args, Debug)]
pub struct SetupArgs {
    /// Reinstall even when the library is already there.
    #[arg(long)]
    pub force: bool,
    /// Only install ONNX Runtime, not the models.
    #[arg(long)]
    pub no_models: bool,
    /// Also install ONNX Runtime's GPU build with its CUDA libraries (PyPI's
    /// `onnxruntime-gpu[cuda,cudnn]`, several GB) into `.cache/venv-gpu`, and
    /// write `.cache/onnxruntime-gpu.env`, which points `mp` at it.
    #[arg(long)]
    pub gpu: bool,
}

pub use mp_eval::workspace_dir;

pub fn run(args: &SetupArgs) -> Result<()> {
    let root = workspace_dir()?;
    let lib = install_onnxruntime(&root, args.force)?;
    check_runtime(&lib)?;
    if !args.no_models {
        crate::models::run(&crate::models::ModelsArgs::default())?;
    }
    if args.gpu {
        install_gpu_runtime(&root)?;
    }
    Ok(())
}

/// The GPU build of ONNX Runtime with the CUDA and cuDNN libraries it loads.
const GPU_PACKAGE: &str = "onnxruntime-gpu[cuda,cudnn]";

/// Installs ONNX Runtime's GPU build and its CUDA libraries into
/// `.cache/venv-gpu` and writes `.cache/onnxruntime-gpu.env`: `source` it
/// and `mp` loads that library (`ORT_DYLIB_PATH`) and finds the CUDA
/// libraries (`LD_LIBRARY_PATH`); `--device auto` (the default) then runs
/// the pose models on the GPU, and falls back to the CPU where there is no
/// GPU.
fn install_gpu_runtime(root: &Path) -> Result<()> {
    let python = mp_eval::pyenv::venv(root, ".cache/venv-gpu", "setup")?;
    let spec = format!("{GPU_PACKAGE}=={ORT_VERSION}");
    mp_eval::pyenv::ensure_packages(
        &python,
        "onnxruntime, nvidia.cudnn",
        &[&spec],
        "setup",
        " (the GPU build with CUDA and cuDNN: several GB)",
    )?;
    let out = Command::new(&python)
        .args([
            "-c",
            "import onnxruntime, os, glob, nvidia\n\
             capi = os.path.join(os.path.dirname(onnxruntime.__file__), 'capi')\n\
             print(os.path.join(capi, 'libonnxruntime.so.' + onnxruntime.__version__))\n\
             libs = sorted(glob.glob(os.path.join(list(nvidia.__path__)[0], '*', 'lib')))\n\
             print(':'.join([capi] + libs))",
        ])
        .output()
        .context("asking the GPU environment where its libraries are")?;
    if !out.status.success() {
        bail!(
            "the GPU environment does not import: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let mut lines = text.lines();
    let (Some(lib), Some(dirs)) = (lines.next(), lines.next()) else {
        bail!("the GPU environment did not name its libraries: {text}");
    };
    if !Path::new(lib).is_file() {
        bail!("the GPU build's library {lib} is missing");
    }
    let env = root.join(".cache/onnxruntime-gpu.env");
    crate::write_file(
        &env,
        format!(
            "# ONNX Runtime's GPU build for `mp` (written by `cargo xtask setup --gpu`)\n\
             export ORT_DYLIB_PATH={lib}\n\
             export LD_LIBRARY_PATH={dirs}${{LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}}\n"
        ),
    )?;
    println!(
        "setup: ONNX Runtime's GPU build is in {}; `source {}` before running `mp` to use it",
        python
            .parent()
            .and_then(Path::parent)
            .unwrap_or(root)
            .display(),
        env.display()
    );
    Ok(())
}

fn lib_name() -> String {
    format!("libonnxruntime.so.{ORT_VERSION}")
}

/// Installs the library (unless present) and returns its stable path
/// (`.cache/onnxruntime/lib/libonnxruntime.so`).
pub fn install_onnxruntime(root: &Path, force: bool) -> Result<PathBuf> {
    let dir = root.join(".cache/onnxruntime");
    let lib_dir = dir.join("lib");
    let versioned = lib_dir.join(lib_name());
    let stable = lib_dir.join("libonnxruntime.so");
    let present = std::fs::metadata(&versioned)
        .map(|m| m.len() > 1_000_000)
        .unwrap_or(false);
    if present && !force {
        link_stable_names(&lib_dir)?;
        println!(
            "setup: ONNX Runtime {ORT_VERSION} already installed at {}",
            stable.display()
        );
        return Ok(stable);
    }
    let wheels = dir.join("wheels");
    std::fs::create_dir_all(&wheels).with_context(|| format!("creating {}", wheels.display()))?;
    let wheel = match find_wheel(&wheels)? {
        Some(w) if !force => w,
        _ => {
            println!("setup: downloading onnxruntime=={ORT_VERSION} from PyPI (no dependencies)");
            pip_download(&wheels, &format!("onnxruntime=={ORT_VERSION}"))?;
            find_wheel(&wheels)?.with_context(|| {
                format!(
                    "pip reported success but no onnxruntime wheel is in {}",
                    wheels.display()
                )
            })?
        }
    };
    std::fs::create_dir_all(&lib_dir).with_context(|| format!("creating {}", lib_dir.display()))?;
    let member = format!("onnxruntime/capi/{}", lib_name());
    extract_zip_member(&wheel, &member, &versioned)?;
    link_stable_names(&lib_dir)?;
    println!(
        "setup: installed {} (from {})",
        versioned.display(),
        wheel.display()
    );
    Ok(stable)
}

fn find_wheel(dir: &Path) -> Result<Option<PathBuf>> {
    let prefix = format!("onnxruntime-{ORT_VERSION}-");
    let mut found = None;
    for e in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let p = e?.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name.starts_with(&prefix) && name.ends_with(".whl") {
            found = Some(p);
        }
    }
    Ok(found)
}

/// `python3 -m pip download --no-deps --only-binary=:all: -d DIR SPEC`.
pub fn pip_download(dir: &Path, spec: &str) -> Result<()> {
    let mut last_err = String::new();
    for python in ["python3", "python"] {
        let out = Command::new(python)
            .args([
                "-m",
                "pip",
                "download",
                "--no-deps",
                "--only-binary=:all:",
                "-d",
            ])
            .arg(dir)
            .arg(spec)
            .output();
        match out {
            Ok(o) if o.status.success() => return Ok(()),
            Ok(o) => {
                last_err = String::from_utf8_lossy(&o.stderr).trim().to_string();
            }
            Err(e) => last_err = format!("{python}: {e}"),
        }
    }
    bail!("`pip download {spec}` failed (Python 3 with pip is needed for set-up): {last_err}")
}

/// Extracts one member of a zip archive to `dest` (atomically, mode 0755).
pub fn extract_zip_member(archive: &Path, member: &str, dest: &Path) -> Result<()> {
    let f =
        std::fs::File::open(archive).with_context(|| format!("opening {}", archive.display()))?;
    let mut zip =
        zip::ZipArchive::new(f).with_context(|| format!("reading zip {}", archive.display()))?;
    let mut entry = zip
        .by_name(member)
        .with_context(|| format!("{} has no member {member}", archive.display()))?;
    let mut bytes = Vec::with_capacity(entry.size() as usize);
    entry
        .read_to_end(&mut bytes)
        .with_context(|| format!("extracting {member} from {}", archive.display()))?;
    let tmp = dest.with_extension("part");
    std::fs::write(&tmp, &bytes).with_context(|| format!("writing {}", tmp.display()))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&tmp, std::fs::Permissions::from_mode(0o755))?;
    }
    std::fs::rename(&tmp, dest).with_context(|| format!("moving {} into place", dest.display()))?;
    Ok(())
}

fn link_stable_names(lib_dir: &Path) -> Result<()> {
    for alias in ["libonnxruntime.so", "libonnxruntime.so.1"] {
        let p = lib_dir.join(alias);
        let ok = std::fs::read_link(&p)
            .map(|t| t == Path::new(&lib_name()))
            .unwrap_or(false);
        if ok {
            continue;
        }
        let _ = std::fs::remove_file(&p);
        #[cfg(unix)]
        std::os::unix::fs::symlink(lib_name(), &p)
            .with_context(|| format!("linking {}", p.display()))?;
        #[cfg(not(unix))]
        std::fs::copy(lib_dir.join(lib_name()), &p)
            .with_context(|| format!("copying {}", p.display()))?;
    }
    Ok(())
}

fn check_runtime(lib: &Path) -> Result<()> {
    // The library search of mp-pose must find what was just installed.
    let found = mp_onnx::find_library()
        .map_err(|e| anyhow::anyhow!("{e}"))
        .context("ONNX Runtime was installed but mp-pose cannot find it")?;
    mp_onnx::environment()
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("loading {}", lib.display()))?;
    println!("setup: ONNX Runtime loads from {}", found.display());
    Ok(())
}
