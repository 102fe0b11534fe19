use super::*;
use mp_geom::{perform, PerformerParams};

fn performer() -> Track {
    perform(&PerformerParams::default()).unwrap().track_2d
}

#[test]
fn method_names_round_trip() {
    for m in [
        ForecastMethod::Constant,
        ForecastMethod::Loop,
        ForecastMethod::Nn,
        ForecastMethod::Ar,
        ForecastMethod::ArPose,
    ] {
        assert_eq!(m.as_str().parse::<ForecastMethod>().unwrap(), m);
    }
    let e = "walk".parse::<ForecastMethod>().unwrap_err().to_string();
    assert!(e.contains("walk") && e.contains("ar-pose"), "{e}");
    assert_eq!(PredictOptions::default().method, ForecastMethod::Loop);
    assert!(PredictOptions::default().validate().is_ok());
}

#[test]
fn nn_takes_the_product_skeletons_through_the_mappings() {
    let train = mp_geom::data_or_return!(PennAction::TRAIN_FILE);
    let track = performer();
    assert_eq!(track.skeleton().name, "coco17");
    let opts = PredictOptions {
        train: Some(train),
        ..PredictOptions::with_method(ForecastMethod::Nn)
    };
    let p = forecast(&track, 60, 15, &opts).unwrap();
    assert_eq!(p.track.skeleton().name, "coco17");
    assert_eq!((p.track.n_frames(), p.track.n_joints()), (15, 17));
    // Within a body's reach of the truth, which a prediction of the
    // wrong joints or scale would not be.
    let kd = p.actual_kd.unwrap();
    assert!(kd.is_finite() && kd < 0.5 * track.scale(), "{kd}");
}

#[test]
fn constant_prediction_holds_the_last_observed_pose() {
    let track = performer();
    let observe = 40;
    let opts = PredictOptions::with_method(ForecastMethod::Constant);
    let p = forecast(&track, observe, 12, &opts).unwrap();
    assert_eq!(p.method, ForecastMethod::Constant);
    assert_eq!(p.path, PredictPath::Constant);
    assert!(p.explanation().is_none());
    assert_eq!(p.track.n_frames(), 12);
    assert_eq!(p.track.skeleton(), track.skeleton());
    assert_eq!(p.track.fps(), track.fps());
    for h in 0..12 {
        for j in 0..track.n_joints() {
            if track.confidence()[[observe - 1, j]] > 0.0 {
                let d = &p.track.point(h, j) - &track.point(observe - 1, j);
                assert!(d.dot(&d).sqrt() < 1e-12);
            }
        }
    }
    // the track continues: the KD to its own frames is reported
    let kd = p.actual_kd.expect("the track holds the predicted frames");
    assert!(kd.is_finite() && kd >= 0.0);
    // at the track's end there is nothing to compare with
    let n = track.n_frames();
    let p = forecast(&track, n, 5, &opts).unwrap();
    assert_eq!(p.track.n_frames(), 5);
    assert!(p.actual_kd.is_none());
}

#[test]
fn loop_prediction_explains_its_path_and_beats_holding_on_a_repetitive_routine() {
    let perf = perform(&PerformerParams::default()).unwrap();
    let track = perf.track_2d;
    // observe three repetitions of the first move, predict into the fourth
    let first = &perf.segments[0];
    assert!(first.reps.len() >= 4, "{} repetitions", first.reps.len());
    let observe = first.reps[2].end;
    let horizon = first.reps[3].end - observe;
    let opts = PredictOptions::default();
    let p = forecast(&track, observe, horizon, &opts).unwrap();
    assert_eq!(p.method, ForecastMethod::Loop);
    assert_eq!(p.track.n_frames(), horizon);
    assert!(p.track.positions().iter().all(|v| v.is_finite()));
    let text = p
        .explanation()
        .expect("loop prediction says which path it took");
    assert!(
        !matches!(p.path, PredictPath::Hold),
        "a repetitive routine is not held: {text}"
    );
    let held = forecast(
        &track,
        observe,
        horizon,
        &PredictOptions::with_method(ForecastMethod::Constant),
    )
    .unwrap();
    let (kd_loop, kd_hold) = (p.actual_kd.unwrap(), held.actual_kd.unwrap());
    println!("{text}: KD {kd_loop:.2} px (holding the last pose: {kd_hold:.2} px)");
    assert!(
        kd_loop < kd_hold,
        "{text}: loop KD {kd_loop:.2} vs holding {kd_hold:.2}"
    );
    // the same options give the same prediction
    assert_eq!(forecast(&track, observe, horizon, &opts).unwrap(), p);
}

