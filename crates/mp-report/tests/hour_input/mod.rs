//! A synthetic hour of motion for the report's size tests: 108,000 frames at
//! 30 fps of a 17-joint skeleton, its program, hundreds of counted intervals,
//! the abstract program and a frame store filled to its cap.
#![allow(dead_code, clippy::unwrap_used)] // test code: failing loudly is the point

use mp_abstract::{CountFeatures, CountMethod, CountSignal, CountedInterval, Counts};
use mp_concrete::{Program, Segment};
use mp_geom::{Primitive, Skeleton, Track, Units};
use mp_report::{FrameStore, FrameStoreParams};
use ndarray::{Array2, Array3};

pub const FPS: f64 = 30.0;
pub const HOUR: usize = 108_000;
pub const FRAME_W: usize = 640;
pub const FRAME_H: usize = 360;

/// A program of `frames` frames: segments of 12–28 frames, every joint's
/// primitive a stationary point, a line or an arc in turn.
pub fn program(frames: usize, shift: usize) -> Program {
    let sk = Skeleton::coco17();
    let durations = [14usize, 22, 18, 26, 20, 16, 24, 12, 28, 20];
    let mut segments = Vec::new();
    let mut t = 0;
    let mut s = 0usize;
    while t < frames {
        let d = durations[(s + shift) % durations.len()].min(frames - t);
        let primitives = (0..sk.len())
            .map(|j| {
                let base = [
                    200.0 + 14.0 * j as f64 + 40.0 * ((s as f64) * 0.37).sin(),
                    80.0 + 12.0 * j as f64,
                ];
                match (s + j + shift) % 3 {
                    0 => Primitive::Stationary {
                        point: base.to_vec(),
                    },
                    1 => Primitive::Line {
                        start: base.to_vec(),
                        velocity: vec![0.8, -0.6],
                    },
                    _ => Primitive::Circle {
                        center: base.to_vec(),
                        radius: 12.0,
                        angle_start: 0.3 * s as f64,
                        angle_vel: 6.0,
                        angle_acc: 0.0,
                        axes: vec![],
                    },
                }
            })
            .collect();
        segments.push(Segment {
            duration_frames: d,
            primitives,
        });
        t += d;
        s += 1;
    }
    Program {
        fps: FPS,
        units: Units::Pixels,
        dims: 2,
        skeleton: "coco17".into(),
        joints: sk.joints.clone(),
        continuity: mp_concrete::Continuity::None,
        segments,
    }
}

/// The keypoints: the executed program with a little deterministic noise,
/// lower confidence on the face, and ten frames without a person every
/// thousand.
pub fn track(executed: &Track) -> Track {
    let (t, j, d) = executed.positions().dim();
    let mut pos = Array3::<f64>::zeros((t, j, d));
    let mut conf = Array2::<f64>::zeros((t, j));
    for ti in 0..t {
        let gone = ti % 1000 < 10;
        for ji in 0..j {
            conf[[ti, ji]] = if gone {
                0.0
            } else if ji < 5 {
                0.55 + 0.4 * ((ti + ji) as f64 * 0.01).sin()
            } else {
                0.93
            };
            for k in 0..d {
                let noise = (((ti * 31 + ji * 7 + k * 3) % 17) as f64 - 8.0) * 0.06;
                pos[[ti, ji, k]] = if gone {
                    f64::NAN
                } else {
                    executed.positions()[[ti, ji, k]] + noise
                };
            }
        }
    }
    Track::new(pos, Some(conf), FPS, Units::Pixels, Skeleton::coco17()).unwrap()
}

/// Counted repetitions: an interval of ten repetitions of a second each,
/// starting every 12 s (300 intervals in an hour), in frames `0..frames`.
pub fn counts(frames: usize, first: usize) -> Counts {
    let mut intervals = Vec::new();
    let mut a = first;
    while a + 300 <= frames {
        let period = 30;
        let boundaries: Vec<usize> = (0..=10).map(|i| a + i * period).collect();
        intervals.push(CountedInterval {
            start_frame: a,
            end_frame: a + 300,
            period_frames: period,
            cycles: 10.0,
            count: 10,
            boundaries,
            signal: mp_abstract::CountSignal::Keypoints,
            periodicity: 0.8,
        });
        a += 360;
    }
    let total = intervals.iter().map(|i| i.count).sum();
    Counts {
        intervals,
        total,
        signal: CountSignal::Keypoints,
        method: CountMethod::Intervals,
        confidence: 0.87,
        periodicity: 0.7,
        features: CountFeatures::default(),
        frames,
        fps: FPS,
    }
}

/// A few textured pictures of `w × h` (smooth shading, shapes, a little
/// grain), as JPEG at the report's quality: about the size of a video frame's
/// reduced copy.
pub fn pictures(w: usize, h: usize, n: usize) -> Vec<Vec<u8>> {
    (0..n)
        .map(|k| {
            let mut rgb = vec![0u8; w * h * 3];
            for y in 0..h {
                for x in 0..w {
                    let o = (y * w + x) * 3;
                    let fx = x as f64 / w as f64;
                    let fy = y as f64 / h as f64;
                    let ring = (((fx - 0.5).powi(2) + (fy - 0.4).powi(2)).sqrt()
                        * (20.0 + k as f64))
                        .sin();
                    let grain = ((x * 73 + y * 151 + k * 37) % 23) as f64 - 11.0;
                    let person = (fx - 0.3 - 0.02 * k as f64).abs() < 0.06 && fy > 0.2;
                    let v = |c: f64| (c + grain).clamp(0.0, 255.0) as u8;
                    rgb[o] = v(if person {
                        200.0
                    } else {
                        90.0 + 80.0 * fy + 30.0 * ring
                    });
                    rgb[o + 1] = v(if person { 60.0 } else { 110.0 + 60.0 * fx });
                    rgb[o + 2] = v(if person {
                        70.0
                    } else {
                        140.0 - 50.0 * fy + 20.0 * ring
                    });
                }
            }
            mp_report::encode_jpeg(&rgb, w, h, 75).unwrap()
        })
        .collect()
}

/// A frame store for an hour of 640 × 360 video, filled to its cap.
pub fn frame_store() -> FrameStore {
    let mut store =
        FrameStore::new(FRAME_W, FRAME_H, Some(HOUR), &FrameStoreParams::default()).unwrap();
    let pics = pictures(store.size.0, store.size.1, 8);
    for i in (0..HOUR).step_by(store.step) {
        store
            .push_jpeg(i, pics[(i / store.step) % pics.len()].clone())
            .unwrap();
    }
    store
}
