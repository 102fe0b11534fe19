//! One call for the learned refinement with the defaults of `mp refine`:
//! [`refine_default`] finds the model folder, reads the anchor concepts,
//! loads the networks, builds the [`NetRefiner`] and refines a track of any
//! supported skeleton ([`refine_any`]); [`RefineOptions`] holds everything it
//! reads. [`read_input`] reads what `mp refine` accepts (a track file, or a
//! CMU BVH file mapped onto the 20 MSR joints).

use std::path::{Path, PathBuf};

use mp_geom::read_track;
use mp_geom::Bvh;
use mp_geom::MsrAction3D;
use mp_geom::Track;
use mp_onnx::SessionParams;

use crate::concepts::Concepts;
use crate::error::{RefineError, Result};
use crate::learned::{NetRefineParams, NetRefiner, RefineMode};
use crate::mapped::{msr20_map, refine_any, MappedRefinement};
use crate::motion::bvh_to_msr20;
use crate::nets::RefineNets;

/// File name of the anchor concepts in a model folder.
pub const CONCEPTS_FILE: &str = "concepts.json";

/// Everything [`refine_default`] needs besides the track;
/// `RefineOptions::default()` is what `mp refine` uses without flags.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RefineOptions {
    /// Model folder. Default `None`: `MP_REFINE_MODELS` or `models/refine`
    /// ([`RefineNets::find_dir`]).
    pub models: Option<PathBuf>,
    /// Anchor concepts JSON. Default `None`: `CONCEPTS_FILE` in the model folder.
    pub concepts: Option<PathBuf>,
    /// MSR action (1–20) of the motion. Default `None`: the evaluator's prediction.
    pub action: Option<u32>,
    /// The refinement: which steps run ([`NetRefineParams::mode`],
    /// [`NetRefineParams::flaw_detection`]) and their thresholds. Default
    /// [`NetRefineParams::default`] (the flaw detector and its repair only);
    /// [`RefineOptions::generated`] starts from [`NetRefineParams::for_generated`].
    pub params: NetRefineParams,
    /// ONNX Runtime sessions of the networks. Default [`SessionParams::default`].
    pub session: SessionParams,
}

impl RefineOptions {
    /// Options for the output of a motion generator trained on the concepts'
    /// subjects: [`NetRefineParams::for_generated`] (flaw detector, then the
    /// anchor step moving flawed anchors to their nearest concept).
    pub fn generated() -> Self {
        RefineOptions {
            params: NetRefineParams::for_generated(),
            ..RefineOptions::default()
        }
    }

    /// Sets the flaw detector's threshold ([`NetRefineParams::flaw_probability`])
    /// and keeps the hysteresis threshold
    /// ([`NetRefineParams::flaw_extend_probability`]) consistent with it:
    /// without growth before (both equal, the default) there is none after;
    /// otherwise it is lowered to the new threshold where it was above it.
    pub fn set_flaw_probability(&mut self, p: f64) {
        let q = &mut self.params;
        if q.flaw_extend_probability >= q.flaw_probability || q.flaw_extend_probability > p {
            q.flaw_extend_probability = p;
        }
        q.flaw_probability = p;
    }

    /// Checks every field: the parameters ([`NetRefineParams::validate`]),
    /// that the steps chosen do something, the action and the sessions.
    pub fn validate(&self) -> Result<()> {
        self.params.validate()?;
        if !self.params.flaw_detection && self.params.mode == RefineMode::DetectorOnly {
            return Err(RefineError::param(
                "flaw_detection",
                "the flaw detector is off and the mode runs no other step, so nothing would be \
                 refined: switch the detector on or run the anchor step \
                 (RefineMode::AnchorsOnly or AnchorsAndTransitions)",
            ));
        }
        if let Some(a) = self.action {
            if !(1..=20).contains(&a) {
                return Err(RefineError::param(
                    "action",
                    format!("must be an MSR Action3D action in 1..=20, got {a}"),
                ));
            }
        }
        self.session.validate()?;
        Ok(())
    }

    /// The model folder: [`Self::models`], else the first standard one holding a manifest.
    pub fn model_dir(&self) -> Result<PathBuf> {
        match &self.models {
            Some(d) => Ok(d.clone()),
            None => RefineNets::find_dir(),
        }
    }

    /// The anchor concepts file for the model folder `model_dir`.
    pub fn concepts_path(&self, model_dir: &Path) -> PathBuf {
        self.concepts
            .clone()
            .unwrap_or_else(|| model_dir.join(CONCEPTS_FILE))
    }
}

/// Reads anchor concepts (written by `mp concepts` or the training); errors
/// name the file.
pub fn read_concepts(path: &Path) -> Result<Concepts> {
    let text = std::fs::read_to_string(path).map_err(|e| RefineError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(
            e.kind(),
            format!("reading anchor concepts: {e} (learn them with `mp concepts`)"),
        ),
    })?;
    Concepts::from_json(&text).map_err(|e| RefineError::Model {
        model: path.display().to_string(),
        reason: format!("invalid anchor concepts: {e}"),
    })
}

