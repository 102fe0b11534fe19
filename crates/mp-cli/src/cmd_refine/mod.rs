//! `mp refine` (learned motion refinement of a 20-joint 3D track or of
//! BlazePose-33 world landmarks, `mp_refine::mapped`) and
//! `mp concepts` (anchor concepts from MSR Action3D or a folder of tracks,
//! in [`concepts`]).

mod concepts;

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use clap::Args;
use mp_geom::write_track;
use mp_geom::Track;
use mp_refine::read_input;
use mp_refine::MappedRefinement;
use mp_refine::DEFAULT_BVH_LENGTH_SCALE;
use mp_refine::{refine_default, RefineOptions};
use mp_refine::{NetRefineParams, RefineMode, TransitionMethod};

pub use concepts::{concepts_cmd, ConceptsArgs};

/// Arguments of `mp refine`.
#[derive(Args, Debug)]
pub struct RefineArgs {
    /// Input track: 20 MSR Action3D joints in 3D, metres (npz, npy, json, csv, mpt); BlazePose-33 world landmarks (`mp extract VIDEO --world`), refined through the 20
    /// MSR joints and carried back; or a CMU BVH file (mapped onto the 20 joints).
    pub track: PathBuf,
    /// Output track (format by extension).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Model folder (default: `MP_REFINE_MODELS` or models/refine).
    #[arg(long)]
    pub models: Option<PathBuf>,
    /// Anchor concepts JSON (default: concepts.json in the model folder).
    #[arg(long)]
    pub concepts: Option<PathBuf>,
    /// MSR action (1–20) of the motion; default: the evaluator's prediction.
    #[arg(long)]
    pub action: Option<u32>,
    /// Also run the paper's anchor step (recognition, concept scores, repair of flawed anchors)
    /// after the flaw detector.
    #[arg(long)]
    pub anchors: bool,
    /// Also run the anchor step and the transition refinement after the flaw detector.
    #[arg(long, conflicts_with = "anchors")]
    pub transitions: bool,
    /// The track comes from a motion generator trained on the concepts' subjects: run the anchor
    /// step with the generated-motion settings (anchors scored below their action's threshold are
    /// moved to their nearest concept; `NetRefineParams::for_generated`).
    #[arg(long)]
    pub generated: bool,
    /// Switch the learned flaw detector off (with --anchors or --transitions).
    #[arg(long)]
    pub no_detector: bool,
    // Thresholds: `None` keeps the value of the starting parameters (`NetRefineParams::default()`,
    // or `for_generated()` with --generated); the help shows the default.
    #[arg(long, help = format!(
        "Flaw probability above which a (frame, joint) is refilled [default: {}]",
        NetRefineParams::default().flaw_probability
    ))]
    pub flaw_probability: Option<f64>,
    /// Regenerate transitions with the transition generator (z = 0) instead of the refinement network.
    #[arg(long)]
    pub generator_transitions: bool,
    #[arg(long, help = format!(
        "Anchor probability threshold [default: {}]",
        NetRefineParams::default().anchor_probability
    ))]
    pub anchor_probability: Option<f64>,
    #[arg(long, help = format!(
        "Transition deviation threshold (metres) [default: {}]",
        NetRefineParams::default().transition_deviation_m
    ))]
    pub deviation_m: Option<f64>,
    /// Also write the report as JSON.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// BVH length unit → metres (BVH input only).
    #[arg(long, default_value_t = DEFAULT_BVH_LENGTH_SCALE)]
    pub bvh_scale: f64,
}

impl RefineArgs {
    /// The library's options with these flags: `--generated` starts from
    /// `RefineOptions::generated()`, the step flags set the mode and the
    /// detector, the thresholds override only when given.
    pub fn options(&self) -> RefineOptions {
        let mut opts = if self.generated {
            RefineOptions::generated()
        } else {
            RefineOptions::default()
        };
        opts.models = self.models.clone();
        opts.concepts = self.concepts.clone();
        opts.action = self.action;
        let p = &mut opts.params;
        if self.transitions {
            p.mode = RefineMode::AnchorsAndTransitions;
        } else if self.anchors {
            p.mode = RefineMode::AnchorsOnly;
        }
        p.flaw_detection = !self.no_detector;
        if self.generator_transitions {
            p.transition_method = TransitionMethod::Generator;
        }
        if let Some(v) = self.anchor_probability {
            p.anchor_probability = v;
        }
        if let Some(v) = self.deviation_m {
            p.transition_deviation_m = v;
        }
        if let Some(v) = self.flaw_probability {
            opts.set_flaw_probability(v);
        }
        opts
    }
}

