//! The online concrete program: segments tile the frames, the buffer stays
//! bounded, and on real keypoints the final program is close to the offline one.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use std::time::Instant;

use mp_concrete::Program;
use mp_geom::{Skeleton, Track};
use mp_live::{LiveParams, OnlineProgram, ProgramSegment};

/// A COCO-17 pose: wrists and elbows swing with period `period` frames, and
/// every 7 s the person holds still for 2 s.
fn pose(f: usize, period: f64, fps: f64) -> (Vec<[f64; 2]>, Vec<f64>) {
    let still = (f as f64 / fps) % 7.0 > 5.0;
    let a = if still {
        0.0
    } else {
        (2.0 * std::f64::consts::PI * f as f64 / period).sin()
    };
    let pts = (0..17)
        .map(|q| {
            let x = 100.0 + 10.0 * (q % 4) as f64;
            let y = 100.0 + 20.0 * (q / 4) as f64;
            let swing = if (7..=10).contains(&q) { 60.0 } else { 3.0 };
            [x + 0.3 * swing * a, y - swing * a]
        })
        .collect();
    (pts, vec![0.9; 17])
}

fn check_tiling(segs: &[ProgramSegment], first: usize, end: usize) {
    assert!(!segs.is_empty());
    assert_eq!(segs[0].start_frame, first);
    assert_eq!(segs[segs.len() - 1].end_frame, end);
    for (k, s) in segs.iter().enumerate() {
        assert_eq!(s.index, k, "index rises by one");
        assert!(s.end_frame > s.start_frame);
        assert_eq!(s.segment.duration_frames, s.end_frame - s.start_frame);
        assert_eq!(s.segment.primitives.len(), 17);
        if k > 0 {
            assert_eq!(s.start_frame, segs[k - 1].end_frame, "no gap, no overlap");
        }
    }
}

#[test]
fn segments_tile_the_frames_and_the_buffer_stays_bounded() {
    let fps = 15.0;
    let params = LiveParams {
        program: true,
        program_max_lag_s: 6.0,
        ..LiveParams::default()
    };
    let mut p = OnlineProgram::new(fps, Skeleton::coco17(), Some(640.0), &params);
    let frames = (4.0 * 60.0 * fps) as usize;
    let mut segs = Vec::new();
    for f in 0..frames {
        let (pts, v) = pose(f, 24.0, fps);
        segs.extend(p.push(f, pts, v, &params).unwrap());
        segs.extend(p.update(&params).unwrap());
        assert!(p.buffer_len() <= p.max_buffer());
    }
    let before_end = segs.len();
    segs.extend(p.finish(&params).unwrap());
    check_tiling(&segs, 0, frames);
    assert_eq!(p.max_buffer(), 90 + 4);
    assert!(p.longest_buffer() <= p.max_buffer());
    assert!(p.longest_buffer() >= 45, "{}", p.longest_buffer());
    assert!(
        before_end > segs.len() / 2,
        "{before_end} of {}",
        segs.len()
    );
    assert_eq!(p.buffer_len(), 0);
    // Summaries name the kinds.
    assert!(segs[0].summary().chars().next().unwrap().is_ascii_digit());
}

#[test]
fn a_long_gap_commits_the_buffer_and_leaves_a_hole() {
    let params = LiveParams {
        program: true,
        ..LiveParams::default()
    };
    let mut p = OnlineProgram::new(30.0, Skeleton::coco17(), Some(640.0), &params);
    let mut segs = Vec::new();
    for f in (0..90).chain(200..260) {
        let (pts, v) = pose(f, 30.0, 30.0);
        segs.extend(p.push(f, pts, v, &params).unwrap());
        segs.extend(p.update(&params).unwrap());
    }
    segs.extend(p.finish(&params).unwrap());
    let hole = segs.iter().position(|s| s.start_frame == 200).unwrap();
    check_tiling(&segs[..hole], 0, 90);
    assert_eq!(segs[hole - 1].end_frame, 90);
    assert_eq!(segs[segs.len() - 1].end_frame, 260);
}

#[test]
fn no_frame_or_one_frame_gives_no_panic() {
    let params = LiveParams::default();
    let mut p = OnlineProgram::new(30.0, Skeleton::coco17(), None, &params);
    assert!(p.finish(&params).unwrap().is_empty());
    let (pts, v) = pose(0, 30.0, 30.0);
    p.push(5, pts, v, &params).unwrap();
    let segs = p.finish(&params).unwrap();
    assert_eq!(segs.len(), 1);
    assert_eq!((segs[0].start_frame, segs[0].end_frame), (5, 6));
    assert_eq!(segs[0].summary(), "17 stationary");
    // Nothing observed: no segment, no error.
    let mut q = OnlineProgram::new(30.0, Skeleton::coco17(), None, &params);
    for f in 0..40 {
        q.push(f, vec![[f64::NAN; 2]; 17], vec![0.0; 17], &params)
            .unwrap();
        assert!(q.update(&params).unwrap().is_empty());
    }
    assert!(q.finish(&params).unwrap().is_empty());
}

