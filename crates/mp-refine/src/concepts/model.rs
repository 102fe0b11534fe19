//! The learned concepts: per action ([`ActionConcepts`]) and for every
//! action ([`Concepts`]), with JSON loading and its consistency checks.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{ConceptParams, Gmm};
use crate::error::{RefineError, Result};

/// Concepts of one action.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ActionConcepts {
    /// Action label.
    pub action: u32,
    /// Anchor concepts (cluster centres), one feature each.
    pub centroids: Vec<Vec<f64>>,
    /// Cluster of each training anchor (`None` = DBSCAN noise).
    pub labels: Vec<Option<usize>>,
    /// Quality model over the action's anchor features.
    pub gmm: Gmm,
    /// Anchors scoring below this log-likelihood are flawed.
    pub score_threshold: f64,
}

impl ActionConcepts {
    /// Index of and L2 distance to the nearest concept.
    pub fn nearest(&self, feature: &[f64]) -> Option<(usize, f64)> {
        self.centroids
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let d2: f64 = c.iter().zip(feature).map(|(a, b)| (a - b) * (a - b)).sum();
                (i, d2.sqrt())
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// Anchor concepts of every action, serialisable to JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Concepts {
    /// Feature dimension (`J · D`).
    pub dim: usize,
    /// Parameters they were learned with.
    pub params: ConceptParams,
    /// Per action.
    pub actions: BTreeMap<u32, ActionConcepts>,
}

impl Concepts {
    /// The concepts of `action`.
    pub fn action(&self, action: u32) -> Result<&ActionConcepts> {
        self.actions
            .get(&action)
            .ok_or(RefineError::UnknownAction(action))
    }
    /// Quality score (GMM log-likelihood) of a feature under `action`'s model.
    pub fn score(&self, action: u32, feature: &[f64]) -> Result<f64> {
        self.action(action)?.gmm.log_likelihood(feature)
    }
    /// Pretty JSON.
    pub fn to_json(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(self)?)
    }
    /// Parses JSON written by [`Concepts::to_json`] and checks it with
    /// [`Concepts::validate`].
    pub fn from_json(text: &str) -> Result<Self> {
        let c: Concepts = serde_json::from_str(text)?;
        c.validate()?;
        Ok(c)
    }