/// A track file (any format `mp_geom::read_track` reads), or a CMU BVH
/// file (`.bvh`) mapped onto the 20 MSR joints at MSR Action3D's frame rate
/// (`bvh_scale`: BVH length unit → metres).
pub fn read_input(path: &Path, bvh_scale: f64) -> Result<Track> {
    let is_bvh = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"));
    if is_bvh {
        let bvh = Bvh::read(path)?;
        bvh_to_msr20(&bvh, bvh_scale, MsrAction3D::FPS)
    } else {
        Ok(read_track(path)?)
    }
}

/// Refines `track` (20 MSR joints in 3D, or BlazePose-33 world landmarks,
/// see `crate::mapped`) with the networks and concepts that `opts` names:
/// options checked, the track checked before the networks are loaded, the
/// model folder found, the networks loaded, the concepts read, then
/// [`refine_any`] with `opts.action`.
pub fn refine_default(track: &Track, opts: &RefineOptions) -> Result<MappedRefinement> {
    opts.validate()?;
    msr20_map(track)?;
    let dir = opts.model_dir()?;
    let nets = RefineNets::load(&dir, &opts.session)?;
    let concepts = read_concepts(&opts.concepts_path(&dir))?;
    let refiner = NetRefiner::new(&nets, &concepts, &opts.params)?;
    refine_any(&refiner, track, opts.action)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::learned::AnchorRepair;

    #[test]
    fn defaults_are_those_of_the_refinement() {
        let d = RefineOptions::default();
        assert_eq!(d.params, NetRefineParams::default());
        assert!(d.validate().is_ok());
        let g = RefineOptions::generated();
        assert_eq!(g.params, NetRefineParams::for_generated());
        assert_eq!(g.params.anchor_repair, AnchorRepair::NearestConcept);
        assert!(g.validate().is_ok());
        let dir = Path::new("/models");
        assert_eq!(d.concepts_path(dir), dir.join(CONCEPTS_FILE));
    }

    #[test]
    fn a_refinement_without_a_step_and_bad_actions_are_refused() {
        let mut o = RefineOptions::default();
        o.params.flaw_detection = false;
        let e = o.validate().unwrap_err();
        assert!(
            matches!(
                e,
                RefineError::InvalidParam {
                    name: "flaw_detection",
                    ..
                }
            ),
            "{e}"
        );
        o.params.mode = RefineMode::AnchorsOnly;
        assert!(o.validate().is_ok());
        for a in [0, 21] {
            let o = RefineOptions {
                action: Some(a),
                ..RefineOptions::default()
            };
            assert!(o.validate().is_err(), "action {a}");
        }
    }

    #[test]
    fn the_flaw_threshold_keeps_the_hysteresis_consistent() {
        for p in [0.5, 0.7, 0.9] {
            let mut o = RefineOptions::default();
            o.set_flaw_probability(p);
            assert_eq!(o.params.flaw_probability, p);
            // no growth by default, none after
            assert_eq!(o.params.flaw_extend_probability, p);
            assert!(o.validate().is_ok());
        }
        let mut o = RefineOptions::default();
        o.params.flaw_extend_probability = 0.3;
        o.set_flaw_probability(0.9);
        assert_eq!(o.params.flaw_extend_probability, 0.3);
        o.set_flaw_probability(0.2);
        assert_eq!(o.params.flaw_extend_probability, 0.2);
        assert!(o.validate().is_ok());
    }

    #[test]
    fn invalid_concepts_name_the_file_and_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("concepts.json");
        let text = r#"{"dim": 3, "params": {"method": {"KMeans": {"n_clusters": 2, "n_runs": 1,
            "max_iterations": 10}}, "root_joint": null, "scale_normalise": true,
            "gmm_components": 1, "gmm_reg_covariance": 0.001, "gmm_n_runs": 1,
            "score_quantile": 0.05, "seed": 0},
            "actions": {"1": {"action": 1, "centroids": [[0.0, 0.0]], "labels": [],
            "gmm": {"dim": 3, "weights": [1.0], "means": [[0.0, 0.0, 0.0]],
            "covariances": [[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]]},
            "score_threshold": -3.0}}}"#;
        std::fs::write(&p, text).unwrap();
        let e = read_concepts(&p).unwrap_err().to_string();
        assert!(
            e.contains(&p.display().to_string()) && e.contains("`centroids`[0] has 2 values"),
            "{e}"
        );
        std::fs::write(&p, text.replace("[[0.0, 0.0]]", "[[0.0, 0.0, 0.0]]")).unwrap();
        read_concepts(&p).unwrap();
        std::fs::write(
            &p,
            text.replace("[[0.0, 0.0]]", "[[0.0, 0.0, 0.0]]")
                .replace("\"weights\": [1.0]", "\"weights\": [-1.0]"),
        )
        .unwrap();
        let e = read_concepts(&p).unwrap_err().to_string();
        assert!(
            e.contains(&p.display().to_string()) && e.contains("`gmm.weights[0]` is negative"),
            "{e}"
        );
    }

    #[test]
    fn missing_concepts_are_named() {
        let e = read_concepts(Path::new("/nonexistent/concepts.json"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("/nonexistent/concepts.json") && e.contains("mp concepts"),
            "{e}"
        );
    }
}
