//! One interface for the two refinements: the learned pipeline
//! ([`NetRefiner`]) and the spline baseline ([`BaselineRefiner`]), so a
//! caller (an evaluation, a comparison, a user trying both) can hold either
//! as a `&dyn Refiner`.

use mp_geom::Track;

use crate::baseline::{refine, RefineParams};
use crate::concepts::Concepts;
use crate::error::Result;
use crate::learned::NetRefiner;

/// A refined track and the frames the refinement changed.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The refined track (the input's frames, rate, confidence and skeleton).
    pub track: Track,
    /// Per frame of the input: whether the refinement moved a joint in it.
    pub changed: Vec<bool>,
}

/// Refines 3D motion of the 20 MSR Action3D joints (metres).
pub trait Refiner {
    /// Refines `track`, of action `action` (1–20) when it is known.
    fn refine(&self, track: &Track, action: Option<u32>) -> Result<Refined>;

    /// A short name for reports (`learned`, `baseline`).
    fn name(&self) -> &'static str;
}

/// The frames of `after` in which a joint moved from `before`.
fn changed_frames(before: &Track, after: &Track) -> Vec<bool> {
    let (a, b) = (before.positions(), after.positions());
    a.outer_iter()
        .zip(b.outer_iter())
        .map(|(x, y)| x.iter().zip(y.iter()).any(|(p, q)| p != q))
        .collect()
}

impl Refiner for NetRefiner<'_> {
    fn refine(&self, track: &Track, action: Option<u32>) -> Result<Refined> {
        let r = self.refine_track(track, action)?;
        Ok(Refined {
            changed: changed_frames(track, &r.track),
            track: r.track,
        })
    }

    fn name(&self) -> &'static str {
        "learned"
    }
}

/// The spline baseline ([`crate::baseline::refine`]) as a [`Refiner`]: its
/// parameters and, optionally, the concepts whose low-scoring anchors it
/// also repairs (used when the action is known).
#[derive(Debug, Clone, Copy)]
pub struct BaselineRefiner<'a> {
    /// The baseline's parameters.
    pub params: &'a RefineParams,
    /// Anchor concepts, read when the action is given.
    pub concepts: Option<&'a Concepts>,
}

impl Refiner for BaselineRefiner<'_> {
    fn refine(&self, track: &Track, action: Option<u32>) -> Result<Refined> {
        let concepts = self.concepts.zip(action);
        let r = refine(track, concepts, self.params)?;
        Ok(Refined {
            changed: changed_frames(track, &r.track),
            track: r.track,
        })
    }

    fn name(&self) -> &'static str {
        "baseline"
    }
}
