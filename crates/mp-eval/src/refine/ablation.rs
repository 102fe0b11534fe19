//! The ablation of [`crate::refine::evaluation::evaluate`]: anchor-only vs
//! anchors + transitions, the flaw detector on and off, the anchor decoder
//! vs bridges, and the anchor quality score — the Gaussian mixture of the
//! committed concepts vs the distance to the nearest concept with concepts
//! relearned (k-means, DBSCAN, OPTICS, hierarchical) from the training
//! subjects' segmentation anchors. Each setting is scored on the injected
//! flaws of the evaluation subjects and on the generated clips.
//!
//! The relearned-concept rows need clips of the training subjects
//! ([`RefineEvalParams::concept_subjects`]); on data without any they are
//! left out and the other rows are reported.

use std::collections::BTreeMap;

use mp_geom::MsrAction3D;
use ndarray::{Array2, Array3};
use serde::{Deserialize, Serialize};

use crate::refine::evaluation::{
    evaluate_injected_nets, evaluator_outputs, refine_clips, usable_clips, RefineEvalParams,
};
use crate::refine::quality::{accuracy, fid};
use crate::refine::split::subjects_of;
use crate::refine::RefineResult as Result;
use mp_refine::RefineNets;
use mp_refine::HIP_CENTRE;
use mp_refine::{learn_concepts, msr_anchor_samples, ConceptParams, Concepts};
use mp_refine::{
    nearest_concept_thresholds, AnchorDetection, AnchorRepair, NetRefineParams, NetRefiner,
    RefineMode, TransitionMethod,
};

/// One ablation setting on generated clips and injected flaws.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AblationRow {
    /// Setting.
    pub name: String,
    /// FID after refinement.
    pub fid_after: f64,
    /// Accuracy after refinement.
    pub accuracy_after: f64,
    /// Share of generated clips changed.
    pub changed_share: f64,
    /// Injected flaws: MPJPE after refinement (metres).
    pub injected_mpjpe_after_m: f64,
    /// Injected flaws: relative reduction.
    pub injected_reduction: f64,
    /// Clean clips: MPJPE change (metres).
    pub clean_change_m: f64,
}

/// The generated clips of the evaluation and the real features they are compared with.
pub(crate) struct GeneratedSet<'a> {
    /// Canonical clips, `N × 60 × 60` features.
    pub clips: &'a Array3<f32>,
    /// Their actions.
    pub labels: &'a [u32],
    /// Evaluator features of the real clips.
    pub real_features: &'a Array2<f64>,
}

/// An ablation setting: name, concepts, parameters, nearest-concept thresholds.
type Setting<'a> = (
    &'static str,
    &'a Concepts,
    &'a NetRefineParams,
    Option<&'a BTreeMap<u32, f64>>,
);

/// Concepts relearned from the training subjects' anchors, with the
/// nearest-concept thresholds of each clustering.
struct Relearned {
    kmeans: Concepts,
    dbscan: Concepts,
    optics: Concepts,
    hierarchical: Concepts,
    thresholds: [BTreeMap<u32, f64>; 4],
}

/// The subjects whose clips the concepts are relearned from.
fn concept_subjects(data: &MsrAction3D, params: &RefineEvalParams) -> Vec<u32> {
    match &params.concept_subjects {
        Some(s) => s.clone(),
        None => subjects_of(data)
            .into_iter()
            .filter(|s| !params.val_subjects.contains(s))
            .collect(),
    }
}

fn relearn(
    data: &MsrAction3D,
    concepts: &Concepts,
    params: &RefineEvalParams,
) -> Result<Option<Relearned>> {
    let train_idx = usable_clips(data, &concept_subjects(data, params), params);
    if train_idx.is_empty() {
        return Ok(None);
    }
    let kmeans_params = ConceptParams {
        root_joint: Some(HIP_CENTRE),
        seed: params.seed,
        score_quantile: params.score_quantile,
        ..concepts.params.clone()
    };
    let samples = msr_anchor_samples(data, &train_idx, &params.segment, &kmeans_params)?;
    let with = |method: &mp_refine::ClusterMethod| ConceptParams {
        method: method.clone(),
        ..kmeans_params.clone()
    };
    let kmeans = learn_concepts(&samples, &kmeans_params)?;
    let dbscan = learn_concepts(&samples, &with(&params.dbscan))?;
    let optics = learn_concepts(&samples, &with(&params.optics))?;
    let hierarchical = learn_concepts(&samples, &with(&params.hierarchical))?;
    let q = params.score_quantile;
    let thresholds = [
        nearest_concept_thresholds(&kmeans, &samples, q)?,
        nearest_concept_thresholds(&dbscan, &samples, q)?,
        nearest_concept_thresholds(&optics, &samples, q)?,
        nearest_concept_thresholds(&hierarchical, &samples, q)?,
    ];
    Ok(Some(Relearned {
        kmeans,
        dbscan,
        optics,
        hierarchical,
        thresholds,
    }))
}

