mod common;
use mp_pose::blazepose::{BlazePose, BlazePoseParams};
use mp_pose::video::VideoReader;

#[test]
#[ignore]
fn dev_compare_golf() {
    let stem = std::env::var("STEM").unwrap_or("golf_swing".into());
    let vid = if stem == "golf_swing" {
        common::data("golfdb/golf_swing.mp4")
    } else {
        common::data(&format!("quva_repetition/videos/{stem}.mp4"))
    };
    let r = common::reference(&stem);
    let n: usize = std::env::var("N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    let mut bp = BlazePose::new(BlazePoseParams {
        fixed_frame_interval_s: Some(0.033333),
        ..Default::default()
    })
    .unwrap();
    let reader = VideoReader::open(&vid).unwrap();
    let (w, h) = (reader.info().width as f64, reader.info().height as f64);
    let mut all = Vec::new();
    for (t, f) in reader.enumerate().take(n) {
        let f = f.unwrap();
        let (pose, diag) = bp.process(&f).unwrap();
        let mut errs = Vec::new();
        if let Some(p) = &pose {
            if r.found[t] {
                for k in 0..33 {
                    if r.visibility[[t, k]] > 0.5 {
                        let dx = p.keypoints_px[k][0] - r.landmarks_px[[t, k, 0]] as f64;
                        let dy = p.keypoints_px[k][1] - r.landmarks_px[[t, k, 1]] as f64;
                        errs.push((dx * dx + dy * dy).sqrt());
                    }
                }
            }
        }
        all.extend(errs.iter().copied());
        let mean = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
        let rl = r.roi_from_landmarks.row(t);
        let rd = r.roi_from_detection.row(t);
        let nr = diag.next_roi.map(|q| {
            (
                q.center_x_px / w,
                q.center_y_px / h,
                q.width_px / w,
                q.rotation_rad,
            )
        });
        let ur = diag.roi.map(|q| {
            (
                q.center_x_px / w,
                q.center_y_px / h,
                q.width_px / w,
                q.rotation_rad,
            )
        });
        println!("t={t} found={} ref={} det={} mean_err={mean:.2} n={} used_roi={ur:?} det_ref={:?} next={nr:?} ref_next={:?}",
            pose.is_some(), r.found[t], diag.detector_ran, errs.len(),
            (rd[0], rd[1], rd[2], rd[4]), (rl[0], rl[1], rl[2], rl[4]));
    }
    all.sort_by(f64::total_cmp);
    if !all.is_empty() {
        println!(
            "median {:.3} p90 {:.3}",
            all[all.len() / 2],
            all[all.len() * 9 / 10]
        );
    }
}
