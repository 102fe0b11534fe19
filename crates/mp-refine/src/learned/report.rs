//! What the refinement reports: the anchors it recognised and scored, the
//! transitions it kept or regenerated, the flagged cells and frames and the
//! refilled runs, and the canonical frames that changed.

use serde::{Deserialize, Serialize};

use crate::motion::NET_FRAMES;

/// One recognised anchor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AnchorReport {
    /// Canonical frame (0..60).
    pub frame: usize,
    /// The corresponding frame of the source track (rounded).
    pub source_frame: usize,
    /// Anchor probability from the recognition network.
    pub probability: f64,
    /// GMM log-likelihood of the anchor pose (`None` for the first and last frame).
    pub score: Option<f64>,
    /// The action's flaw threshold (score margin included).
    pub threshold: f64,
    /// Whether the anchor was judged flawed (score below the threshold).
    pub flawed: bool,
    /// Whether the flawed anchor was repaired (a bridge longer than
    /// [`NetRefineParams::max_bridge_frames`](super::NetRefineParams::max_bridge_frames) is not attempted).
    pub repaired: bool,
    /// Global concept id of a refined anchor (`(action − 1)·4 + cluster` in
    /// the committed models): from the refinement network's classifier, or
    /// the nearest concept for [`AnchorRepair::NearestConcept`](super::AnchorRepair::NearestConcept).
    pub concept: Option<usize>,
}

/// Why a transition was regenerated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum TransitionReason {
    /// Next to a refined anchor.
    NextToRefinedAnchor,
    /// Its frames deviate from their own cubic.
    Deviation,
}

/// One transition between consecutive anchors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TransitionReport {
    /// First canonical frame (an anchor).
    pub start: usize,
    /// Last canonical frame (the next anchor).
    pub end: usize,
    /// Source frames of `start` and `end`.
    pub source_frames: (usize, usize),
    /// Largest per-frame mean joint distance to its own cubic, metres
    /// (measured before the transition step; `None` when too short).
    pub deviation_m: Option<f64>,
    /// Why it was regenerated (`None`: kept).
    pub refined: Option<TransitionReason>,
}

/// A (canonical frame, joint) cell flagged by the flaw detector.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlawCell {
    /// Canonical frame (0..60).
    pub frame: usize,
    /// Joint (MSR order).
    pub joint: usize,
    /// Flaw probability.
    pub probability: f64,
}

/// A run of flagged frames of one joint that was refilled.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RepairedRun {
    /// Joint (MSR order).
    pub joint: usize,
    /// First refilled frame (source frames of the track; canonical frames
    /// for [`NetRefiner::refine_canonical`](super::NetRefiner::refine_canonical)).
    pub start: usize,
    /// Last refilled frame (inclusive).
    pub end: usize,
}

/// What the refinement found and did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefineReport {
    /// Action used for scoring (given or predicted).
    pub action: u32,
    /// Whether the action was predicted by the evaluator.
    pub action_predicted: bool,
    /// Anchors, first and last frame included.
    pub anchors: Vec<AnchorReport>,
    /// Transitions between consecutive anchors.
    pub transitions: Vec<TransitionReport>,
    /// Cells flagged by the flaw detector, with their probabilities.
    pub flaw_cells: Vec<FlawCell>,
    /// Frames (source frames of the track) where the detector flagged at
    /// least one joint, or that repeat a held pose, before dilation.
    pub flagged_frames: Vec<usize>,
    /// Frames that repeat the previous frame's pose
    /// ([`NetRefineParams::held_pose_tolerance`](super::NetRefineParams::held_pose_tolerance)).
    #[serde(default)]
    pub held_frames: Vec<usize>,
    /// Runs refilled by the flaw repair (after dilation).
    pub repaired_runs: Vec<RepairedRun>,
}

impl RefineReport {
    /// Anchors judged flawed.
    pub fn flawed_anchors(&self) -> impl Iterator<Item = &AnchorReport> {
        self.anchors.iter().filter(|a| a.flawed)
    }
    /// Transitions regenerated.
    pub fn refined_transitions(&self) -> impl Iterator<Item = &TransitionReport> {
        self.transitions.iter().filter(|t| t.refined.is_some())
    }
    /// Whether anything changed.
    pub fn changed(&self) -> bool {
        !self.repaired_runs.is_empty()
            || self.anchors.iter().any(|a| a.repaired)
            || self.refined_transitions().next().is_some()
    }
}

/// Canonical frames changed by the refinement: refined anchors and frames
/// strictly inside regenerated transitions.
pub fn changed_frames(anchors: &[AnchorReport], transitions: &[TransitionReport]) -> Vec<bool> {
    let mut changed = vec![false; NET_FRAMES];
    for a in anchors.iter().filter(|a| a.repaired) {
        if let Some(c) = changed.get_mut(a.frame) {
            *c = true;
        }
    }
    for t in transitions.iter().filter(|t| t.refined.is_some()) {
        let end = t.end.min(NET_FRAMES);
        if t.start + 1 < end {
            changed[t.start + 1..end].fill(true);
        }
    }
    changed
}
