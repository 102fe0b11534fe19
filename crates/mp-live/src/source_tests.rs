#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use super::*;

fn frame(index: usize) -> Frame {
    Frame::new(index, index as f64 / 30.0, 2, 2, vec![0; 12]).unwrap()
}

fn info(width: usize, height: usize, fps: f64) -> VideoInfo {
    VideoInfo {
        path: PathBuf::from("-"),
        width,
        height,
        fps,
        frame_count: None,
        duration_s: None,
        codec: "h264".into(),
    }
}

fn taken(slot: &Slot) -> Option<usize> {
    match slot.take(Duration::from_millis(1)) {
        Taken::Frame(f) => Some(f.index),
        _ => None,
    }
}

#[test]
fn a_full_queue_of_a_live_source_drops_its_oldest_frames() {
    let slot = Slot::new(true, 3);
    for i in 0..5 {
        assert!(slot.put(frame(i)));
    }
    assert_eq!(slot.dropped(), 2);
    let order: Vec<_> = std::iter::from_fn(|| taken(&slot)).collect();
    assert_eq!(order, vec![2, 3, 4], "the newest frames wait, in order");
    assert_eq!(slot.newest_s(), 4.0 / 30.0);
}

#[test]
fn frames_within_the_queue_are_not_dropped() {
    let slot = Slot::new(true, 4);
    for i in 0..6 {
        assert!(slot.put(frame(i)));
        if i % 2 == 1 {
            // The analysis takes a frame every second frame: the queue
            // absorbs what it is behind by.
            assert!(taken(&slot).is_some());
        }
    }
    assert_eq!(slot.dropped(), 0);
    let rest: Vec<_> = std::iter::from_fn(|| taken(&slot)).collect();
    assert_eq!(rest, vec![3, 4, 5]);
}

#[test]
fn a_file_read_as_fast_as_possible_waits_instead_of_dropping() {
    let slot = Slot::new(false, 2);
    let s = slot.clone();
    let writer = std::thread::spawn(move || {
        for i in 0..10 {
            assert!(s.put(frame(i)));
        }
        s.end(Ok(()));
    });
    let mut got = Vec::new();
    loop {
        match slot.take(Duration::from_secs(10)) {
            Taken::Frame(f) => got.push(f.index),
            Taken::Ended(r) => {
                r.unwrap();
                break;
            }
            Taken::Stalled => panic!("stalled"),
        }
    }
    writer.join().unwrap();
    assert_eq!(got, (0..10).collect::<Vec<_>>());
    assert_eq!(slot.dropped(), 0);
}

#[test]
fn the_queue_holds_seconds_of_frames_within_its_byte_bound() {
    assert_eq!(queue_frames(&info(640, 360, 30.0), 0.5), 15);
    assert_eq!(queue_frames(&info(640, 360, 30.0), 0.0), 1);
    assert_eq!(queue_frames(&info(640, 360, 25.0), f64::NAN), 1);
    // 4K RGB frames: 24.9 MB each, so at most 10 within 256 MiB.
    assert_eq!(queue_frames(&info(3840, 2160, 60.0), 2.0), 10);
}
