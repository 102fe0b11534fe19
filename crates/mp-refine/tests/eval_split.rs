//! The refinement evaluation on MSR Action3D files without subject 9: the
//! clips of every subject the training manifest does not name are scored,
//! or the subjects named explicitly. The files are built from clips of the
//! shared odd-subjects file (same keys), so the test is skipped, with a
//! message, where the shared data are absent.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

mod common;

use std::path::Path;

use mp_geom::io::datasets::MsrAction3D;
use mp_geom::io::npz::NpzOut;
use mp_refine::eval_refine::{evaluate, RefineEvalParams, RefineEvalReport};
use mp_refine::eval_split::{split_for, split_params, subjects_of, TrainingSubjects};
use mp_refine::nets::find_model_dir;
use ndarray::{concatenate, Array1, Axis};

/// Writes an MSR Action3D npz (the shared file's keys) holding `n` clips of
/// each `(source subject, subject written)` pair.
fn write_subset(data: &MsrAction3D, pairs: &[(u32, u32)], n: usize, path: &Path) {
    let (mut joints, mut conf) = (Vec::new(), Vec::new());
    let (mut offsets, mut action, mut subject, mut rep, mut name) =
        (vec![0i64], Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for &(from, to) in pairs {
        let clips = data
            .clips()
            .iter()
            .filter(|c| c.subject == from && (20..=120).contains(&c.rows.len()))
            .take(n);
        for c in clips {
            let t = data.clip(c.index).unwrap();
            joints.push(t.positions().to_owned());
            conf.push(t.confidence().to_owned());
            offsets.push(offsets.last().unwrap() + t.n_frames() as i64);
            action.push(i64::from(c.action));
            subject.push(i64::from(to));
            rep.push(i64::from(c.rep));
            name.push(format!("a{:02}_s{to:02}_e{:02}", c.action, c.rep));
        }
    }
    let jv: Vec<_> = joints.iter().map(|a| a.view()).collect();
    let cv: Vec<_> = conf.iter().map(|a| a.view()).collect();
    let mut z = NpzOut::new(true);
    z.add("joints", &concatenate(Axis(0), &jv).unwrap())
        .unwrap();
    z.add("conf", &concatenate(Axis(0), &cv).unwrap()).unwrap();
    z.add("offsets", &Array1::from(offsets)).unwrap();
    z.add("action", &Array1::from(action)).unwrap();
    z.add("subject", &Array1::from(subject)).unwrap();
    z.add("rep", &Array1::from(rep)).unwrap();
    z.add_strings("name", &name, &[name.len()]).unwrap();
    std::fs::write(path, z.finish().unwrap()).unwrap();
}

fn quick(params: RefineEvalParams) -> RefineEvalParams {
    RefineEvalParams {
        samples_per_action: 2,
        max_clips: Some(3),
        ablation: false,
        ..params
    }
}

fn assert_finite(r: &RefineEvalReport) {
    let i = &r.injected;
    assert!(i.n_clips > 0);
    for (what, v) in [
        ("MPJPE before", i.mpjpe_before_m),
        ("MPJPE after", i.mpjpe_after_m),
        ("baseline", i.baseline_after_m),
        ("clean change", i.clean_change_m),
        ("FID before", r.generated.before.fid),
        ("FID after", r.generated.after.fid),
        ("accuracy after", r.generated.after.accuracy),
    ] {
        assert!(v.is_finite(), "{what} is {v}");
    }
    assert!(i.mpjpe_before_m > 0.0);
}

#[test]
fn files_without_subject_9_are_scored_on_the_subjects_the_networks_never_saw() {
    let path = mp_geom::data_or_return!(MsrAction3D::FILE);
    let shared = MsrAction3D::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let dir = find_model_dir().expect("models/refine/manifest.json is part of the repository");
    let (nets, concepts) = common::shipped();
    let trained = TrainingSubjects::read(&dir).unwrap();
    assert_eq!(trained.seen(), vec![1, 3, 5, 7]);
    let tmp = tempfile::tempdir().unwrap();

    // Subject 1 (a training subject) and subject 3's clips written as
    // subject 2, which the manifest does not name: subject 2 is scored.
    let mixed = tmp.path().join("mixed.npz");
    write_subset(&shared, &[(1, 1), (3, 2)], 4, &mixed);
    let data = MsrAction3D::open(&mixed).unwrap();
    assert!(!subjects_of(&data).contains(&9));
    let split = split_for(&data, &trained, None).unwrap();
    assert_eq!(split.eval_subjects, vec![2]);
    assert!(split.seen_eval_subjects.is_empty());
    assert_eq!(split.concept_subjects, vec![1]);
    let params = quick(split_params(RefineEvalParams::default(), &split));
    let r = evaluate(&data, &nets, &concepts, &params).unwrap();
    assert_finite(&r);
    let real = r
        .generated
        .real
        .as_ref()
        .expect("subject 2 against subject 1");
    assert!(real.fid.is_finite());

    // Only training subjects: nothing unseen is left, unless named.
    let seen_only = tmp.path().join("seen.npz");
    write_subset(&shared, &[(5, 5)], 4, &seen_only);
    let data = MsrAction3D::open(&seen_only).unwrap();
    let e = split_for(&data, &trained, None).unwrap_err().to_string();
    assert!(e.contains("name the subjects"), "{e}");
    assert!(split_for(&data, &trained, Some(&[2])).is_err());
    let split = split_for(&data, &trained, Some(&[5])).unwrap();
    assert_eq!(split.seen_eval_subjects, vec![5]);
    let params = quick(split_params(RefineEvalParams::default(), &split));
    let r = evaluate(&data, &nets, &concepts, &params).unwrap();
    assert_finite(&r);
    // no clip outside the evaluation subjects to compare the real clips with
    assert!(r.generated.real.is_none());

    // A folder of both files reads as one set.
    let both = MsrAction3D::open_path(tmp.path()).unwrap();
    assert_eq!(both.len(), 12);
    assert_eq!(subjects_of(&both), vec![1, 2, 5]);
}
