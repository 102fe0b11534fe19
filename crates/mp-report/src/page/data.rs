//! The files beside the report page, in its folder `report/`, and what bounds
//! their size.
//!
//! * `frames/NNNNNN.jpg`: the reduced video frames, one JPEG each, named by
//!   their frame of the video; the page shows them in an `<img>` (which
//!   loads from disk where `fetch()` may not).
//! * `pK/person.js`: person K's structure (segment boundaries, kinds per
//!   segment, counted repetitions, the timeline, the tables and the abstract
//!   program); `pK/joint-JJ.js`: the program listing of joint JJ and the
//!   joint's trajectory over the whole recording (at most
//!   [`OVERVIEW_POINTS`] samples); `pK/data-CCCC.js`: keypoints,
//!   confidences and the executed program of [`CHUNK_FRAMES`] data frames.
//!
//! Each data file is a script that hands its content to the page's
//! registration function, `mpReport(kind, key, content)`, so that the page
//! can load it with `<script src>` from disk as well as from a server.
//!
//! Sizes are bounded whatever the recording's length: the frames to
//! [`FRAMES_BUDGET_BYTES`] (beyond it every second frame is left out, until
//! they fit), the per-frame data to [`DATA_BUDGET_VALUES`] numbers over
//! everyone shown (beyond it the data keeps every `stride`-th frame).
//! Numbers are quantised (0.1 px, 10⁻⁴ of other units, confidences to
//! 0.01), stored as differences from the same joint's value in the previous
//! frame, as zigzag LEB128 bytes in base64: about 1.4 characters a number
//! for motion.

use base64::Engine as _;
use mp_geom::{Track, Units};
use serde_json::json;

use crate::error::{ReportError, Result};
use crate::frames::FrameStore;

/// Folder of the page's files, beside `report.html`.
pub const FOLDER: &str = "report";

/// At most this many bytes of frames are written for the page (1,200
/// frames of about 20 KB, the frame store's cap at its size).
pub const FRAMES_BUDGET_BYTES: usize = 24 << 20;

/// At most this many numbers of per-frame data (keypoints, confidences,
/// executed program) over everyone on the page: an hour at 30 fps of one
/// 17-joint person in 2-D is 9.2 million; about 17 MB.
pub const DATA_BUDGET_VALUES: usize = 12_000_000;

/// At most this many bytes in `report/` for an hour of one person at
/// 30 fps with the frame store at its cap (frames, per-frame data, the
/// program listings and the rest); the folder grows past it only with the
/// programs' length (the listings are about the size of `program.txt`).
pub const FOLDER_BUDGET_BYTES: usize = 64 << 20;

/// Data frames per chunk file (8.5 s at 30 fps).
pub const CHUNK_FRAMES: usize = 256;

/// Samples of a joint's trajectory in its joint file (every frame up to
/// this many frames).
pub const OVERVIEW_POINTS: usize = 2400;

/// The frames the page shows: every frame of the store, or every 2nd, 4th…
/// until their bytes fit [`FRAMES_BUDGET_BYTES`]. Returns (frame index,
/// JPEG) pairs in frame order.
pub(crate) fn frames_within_budget(store: &FrameStore, budget: usize) -> Vec<(usize, &[u8])> {
    let mut every = 1usize;
    loop {
        let kept: Vec<(usize, &[u8])> = store
            .frames
            .iter()
            .step_by(every)
            .map(|(i, j)| (*i, j.as_slice()))
            .collect();
        let bytes: usize = kept.iter().map(|(_, j)| j.len()).sum();
        if bytes <= budget || kept.len() <= 1 {
            return kept;
        }
        every *= 2;
    }
}

/// Path of a frame's picture, relative to the page.
pub(crate) fn frame_file(index: usize) -> String {
    format!("{FOLDER}/frames/{index:06}.jpg")
}

/// The stride of the per-frame data: 1 while everyone's frames × numbers per
/// frame fit [`DATA_BUDGET_VALUES`], else the smallest stride that fits.
pub(crate) fn data_stride(frames_values: impl IntoIterator<Item = (usize, usize)>) -> usize {
    let total: usize = frames_values.into_iter().map(|(f, v)| f * v).sum();
    total.div_ceil(DATA_BUDGET_VALUES).max(1)
}

