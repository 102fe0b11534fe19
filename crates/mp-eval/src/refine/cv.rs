//! Cross-validation of the flaw detector over subjects.
//!
//! [`folds`] cuts the subjects into folds: fold `i` scores subject `S[i]`,
//! chooses the detector's epoch (and, pooled with the other folds, the
//! refinement's settings) on `S[i − 1]` and trains on every other subject.
//! [`pool`] adds the injected-flaw figures of several subjects (weighted
//! by their (clip, flaw) cases), and [`choose_setting`] picks one setting of
//! a grid from the pooled figures of the selection subjects: the lowest
//! injected MPJPE among the settings that make no flaw kind worse. For the
//! figure of a held-out subject the folds that chose on that subject are
//! left out of the pool, so no figure is measured on a subject its network
//! was trained on or its settings were chosen on.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::refine::evaluation::InjectedReport;
use crate::refine::RefineResult as Result;
use mp_refine::RefineError;

/// One cross-validation fold.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fold {
    /// The scored subject (neither trained nor selected on).
    pub test: u32,
    /// The subject the epoch and settings are chosen on.
    pub select: u32,
    /// The training subjects.
    pub train: Vec<u32>,
}

/// Folds over `subjects` (at least 3, no repeats): fold `i` scores
/// `subjects[i]`, selects on `subjects[i − 1]` (cyclically) and trains on
/// the rest.
pub fn folds(subjects: &[u32]) -> Result<Vec<Fold>> {
    if subjects.len() < 3 {
        return Err(RefineError::param(
            "cv_subjects",
            format!("need at least 3 subjects (train, select, test), got {subjects:?}"),
        ));
    }
    let mut seen = subjects.to_vec();
    seen.sort_unstable();
    seen.dedup();
    if seen.len() != subjects.len() {
        return Err(RefineError::param(
            "cv_subjects",
            format!("subjects repeat in {subjects:?}"),
        ));
    }
    let n = subjects.len();
    Ok((0..n)
        .map(|i| {
            let test = subjects[i];
            let select = subjects[(i + n - 1) % n];
            Fold {
                test,
                select,
                train: subjects
                    .iter()
                    .copied()
                    .filter(|&s| s != test && s != select)
                    .collect(),
            }
        })
        .collect())
}

/// The folder of the fold that scores `test` under `base`.
pub fn fold_dir(base: &Path, test: u32) -> PathBuf {
    base.join(format!("test{test}"))
}

/// Injected-flaw figures pooled over several reports (metres).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pooled {
    /// (clip, flaw) cases.
    pub cases: usize,
    /// MPJPE flawed vs clean.
    pub before_m: f64,
    /// MPJPE refined vs clean.
    pub after_m: f64,
    /// `1 − after / before`.
    pub reduction: f64,
    /// Per flaw kind: (name, cases, before, after).
    pub per_flaw: Vec<(String, usize, f64, f64)>,
    /// Flaw kinds whose pooled MPJPE after refinement exceeds the one before.
    pub worse: Vec<String>,
    /// Clean-clip change, weighted by clips.
    pub clean_change_m: f64,
}

/// Pools reports of the same flaw list, weighting every (clip, flaw) case
/// equally. Errors when there is none or their flaw lists differ.
pub fn pool(reports: &[&InjectedReport]) -> Result<Pooled> {
    let first = reports
        .first()
        .ok_or_else(|| RefineError::param("pool", "no report to pool"))?;
    let names: Vec<&str> = first.per_flaw.iter().map(|f| f.flaw.as_str()).collect();
    let mut per: Vec<(String, usize, f64, f64)> =
        names.iter().map(|n| (n.to_string(), 0, 0.0, 0.0)).collect();
    let (mut clean, mut clips) = (0.0, 0usize);
    for r in reports {
        let these: Vec<&str> = r.per_flaw.iter().map(|f| f.flaw.as_str()).collect();
        if these != names {
            return Err(RefineError::param(
                "pool",
                format!("flaw lists differ: {names:?} and {these:?}"),
            ));
        }
        for (p, f) in per.iter_mut().zip(&r.per_flaw) {
            p.1 += f.n_clips;
            p.2 += f.n_clips as f64 * f.mpjpe_before_m;
            p.3 += f.n_clips as f64 * f.mpjpe_after_m;
        }
        clean += r.n_clips as f64 * r.clean_change_m;
        clips += r.n_clips;
    }
    let cases: usize = per.iter().map(|p| p.1).sum();
    let before = per.iter().map(|p| p.2).sum::<f64>() / cases.max(1) as f64;
    let after = per.iter().map(|p| p.3).sum::<f64>() / cases.max(1) as f64;
    for p in per.iter_mut() {
        let n = p.1.max(1) as f64;
        p.2 /= n;
        p.3 /= n;
    }
    let worse = per
        .iter()
        .filter(|p| p.1 > 0 && p.3 > p.2)
        .map(|p| p.0.clone())
        .collect();
    Ok(Pooled {
        cases,
        before_m: before,
        after_m: after,
        reduction: if before > 0.0 {
            1.0 - after / before
        } else {
            f64::NAN
        },
        per_flaw: per,
        worse,
        clean_change_m: clean / clips.max(1) as f64,
    })
}