/// Every ablation row (see the module docs).
pub(crate) fn ablation_rows(
    data: &MsrAction3D,
    nets: &RefineNets,
    concepts: &Concepts,
    params: &RefineEvalParams,
    generated: &GeneratedSet<'_>,
) -> Result<Vec<AblationRow>> {
    let relearned = relearn(data, concepts, params)?;
    // The anchor and transition steps, with and without the detector first.
    let steps = NetRefineParams {
        mode: RefineMode::AnchorsAndTransitions,
        ..params.refine.clone()
    };
    let no_detector = NetRefineParams {
        flaw_detection: false,
        ..steps.clone()
    };
    let detector_only = NetRefineParams {
        mode: RefineMode::DetectorOnly,
        ..params.refine.clone()
    };
    let anchors_only = NetRefineParams {
        mode: RefineMode::AnchorsOnly,
        ..steps.clone()
    };
    let network_repair = NetRefineParams {
        anchor_repair: AnchorRepair::Network,
        ..steps.clone()
    };
    let segmentation = NetRefineParams {
        anchor_source: AnchorDetection::Segmentation,
        ..steps.clone()
    };
    let generator = NetRefineParams {
        transition_method: TransitionMethod::Generator,
        ..steps.clone()
    };
    let gen_transitions = NetRefineParams {
        mode: RefineMode::AnchorsAndTransitions,
        ..params.generated_refine.clone()
    };
    let gen_network = NetRefineParams {
        anchor_repair: AnchorRepair::Network,
        ..params.generated_refine.clone()
    };
    let gen_no_detector = NetRefineParams {
        flaw_detection: false,
        ..params.generated_refine.clone()
    };
    let gen_preset = &params.generated_refine;
    let mut settings: Vec<Setting<'_>> = vec![
        ("generated_preset", concepts, gen_preset, None),
        (
            "generated_preset_no_detector",
            concepts,
            &gen_no_detector,
            None,
        ),
        (
            "generated_preset_anchors_transitions",
            concepts,
            &gen_transitions,
            None,
        ),
        (
            "generated_preset_network_anchor_repair",
            concepts,
            &gen_network,
            None,
        ),
    ];
    if let Some(r) = &relearned {
        settings.extend([
            (
                "generated_preset_kmeans_relearned",
                &r.kmeans,
                gen_preset,
                None,
            ),
            ("generated_preset_dbscan", &r.dbscan, gen_preset, None),
            ("generated_preset_optics", &r.optics, gen_preset, None),
            (
                "generated_preset_hierarchical",
                &r.hierarchical,
                gen_preset,
                None,
            ),
        ]);
    }
    settings.extend([
        ("detector_only", concepts, &detector_only, None),
        (
            "no_detector_anchors_transitions_gmm",
            concepts,
            &no_detector,
            None,
        ),
        ("anchors_only_gmm", concepts, &anchors_only, None),
        ("anchors_transitions_gmm", concepts, &steps, None),
        ("anchor_network_repair", concepts, &network_repair, None),
        ("segmentation_anchors", concepts, &segmentation, None),
        ("generator_transitions", concepts, &generator, None),
    ]);
    if let Some(r) = &relearned {
        let [th_k, th_d, th_o, th_h] = &r.thresholds;
        settings.extend([
            (
                "anchors_transitions_nearest_kmeans",
                &r.kmeans,
                &steps,
                Some(th_k),
            ),
            (
                "anchors_transitions_nearest_dbscan",
                &r.dbscan,
                &steps,
                Some(th_d),
            ),
            (
                "anchors_transitions_nearest_optics",
                &r.optics,
                &steps,
                Some(th_o),
            ),
            (
                "anchors_transitions_nearest_hierarchical",
                &r.hierarchical,
                &steps,
                Some(th_h),
            ),
        ]);
    }
    let mut rows = Vec::with_capacity(settings.len());
    for (name, c, p, th) in settings {
        let mut r = NetRefiner::new(nets, c, p)?;
        if let Some(t) = th {
            r = r.with_nearest_concept(t);
        }
        let inj = evaluate_injected_nets(data, &r, params)?;
        let (refined, _, changed) = refine_clips(&r, generated.clips, generated.labels)?;
        let (rf, rl) = evaluator_outputs(nets, &refined)?;
        rows.push(AblationRow {
            name: name.to_string(),
            fid_after: fid(rf.view(), generated.real_features.view())?,
            accuracy_after: accuracy(rl.view(), generated.labels)?,
            changed_share: changed,
            injected_mpjpe_after_m: inj.mpjpe_after_m,
            injected_reduction: inj.reduction,
            clean_change_m: inj.clean_change_m,
        });
    }
    Ok(rows)
}