    /// Checks that the concepts are consistent: a feature dimension ≥ 1;
    /// valid learning parameters; per action, a key equal to its `action`,
    /// at most the method's number of concepts, concept features of `dim`
    /// finite values, labels that name existing concepts, a finite
    /// threshold and a valid quality model ([`Gmm::validate`] with the same
    /// dimension).
    ///
    /// Errors name the action and the field: [`RefineError::Shape`] for
    /// wrong lengths or counts, [`RefineError::NonFinite`] for NaN or
    /// infinite values, [`RefineError::InvalidParam`] for bad parameters.
    pub fn validate(&self) -> Result<()> {
        if self.dim == 0 {
            return Err(RefineError::Shape("concepts: `dim` is 0".into()));
        }
        self.params.validate()?;
        for (&key, ac) in &self.actions {
            let at = |field: &str| format!("concepts: action {key}: `{field}`");
            if ac.action != key {
                return Err(RefineError::Shape(format!(
                    "{} is {}, the key is {key}",
                    at("action"),
                    ac.action
                )));
            }
            if let Some(max) = self.params.method.max_concepts() {
                if ac.centroids.len() > max {
                    return Err(RefineError::Shape(format!(
                        "{} holds {} concepts, the {} method at most {max}",
                        at("centroids"),
                        ac.centroids.len(),
                        self.params.method.name()
                    )));
                }
            }
            for (i, c) in ac.centroids.iter().enumerate() {
                if c.len() != self.dim {
                    return Err(RefineError::Shape(format!(
                        "{}[{i}] has {} values, `dim` is {}",
                        at("centroids"),
                        c.len(),
                        self.dim
                    )));
                }
                if c.iter().any(|v| !v.is_finite()) {
                    return Err(RefineError::NonFinite(format!(
                        "{}[{i}] has a non-finite value",
                        at("centroids")
                    )));
                }
            }
            for (i, l) in ac.labels.iter().enumerate() {
                if let Some(l) = l {
                    if *l >= ac.centroids.len() {
                        return Err(RefineError::Shape(format!(
                            "{}[{i}] is {l}, there are {} concepts",
                            at("labels"),
                            ac.centroids.len()
                        )));
                    }
                }
            }
            if !ac.score_threshold.is_finite() {
                return Err(RefineError::NonFinite(format!(
                    "{} is {}",
                    at("score_threshold"),
                    ac.score_threshold
                )));
            }
            if ac.gmm.dim != self.dim {
                return Err(RefineError::Shape(format!(
                    "{} is {}, `dim` is {}",
                    at("gmm.dim"),
                    ac.gmm.dim,
                    self.dim
                )));
            }
            ac.gmm.validate().map_err(|e| match e {
                RefineError::Shape(m) => RefineError::Shape(format!("concepts: action {key}: {m}")),
                RefineError::NonFinite(m) => {
                    RefineError::NonFinite(format!("concepts: action {key}: {m}"))
                }
                other => other,
            })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_data::{blobs, params};
    use super::*;
    use crate::concepts::{learn_concepts, ClusterMethod};

    /// Concepts learned from the blobs, as JSON.
    fn concepts_json() -> serde_json::Value {
        let c = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3))).unwrap();
        serde_json::from_str(&c.to_json().unwrap()).unwrap()
    }

    /// The error of `from_json` on `v` changed by `edit`.
    fn load_error(edit: impl FnOnce(&mut serde_json::Value)) -> RefineError {
        let mut v = concepts_json();
        edit(&mut v);
        Concepts::from_json(&v.to_string()).expect_err("an invalid file loads")
    }

    #[test]
    fn concepts_round_trip_through_validation() {
        let v = concepts_json();
        let c = Concepts::from_json(&v.to_string()).unwrap();
        assert_eq!(c.dim, 3);
        c.validate().unwrap();
    }

    #[test]
    fn concepts_with_wrong_shapes_or_values_are_refused_by_field() {
        type Edit = Box<dyn Fn(&mut serde_json::Value)>;
        let cases: Vec<(Edit, &str, &str)> = vec![
            (
                Box::new(|v| v["actions"]["1"]["centroids"][0] = serde_json::json!([1.0, 2.0])),
                "shape",
                "`centroids`[0] has 2 values",
            ),
            (
                Box::new(|v| {
                    v["actions"]["1"]["gmm"]["means"][0] = serde_json::json!([1.0, 2.0, 3.0, 4.0])
                }),
                "shape",
                "`gmm.means[0]` has 4 values",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["covariances"][0] = serde_json::json!([1.0])),
                "shape",
                "`gmm.covariances[0]` has 1 values",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["weights"][0] = serde_json::json!(-0.5)),
                "shape",
                "`gmm.weights[0]` is negative",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["weights"][0] = serde_json::json!(7.0)),
                "shape",
                "`gmm.weights` sum to",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["means"] = serde_json::json!([])),
                "shape",
                "`gmm.means` 0",
            ),
            (
                Box::new(|v| {
                    v["actions"]["1"]["gmm"]["covariances"][0][1] = serde_json::json!(9.0)
                }),
                "shape",
                "not symmetric",
            ),
            (
                Box::new(|v| {
                    v["actions"]["1"]["gmm"]["covariances"][0] =
                        serde_json::json!([-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
                }),
                "shape",
                "not positive definite",
            ),
            (
                Box::new(|v| v["actions"]["1"]["gmm"]["dim"] = serde_json::json!(4)),
                "shape",
                "`gmm.dim` is 4",
            ),
            (
                Box::new(|v| v["actions"]["1"]["labels"][0] = serde_json::json!(7)),
                "shape",
                "`labels`[0] is 7",
            ),
            (
                Box::new(|v| v["actions"]["1"]["action"] = serde_json::json!(2)),
                "shape",
                "`action` is 2",
            ),
            (
                Box::new(|v| {
                    let c = v["actions"]["1"]["centroids"][0].clone();
                    v["actions"]["1"]["centroids"]
                        .as_array_mut()
                        .unwrap()
                        .extend([c.clone(), c]);
                }),
                "shape",
                "at most 3",
            ),
            (
                Box::new(|v| v["dim"] = serde_json::json!(0)),
                "shape",
                "`dim` is 0",
            ),
        ];
        for (edit, kind, needle) in cases {
            let e = load_error(edit);
            let msg = e.to_string();
            let ok = match kind {
                "shape" => matches!(e, RefineError::Shape(_)),
                _ => matches!(e, RefineError::Json(_)),
            };
            assert!(ok && msg.contains(needle), "{needle}: {e:?}");
            if kind == "shape" && needle != "`dim` is 0" {
                assert!(msg.contains("action 1"), "{msg}");
            }
        }
    }

    #[test]
    fn non_finite_values_in_concepts_are_refused() {
        let mut c = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3))).unwrap();
        let ac = c.actions.get_mut(&1).unwrap();
        ac.gmm.means[0][1] = f64::NAN;
        let e = c.validate().unwrap_err();
        assert!(
            matches!(&e, RefineError::NonFinite(m) if m.contains("`gmm.means[0]`") && m.contains("action 1")),
            "{e:?}"
        );
        let mut c = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3))).unwrap();
        c.actions.get_mut(&1).unwrap().score_threshold = f64::NAN;
        let e = c.validate().unwrap_err();
        assert!(
            matches!(&e, RefineError::NonFinite(m) if m.contains("`score_threshold`")),
            "{e:?}"
        );
        let mut c = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3))).unwrap();
        c.actions.get_mut(&1).unwrap().gmm.weights[0] = f64::INFINITY;
        let e = c.validate().unwrap_err();
        assert!(
            matches!(&e, RefineError::NonFinite(m) if m.contains("`gmm.weights[0]`")),
            "{e:?}"
        );
        // A bad covariance given directly to the score is an error, not a panic.
        let mut g = learn_concepts(&blobs(12), &params(ClusterMethod::kmeans(3)))
            .unwrap()
            .actions[&1]
            .gmm
            .clone();
        g.covariances[0].pop();
        assert!(matches!(
            g.log_likelihood(&[0.0, 0.0, 0.0]),
            Err(RefineError::Shape(_))
        ));
    }
}
