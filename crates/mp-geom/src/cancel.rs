//! Cooperative cancellation of long runs.
//!
//! A [`CancelToken`] is handed to a long computation (decoding, pose
//! estimation, the analysis pipeline, writing an output folder), which checks
//! it between steps and stops with its own "cancelled" error. Clones share
//! one flag, so a Ctrl-C handler, a GUI button or another thread can cancel a
//! run it gave a clone to; unrelated runs in the same process are unaffected.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A shared flag that asks a run to stop (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// A token that is not cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every run holding a clone of this token to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether [`CancelToken::cancel`] was called on this token or a clone.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_flag_and_new_tokens_do_not() {
        let a = CancelToken::new();
        let b = a.clone();
        let other = CancelToken::new();
        assert!(!b.is_cancelled());
        a.cancel();
        assert!(b.is_cancelled() && a.is_cancelled());
        assert!(!other.is_cancelled());
    }
}