#[test]
fn a_motionless_track_is_held_by_the_loop_method() {
    let track = performer();
    let still = {
        let one = track.slice_frames(10, 11).unwrap();
        let (pos, conf, fps, units, sk) = one.into_parts();
        let pos = ndarray::Array3::from_shape_fn((30, pos.dim().1, pos.dim().2), |(_, j, k)| {
            pos[[0, j, k]]
        });
        let conf = ndarray::Array2::from_shape_fn((30, conf.dim().1), |(_, j)| conf[[0, j]]);
        Track::new(pos, Some(conf), fps, units, sk).unwrap()
    };
    let p = forecast(&still, 30, 10, &PredictOptions::default()).unwrap();
    assert_eq!(p.path, PredictPath::Hold);
    assert_eq!(
        p.explanation().unwrap(),
        "no repetition in the observed frames: holding the last pose"
    );
}

#[test]
fn observe_out_of_range_is_refused_with_the_valid_range() {
    let track = performer();
    let n = track.n_frames();
    for (method, observe, min) in [
        (ForecastMethod::Constant, 0, 1),
        (ForecastMethod::Constant, n + 1, 1),
        (ForecastMethod::Loop, 1, 2),
        (ForecastMethod::Nn, 0, 1),
        (ForecastMethod::Ar, n + 5, 1),
    ] {
        let e = forecast(&track, observe, 10, &PredictOptions::with_method(method)).unwrap_err();
        assert!(
            matches!(e, ForecastError::ObserveOutOfRange { observe: o, min: m, frames, .. }
                if o == observe && m == min && frames == n),
            "{method:?}: {e}"
        );
        let msg = e.to_string();
        assert!(msg.contains(&format!("{min}..={n}")), "{msg}");
    }
}

#[test]
fn absurd_horizons_are_refused_before_anything_is_allocated() {
    let track = performer();
    let fps = track.fps();
    let limit = max_horizon_frames(fps);
    assert_eq!(
        limit,
        ((MAX_HORIZON_SECONDS * fps) as usize).min(MAX_HORIZON_FRAMES)
    );
    assert_eq!(max_horizon_frames(1000.0), MAX_HORIZON_FRAMES);
    assert_eq!(max_horizon_frames(15.0), 54_000);
    for method in [
        ForecastMethod::Constant,
        ForecastMethod::Loop,
        ForecastMethod::Ar,
    ] {
        let opts = PredictOptions::with_method(method);
        for horizon in [limit + 1, usize::MAX] {
            let e = forecast(&track, 20, horizon, &opts).unwrap_err();
            assert!(
                matches!(e, ForecastError::HorizonTooLong { limit: l, .. } if l == limit),
                "{method:?}: {e}"
            );
            assert!(e.to_string().contains(&limit.to_string()), "{e}");
        }
        let e = forecast(&track, 20, 0, &opts).unwrap_err();
        assert!(
            matches!(
                e,
                ForecastError::InvalidParam {
                    name: "horizon",
                    ..
                }
            ),
            "{e}"
        );
    }
    // the bound itself is accepted
    let p = forecast(
        &track,
        20,
        limit,
        &PredictOptions::with_method(ForecastMethod::Constant),
    )
    .unwrap();
    assert_eq!(p.track.n_frames(), limit);
}

#[test]
fn a_skeleton_without_a_model_is_named() {
    let track = performer();
    let custom = Track::new(
        ndarray::Array3::zeros((20, 5, 2)),
        None,
        track.fps(),
        track.units(),
        mp_geom::Skeleton::custom(
            "five",
            (0..5).map(|i| format!("j{i}")).collect(),
            Vec::new(),
            None,
        ),
    )
    .unwrap();
    let e = forecast(
        &custom,
        10,
        5,
        &PredictOptions::with_method(ForecastMethod::Ar),
    )
    .unwrap_err();
    assert!(
        matches!(&e, ForecastError::NoModelForSkeleton { skeleton, dims: 2 } if skeleton == "five"),
        "{e}"
    );
    assert!(e.to_string().contains("`five`"), "{e}");
    // an absent training set is named too
    let e = forecast(
        &track,
        20,
        5,
        &PredictOptions {
            method: ForecastMethod::Nn,
            train: Some(PathBuf::from("/nonexistent/train.npz")),
            ..PredictOptions::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, ForecastError::NoTrainingData(_)), "{e}");
    assert!(e.to_string().contains("/nonexistent/train.npz"), "{e}");
}

#[test]
fn invalid_options_are_refused() {
    let mut opts = PredictOptions::default();
    opts.loop_params.max_tail_periods = f64::NAN;
    assert!(matches!(
        opts.validate(),
        Err(ForecastError::InvalidParam { .. })
    ));
    let opts = PredictOptions {
        method: ForecastMethod::Nn,
        nn_params: NnParams {
            context_frames: 0,
            ..NnParams::default()
        },
        ..PredictOptions::default()
    };
    assert!(opts.validate().is_err());
    let opts = StatueOptions {
        params: StatueParams {
            future_frames: 0,
            ..StatueParams::default()
        },
        ..StatueOptions::default()
    };
    assert!(search_statue(&performer(), &opts).is_err());
}
