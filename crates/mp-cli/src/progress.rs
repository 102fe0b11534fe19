//! Progress bars for the pipeline's stages, and Ctrl-C as a cancellation.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, Once, OnceLock};
use std::time::Duration;

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use mp_geom::CancelToken;
use mp_pipeline::{Observer, Stage, StageTime};

/// One progress bar per running stage (hidden when quiet).
pub struct Bars {
    multi: MultiProgress,
    bars: Mutex<HashMap<Stage, ProgressBar>>,
    quiet: bool,
}

impl Bars {
    /// Bars on standard error, or none when `quiet`.
    pub fn new(quiet: bool) -> Self {
        let multi = if quiet {
            MultiProgress::with_draw_target(ProgressDrawTarget::hidden())
        } else {
            MultiProgress::new()
        };
        Bars {
            multi,
            bars: Mutex::new(HashMap::new()),
            quiet,
        }
    }
}

/// A bar of `len` steps, or a spinner.
pub fn bar(len: Option<usize>, msg: &str, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = match len {
        Some(n) => ProgressBar::new(n as u64),
        None => ProgressBar::new_spinner(),
    };
    let template = if len.is_some() {
        "{spinner:.green} {msg:<12} [{bar:36.cyan/blue}] {pos}/{len} ({per_sec}, eta {eta})"
    } else {
        "{spinner:.green} {msg:<12} {elapsed}"
    };
    if let Ok(style) = ProgressStyle::with_template(template) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(msg.to_string());
    if len.is_none() {
        pb.enable_steady_tick(Duration::from_millis(120));
    }
    pb
}

impl Observer for Bars {
    fn started(&self, stage: Stage, total: Option<usize>) {
        let pb = self.multi.add(bar(total, stage.name(), self.quiet));
        if let Ok(mut b) = self.bars.lock() {
            b.insert(stage, pb);
        }
    }

    fn progress(&self, stage: Stage, done: usize) {
        if let Ok(b) = self.bars.lock() {
            if let Some(pb) = b.get(&stage) {
                pb.set_position(done as u64);
            }
        }
    }

    fn finished(&self, time: &StageTime) {
        if let Ok(mut b) = self.bars.lock() {
            if let Some(pb) = b.remove(&time.stage) {
                pb.finish_and_clear();
            }
        }
    }
}

impl Drop for Bars {
    fn drop(&mut self) {
        if let Ok(mut b) = self.bars.lock() {
            for (_, pb) in b.drain() {
                pb.finish_and_clear();
            }
        }
    }
}

static HANDLER: Once = Once::new();
static TOKEN: OnceLock<CancelToken> = OnceLock::new();
/// Whether the running command checks the token (set by [`ctrl_c_token`]).
static OBSERVED: AtomicBool = AtomicBool::new(false);

/// Removes every partial output of the process (files being written and
/// staging folders) and exits with status 130, holding the locks that
/// renames take so that nothing appears meanwhile.
fn exit_interrupted() -> ! {
    let _files = mp_geom::abandon_partial_writes();
    let _staging = mp_report::emergency_cleanup();
    eprintln!("\ninterrupted");
    std::process::exit(130);
}

/// Installs the Ctrl-C handler of the process (once, at start). A command
/// that checks [`ctrl_c_token`] is cancelled and stops at its next check;
/// any other command exits at once. Either way a file being written is
/// removed, never left half written, and earlier outputs stay as they were.
pub fn install_ctrl_c() {
    HANDLER.call_once(|| {
        let token = TOKEN.get_or_init(CancelToken::new).clone();
        let res = ctrlc::set_handler(move || {
            if !OBSERVED.load(Ordering::SeqCst) || token.is_cancelled() {
                exit_interrupted();
            }
            token.cancel();
            std::thread::spawn(|| {
                std::thread::sleep(Duration::from_secs(3));
                exit_interrupted();
            });
        });
        if let Err(e) = res {
            eprintln!("warning: cannot install the Ctrl-C handler: {e}");
        }
    });
}

/// The token that Ctrl-C cancels. The first Ctrl-C cancels it: the run stops
/// at its next check and removes its staging folder; if it has not finished
/// within 3 s, or at a second Ctrl-C, every partial output of the process is
/// removed and the process exits with status 130.
pub fn ctrl_c_token() -> CancelToken {
    install_ctrl_c();
    OBSERVED.store(true, Ordering::SeqCst);
    TOKEN.get_or_init(CancelToken::new).clone()
}