/// `mp refine`.
pub fn refine_cmd(a: &RefineArgs) -> anyhow::Result<()> {
    // BVH (CMU naming) is mapped onto the 20 MSR joints at 15 fps.
    let track = folder_track(&a.track, a.bvh_scale)
        .with_context(|| format!("reading {}", a.track.display()))?;
    if a.no_detector && !(a.anchors || a.transitions || a.generated) {
        bail!("--no-detector leaves nothing to do: add --anchors, --transitions or --generated");
    }
    let opts = a.options();
    let params = &opts.params;
    let mapped =
        refine_default(&track, &opts).with_context(|| format!("refining {}", a.track.display()))?;
    if let Some(map) = &mapped.map {
        println!(
            "{} joints mapped onto the {} MSR Action3D joints (hip centre, spine, neck, hands, feet and head derived); the refinement is carried back onto the {} joints",
            map.source().name,
            map.target().len(),
            map.source().len()
        );
    }
    let r = &mapped.msr;
    let msr_track = &r.track;
    let rep = &r.report;
    let predicted = if rep.action_predicted {
        " (predicted)"
    } else {
        ""
    };
    if params.mode == RefineMode::DetectorOnly {
        println!("action {}{predicted}", rep.action);
    } else {
        println!(
            "action {}{predicted}; {} anchors, {} transitions",
            rep.action,
            rep.anchors.len(),
            rep.transitions.len()
        );
    }
    if params.flaw_detection {
        if !rep.held_frames.is_empty() {
            println!(
                "held pose (frame repeats the previous one): {} frames, {:?}",
                rep.held_frames.len(),
                rep.held_frames
            );
        }
        if rep.repaired_runs.is_empty() {
            println!(
                "flaw detector: nothing above p = {:.2} ({} frames flagged)",
                params.flaw_probability,
                rep.flagged_frames.len()
            );
        } else {
            println!(
                "flaw detector: {} frames flagged; refilled (joint, frames):",
                rep.flagged_frames.len()
            );
            for run in &rep.repaired_runs {
                let name = msr_track
                    .skeleton()
                    .joints
                    .get(run.joint)
                    .map_or("?", |n| n.as_str());
                println!("  {name:<15} {:>4}–{:<4}", run.start, run.end);
            }
        }
    }
    if params.mode == RefineMode::DetectorOnly {
        return finish(a, &mapped, &track);
    }
    let flawed: Vec<_> = rep.flawed_anchors().collect();
    if flawed.is_empty() {
        println!("flawed anchors: none");
    } else {
        println!("flawed anchors (frame, anchor probability, score < threshold, repair):");
        for an in flawed {
            println!(
                "  frame {:>4}  p={:.2}  score {:>9.2} < {:.2}  {}",
                an.source_frame,
                an.probability,
                an.score.unwrap_or(f64::NAN),
                an.threshold,
                match (an.repaired, an.concept) {
                    (true, Some(c)) => format!("new pose, concept {c}"),
                    (true, None) => "bridged".to_string(),
                    (false, _) => "kept (gap too long to bridge)".to_string(),
                }
            );
        }
    }
    let refined: Vec<_> = rep.refined_transitions().collect();
    if refined.is_empty() {
        println!("refined transitions: none");
    } else {
        println!("refined transitions (frames, deviation from a cubic, reason):");
        for t in refined {
            println!(
                "  frames {:>4}–{:<4}  deviation {}  {:?}",
                t.source_frames.0,
                t.source_frames.1,
                t.deviation_m
                    .map_or("-".into(), |d| format!("{:.1} mm", d * 1e3)),
                t.refined.unwrap_or(mp_refine::TransitionReason::Deviation)
            );
        }
    }
    finish(a, &mapped, &track)
}

/// Prints the overall change and writes the refined track and the report.
fn finish(a: &RefineArgs, r: &MappedRefinement, track: &Track) -> anyhow::Result<()> {
    let change = mp_refine::mpjpe_abs(&r.track, track).unwrap_or(f64::NAN);
    println!("mean joint change: {:.1} mm", change * 1e3);
    write_track(&a.output, &r.track).with_context(|| format!("writing {}", a.output.display()))?;
    if let Some(p) = &a.report {
        mp_geom::write_atomic(p, serde_json::to_string_pretty(&r.msr.report)?.as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

/// A track file, or a CMU BVH file mapped onto the 20 MSR joints at MSR's
/// frame rate (`bvh_scale`: BVH length unit → metres; `mp_refine::read_input`).
fn folder_track(p: &Path, bvh_scale: f64) -> anyhow::Result<Track> {
    Ok(read_input(p, bvh_scale)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: RefineArgs,
    }

    fn options(flags: &[&str]) -> RefineOptions {
        let argv = ["mp", "in.json", "-o", "out.json"].iter().chain(flags);
        Cli::try_parse_from(argv).unwrap().args.options()
    }

    #[test]
    fn flags_map_onto_the_library_options() {
        assert_eq!(options(&[]), RefineOptions::default());
        assert_eq!(options(&["--generated"]), RefineOptions::generated());
        // thresholds given with --generated override only themselves
        let o = options(&[
            "--generated",
            "--anchor-probability",
            "0.4",
            "--deviation-m",
            "0.2",
        ]);
        let expected = NetRefineParams {
            anchor_probability: 0.4,
            transition_deviation_m: 0.2,
            ..NetRefineParams::for_generated()
        };
        assert_eq!(o.params, expected);
        let o = options(&[
            "--transitions",
            "--no-detector",
            "--flaw-probability",
            "0.5",
        ]);
        assert_eq!(o.params.mode, RefineMode::AnchorsAndTransitions);
        assert!(!o.params.flaw_detection);
        assert_eq!(o.params.flaw_probability, 0.5);
        assert!(o.validate().is_ok());
        let o = options(&["--anchors", "--generator-transitions", "--action", "7"]);
        assert_eq!(o.params.mode, RefineMode::AnchorsOnly);
        assert_eq!(o.params.transition_method, TransitionMethod::Generator);
        assert_eq!(o.action, Some(7));
    }
}