#[test]
fn invalid_lags_are_named() {
    let params = LiveParams {
        program_lag_s: 12.0,
        ..LiveParams::default()
    };
    let e = params.validate().unwrap_err().to_string();
    assert!(e.contains("program_max_lag_s"), "{e}");
}

/// One recording's online and offline programs (the keypoints `mp run`
/// fits: COCO-17, pixels, the frame's scale).
struct Compared {
    frames: usize,
    online_segments: usize,
    forced: usize,
    offline_segments: usize,
    kd_online: f64,
    kd_offline: f64,
    max_diff: f64,
    ms_per_frame: f64,
}

fn compare(track: &Track, frame_px: Option<f64>, params: &LiveParams) -> Compared {
    let coco = track.to_coco17().unwrap();
    let offline = mp_pipeline::concrete_program(&coco, frame_px, &params.analysis)
        .unwrap()
        .program;
    let mut p = OnlineProgram::new(track.fps(), track.skeleton().clone(), frame_px, params);
    let (pos, conf) = (track.positions(), track.confidence());
    let t0 = Instant::now();
    let mut segs = Vec::new();
    for f in 0..track.n_frames() {
        let pts = (0..track.n_joints())
            .map(|j| [pos[[f, j, 0]], pos[[f, j, 1]]])
            .collect();
        let c = (0..track.n_joints()).map(|j| conf[[f, j]]).collect();
        segs.extend(p.push(f, pts, c, params).unwrap());
        segs.extend(p.update(params).unwrap());
        assert!(p.buffer_len() <= p.max_buffer());
    }
    segs.extend(p.finish(params).unwrap());
    let ms_per_frame = t0.elapsed().as_secs_f64() * 1e3 / track.n_frames() as f64;
    check_tiling(&segs, 0, track.n_frames());
    let online: Program = ProgramSegment::concatenate(&offline, &segs).unwrap();
    let (so, sf) = (online.stats(&coco).unwrap(), offline.stats(&coco).unwrap());
    let (eo, ef) = (online.execute().unwrap(), offline.execute().unwrap());
    let (a, b) = (eo.positions(), ef.positions());
    let mut max_diff = 0.0f64;
    for f in 0..a.shape()[0] {
        for j in 0..a.shape()[1] {
            let d = ((a[[f, j, 0]] - b[[f, j, 0]]).powi(2) + (a[[f, j, 1]] - b[[f, j, 1]]).powi(2))
                .sqrt();
            max_diff = max_diff.max(d);
        }
    }
    Compared {
        frames: track.n_frames(),
        online_segments: segs.len(),
        forced: segs.iter().filter(|s| s.forced).count(),
        offline_segments: offline.n_segments(),
        kd_online: so.kd,
        kd_offline: sf.kd,
        max_diff,
        ms_per_frame,
    }
}

/// The reference keypoints of the QUVA videos (MediaPipe's BlazePose, the
/// keypoints `mp live` tracks) fed frame by frame: the online program's
/// error (KD, `mp stats`' mean distance to the keypoints, px) stays within
/// 1.25 times the offline program's on every recording (measured: at most
/// 1.1; docs/results/live.md). Run with `--nocapture` for the table.
#[test]
fn online_program_is_close_to_the_offline_one_on_real_keypoints() {
    let Some(dir) =
        mp_geom::test_support::data_dir_or_skip(&mp_geom::test_support::current_test_name())
    else {
        return;
    };
    let dir = dir.join("reference_keypoints");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "npz"))
        .collect();
    files.sort();
    assert!(files.len() >= 10, "{}", dir.display());
    let params = LiveParams {
        program: true,
        ..LiveParams::default()
    };
    println!("| recording | frames | segments online (forced) | offline | KD online px | KD offline px | largest difference px | ms/frame |");
    println!("|---|---|---|---|---|---|---|---|");
    for path in files {
        let read = mp_geom::read_track_rated(&path, &mp_geom::ReadOptions::default()).unwrap();
        let frame_px = read.frame_size.map(|(w, h)| w.max(h) as f64);
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        if !read.track.confidence().iter().any(|&c| c > 0.0) {
            println!(
                "| {name} | {} | no pose found | | | | | |",
                read.track.n_frames()
            );
            continue;
        }
        let c = compare(&read.track, frame_px, &params);
        println!(
            "| {name} | {} | {} ({}) | {} | {:.2} | {:.2} | {:.1} | {:.2} |",
            c.frames,
            c.online_segments,
            c.forced,
            c.offline_segments,
            c.kd_online,
            c.kd_offline,
            c.max_diff,
            c.ms_per_frame
        );
        assert!(
            c.kd_online <= 1.25 * c.kd_offline + 0.05,
            "{name}: KD online {} vs offline {}",
            c.kd_online,
            c.kd_offline
        );
    }
}