/// The setting chosen from pooled figures (one per setting, same order as
/// the grid): the lowest MPJPE after refinement among the settings that
/// make no flaw kind worse, or, when every setting makes one worse, the
/// lowest overall (second value `false`). Ties keep the earlier setting.
pub fn choose_setting(pooled: &[Pooled]) -> Result<(usize, bool)> {
    if pooled.is_empty() {
        return Err(RefineError::param("choose_setting", "empty grid"));
    }
    let best = |ok: &dyn Fn(&Pooled) -> bool| {
        pooled
            .iter()
            .enumerate()
            .filter(|(_, p)| ok(p))
            .fold(None::<(usize, f64)>, |b, (i, p)| match b {
                Some((_, v)) if v <= p.after_m => b,
                _ => Some((i, p.after_m)),
            })
            .map(|(i, _)| i)
    };
    match best(&|p| p.worse.is_empty()) {
        Some(i) => Ok((i, true)),
        None => Ok((best(&|_| true).unwrap_or(0), false)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine::evaluation::InjectedFlawReport;

    fn report(n: usize, flaws: &[(&str, f64, f64)]) -> InjectedReport {
        InjectedReport {
            n_clips: n,
            mpjpe_before_m: 0.0,
            mpjpe_after_m: 0.0,
            baseline_after_m: 0.0,
            reduction: 0.0,
            clean_change_m: 0.001,
            clean_changed_share: 0.0,
            clean_flagged_frame_share: 0.0,
            detector_precision: 0.0,
            detector_recall: 0.0,
            per_flaw: flaws
                .iter()
                .map(|&(f, b, a)| InjectedFlawReport {
                    flaw: f.into(),
                    n_clips: n,
                    mpjpe_before_m: b,
                    mpjpe_after_m: a,
                    baseline_after_m: 0.0,
                    changed_share: 0.0,
                    detector_precision: 0.0,
                    detector_recall: 0.0,
                    foot_slide_before: f64::NAN,
                    foot_slide_after: f64::NAN,
                })
                .collect(),
        }
    }

    #[test]
    fn folds_rotate_and_never_overlap() {
        let f = folds(&[1, 3, 5, 7, 9]).unwrap();
        assert_eq!(f.len(), 5);
        assert_eq!(
            f[4],
            Fold {
                test: 9,
                select: 7,
                train: vec![1, 3, 5]
            }
        );
        assert_eq!(
            f[0],
            Fold {
                test: 1,
                select: 9,
                train: vec![3, 5, 7]
            }
        );
        for x in &f {
            assert!(!x.train.contains(&x.test) && !x.train.contains(&x.select));
            assert_ne!(x.test, x.select);
        }
        // Every subject is scored once and selected on once.
        let mut t: Vec<u32> = f.iter().map(|x| x.test).collect();
        let mut s: Vec<u32> = f.iter().map(|x| x.select).collect();
        t.sort_unstable();
        s.sort_unstable();
        assert_eq!(t, s);
        assert!(folds(&[1, 3]).is_err());
        assert!(folds(&[1, 3, 3]).is_err());
        assert_eq!(fold_dir(Path::new("/x"), 9), PathBuf::from("/x/test9"));
    }

    #[test]
    fn pooling_weights_cases_and_the_choice_avoids_worse_kinds() {
        let a = report(10, &[("jump", 0.02, 0.01), ("foot_slide", 0.003, 0.002)]);
        let b = report(30, &[("jump", 0.01, 0.006), ("foot_slide", 0.003, 0.0035)]);
        let p = pool(&[&a, &b]).unwrap();
        assert_eq!(p.cases, 80);
        // jump: (10·0.02 + 30·0.01)/40 = 0.0125 before, (0.1 + 0.18)/40 = 0.007 after.
        assert!((p.per_flaw[0].2 - 0.0125).abs() < 1e-12);
        assert!((p.per_flaw[0].3 - 0.007).abs() < 1e-12);
        // foot slide: 0.003 → (0.02 + 0.105)/40 = 0.003125: worse.
        assert!((p.per_flaw[1].3 - 0.003125).abs() < 1e-12);
        assert_eq!(p.worse, vec!["foot_slide".to_string()]);
        assert!((p.after_m - (0.007 + 0.003125) / 2.0).abs() < 1e-12);
        // A setting that is better overall but makes a kind worse loses.
        let c = report(
            40,
            &[("jump", 0.0125, 0.0080), ("foot_slide", 0.003, 0.0029)],
        );
        let q = pool(&[&c]).unwrap();
        assert!(q.worse.is_empty());
        assert!(q.after_m > p.after_m);
        assert_eq!(choose_setting(&[p.clone(), q.clone()]).unwrap(), (1, true));
        assert_eq!(
            choose_setting(std::slice::from_ref(&p)).unwrap(),
            (0, false)
        );
        assert!(choose_setting(&[]).is_err());
        let d = report(5, &[("jump", 0.01, 0.01)]);
        assert!(pool(&[&a, &d]).is_err());
        assert!(pool(&[]).is_err());
    }
}