/// Numbers per frame of a person's data: keypoints and program (D each per
/// joint) and a confidence per joint.
pub(crate) fn values_per_frame(track: &Track) -> usize {
    let (_, j, d) = track.positions().dim();
    j * (2 * d + 1)
}

/// Quantisation step of positions in `units`.
pub(crate) fn position_step(units: Units) -> f64 {
    if units == Units::Pixels {
        0.1
    } else {
        1e-4
    }
}

/// Packs integers laid out as `slots` values per frame: each value minus the
/// same slot's value in the previous frame, zigzag-coded as LEB128 bytes,
/// in base64.
pub fn pack(values: &[i64], slots: usize) -> String {
    let slots = slots.max(1);
    let mut prev = vec![0i64; slots];
    let mut bytes = Vec::with_capacity(values.len() * 2);
    for (k, &v) in values.iter().enumerate() {
        let d = v.wrapping_sub(prev[k % slots]);
        prev[k % slots] = v;
        let mut z = ((d << 1) ^ (d >> 63)) as u64;
        loop {
            let b = (z & 0x7f) as u8;
            z >>= 7;
            if z == 0 {
                bytes.push(b);
                break;
            }
            bytes.push(b | 0x80);
        }
    }
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// The inverse of [`pack`] (for the tests): `None` if it is not base64
/// or ends inside a number.
#[cfg(test)]
pub fn unpack(text: &str, slots: usize) -> Option<Vec<i64>> {
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(text)
        .ok()?;
    let slots = slots.max(1);
    let mut prev = vec![0i64; slots];
    let mut out = Vec::new();
    let (mut z, mut shift, mut open) = (0u64, 0u32, false);
    for b in bytes {
        z |= u64::from(b & 0x7f).checked_shl(shift).unwrap_or(0);
        shift += 7;
        open = b & 0x80 != 0;
        if !open {
            let d = ((z >> 1) as i64) ^ -((z & 1) as i64);
            let k = out.len() % slots;
            prev[k] = prev[k].wrapping_add(d);
            out.push(prev[k]);
            z = 0;
            shift = 0;
        }
    }
    (!open).then_some(out)
}

fn quantise(v: f64, step: f64) -> i64 {
    if v.is_finite() {
        (v / step).round() as i64
    } else {
        0
    }
}

/// A script that registers `content` with the page.
pub fn registration(kind: &str, key: &str, content: &serde_json::Value) -> Result<String> {
    Ok(format!(
        "mpReport({},{},{});\n",
        serde_json::to_string(kind)?,
        serde_json::to_string(key)?,
        serde_json::to_string(content)?
    ))
}

/// The content of a registration script written by `registration`:
/// (kind, key, content), or `None` when `script` is not one.
pub fn registered(script: &str) -> Option<(String, String, serde_json::Value)> {
    let body = script
        .trim()
        .strip_prefix("mpReport(")?
        .strip_suffix(");")?;
    let mut stream = serde_json::Deserializer::from_str(body).into_iter::<serde_json::Value>();
    let kind = stream.next()?.ok()?;
    let rest = body[stream.byte_offset()..]
        .trim_start()
        .strip_prefix(',')?;
    let mut stream = serde_json::Deserializer::from_str(rest).into_iter::<serde_json::Value>();
    let key = stream.next()?.ok()?;
    let rest = rest[stream.byte_offset()..]
        .trim_start()
        .strip_prefix(',')?;
    let content: serde_json::Value = serde_json::from_str(rest).ok()?;
    Some((
        kind.as_str()?.to_string(),
        key.as_str()?.to_string(),
        content,
    ))
}

/// One chunk of a person's per-frame data: data frames `first..first + n`
/// (video frames `offset + stride · (first..)`) of the keypoints, their
/// confidences and the executed program.
pub fn chunk(
    track: &Track,
    executed: &Track,
    stride: usize,
    first: usize,
    n: usize,
) -> Result<serde_json::Value> {
    let (t, j, d) = track.positions().dim();
    if executed.positions().dim() != (t, j, d) {
        return Err(ReportError::Mismatch(format!(
            "the executed program is {:?}, the keypoints {:?}",
            executed.positions().dim(),
            (t, j, d)
        )));
    }
    let step = position_step(track.units());
    let (mut kp, mut prog, mut conf) = (
        Vec::with_capacity(n * j * d),
        Vec::with_capacity(n * j * d),
        Vec::with_capacity(n * j),
    );
    for df in first..first + n {
        let f = (df * stride).min(t.saturating_sub(1));
        for ji in 0..j {
            conf.push(quantise(track.confidence()[[f, ji]], 0.01));
            for k in 0..d {
                kp.push(quantise(track.positions()[[f, ji, k]], step));
                prog.push(quantise(executed.positions()[[f, ji, k]], step));
            }
        }
    }
    Ok(json!({
        "n": n,
        "kp": pack(&kp, j * d),
        "conf": pack(&conf, j),
        "prog": pack(&prog, j * d),
    }))
}

/// Number of data frames of a track of `frames` frames at `stride`.
pub(crate) fn data_frames(frames: usize, stride: usize) -> usize {
    frames.div_ceil(stride.max(1))
}

/// Joint `ji`'s trajectory over the whole track, every `step`-th frame (1
/// up to [`OVERVIEW_POINTS`] frames): keypoints, confidence, program.
pub(crate) fn overview(track: &Track, executed: &Track, ji: usize) -> serde_json::Value {
    let (t, _, d) = track.positions().dim();
    let step = t.div_ceil(OVERVIEW_POINTS).max(1);
    let q = position_step(track.units());
    let (mut kp, mut prog, mut conf) = (Vec::new(), Vec::new(), Vec::new());
    for f in (0..t).step_by(step) {
        conf.push(quantise(track.confidence()[[f, ji]], 0.01));
        for k in 0..d {
            kp.push(quantise(track.positions()[[f, ji, k]], q));
            prog.push(quantise(executed.positions()[[f, ji, k]], q));
        }
    }
    json!({
        "step": step,
        "n": conf.len(),
        "kp": pack(&kp, d),
        "conf": pack(&conf, 1),
        "prog": pack(&prog, d),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_numbers_come_back() {
        let v = vec![
            0,
            5,
            -3,
            1_000_000,
            -1_000_000,
            7,
            7,
            7,
            i64::from(i32::MAX),
            -1,
        ];
        for slots in [1, 2, 3] {
            assert_eq!(unpack(&pack(&v, slots), slots).unwrap(), v);
        }
        assert_eq!(unpack(&pack(&[], 4), 4).unwrap(), Vec::<i64>::new());
        // Small differences take one byte each.
        let slow: Vec<i64> = (0..300).map(|i| 1500 + (i % 7)).collect();
        let text = pack(&slow, 1);
        assert!(text.len() < 300 * 3 / 2 + 8, "{}", text.len());
        assert!(unpack("@@", 1).is_none());
    }

    #[test]
    fn registration_scripts_read_back() {
        let v = json!({"a": [1, 2], "s": "x);y, \"z\""});
        let s = registration("person", "0/3", &v).unwrap();
        assert!(s.starts_with("mpReport(\"person\",\"0/3\",{"));
        let (kind, key, back) = registered(&s).unwrap();
        assert_eq!((kind.as_str(), key.as_str()), ("person", "0/3"));
        assert_eq!(back, v);
        assert!(registered("alert(1)").is_none());
    }

    #[test]
    fn the_data_stride_keeps_the_budget() {
        assert_eq!(data_stride([(108_000, 85)]), 1);
        assert_eq!(data_stride([(108_000, 85), (108_000, 85)]), 2);
        assert_eq!(data_stride([(1_000_000, 85)]), 8);
        assert_eq!(data_frames(10, 3), 4);
    }

    #[test]
    fn frames_are_thinned_to_the_budget() {
        let p = crate::frames::FrameStoreParams {
            max_side_px: 40,
            ..Default::default()
        };
        let mut s = FrameStore::new(40, 30, Some(8), &p).unwrap();
        for i in 0..8 {
            s.push(i, &vec![(i * 30) as u8; 40 * 30 * 3]).unwrap();
        }
        let all = frames_within_budget(&s, usize::MAX);
        assert_eq!(all.len(), 8);
        let one = s.frames[0].1.len();
        let half = frames_within_budget(&s, one * 5);
        assert_eq!(
            half.iter().map(|(i, _)| *i).collect::<Vec<_>>(),
            vec![0, 2, 4, 6]
        );
        assert_eq!(frames_within_budget(&s, 0).len(), 1);
    }
}
