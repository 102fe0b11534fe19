//! Step 1, a long video: the pose pass in pieces side by side.
//!
//! One tracker follows a video frame after frame, and on a few cores the
//! model's own threads gain little; so a long video is cut into one piece
//! per core (at least a minute each, `crate::PoseParams::pieces`), each with
//! its own decoder and a model with its share of the threads, and the
//! pieces' people are joined where they overlap (`mp_pose::join_pieces`).

use mp_geom::CancelToken;
use mp_pose::{
    decode_ahead, extract_people, DecodeOptions, ExtractOptions, FrameCopies, MultiPose,
};
use mp_pose::{SessionParams, VideoInfo, VideoReader};

use crate::error::{PipelineError, Result};
use crate::keypoints::{extract_options, multi_params, posed_people, Posed};
use crate::params::{Params, PoseParams};
use crate::progress::check;

/// The CPU cores this process may use (1 where the system does not say).
fn cpu_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |c| c.get())
}

/// The pieces ([`PoseParams::pieces`]) the pose pass cuts a video of
/// `expected` frames into: `(start, frames)` each; one piece for a short
/// video, a video of unknown length, a GPU or a shared model.
pub(crate) fn pose_pieces(
    params: &Params,
    info: &VideoInfo,
    expected: Option<usize>,
    shared: bool,
) -> Result<Vec<(usize, usize)>> {
    let Some(n) = expected.filter(|&n| n > 0) else {
        return Ok(vec![(0, expected.unwrap_or(0))]);
    };
    let cores = cpu_cores();
    let on_gpu = match params.pose.device {
        mp_pose::Device::Cpu => false,
        mp_pose::Device::Auto => mp_pose::Device::cuda_available().unwrap_or(false),
        _ => true,
    };
    let fits = (n as f64 / (info.fps * mp_pose::MIN_PIECE_S)).floor() as usize;
    let k = match params.pose.pieces {
        0 if shared || on_gpu => 1,
        0 => cores.min(PoseParams::MAX_PIECES).min(fits).max(1),
        k => k,
    };
    let overlap = (mp_pose::PIECE_OVERLAP_S * info.fps).round().max(1.0) as usize;
    let stride = params.pose.rate.stride(info.fps);
    Ok(mp_pose::piece_ranges(n, k, overlap, stride))
}

/// The pose pass over `pieces` of the video side by side, each with its own
/// decoder (and grey thumbnails at `side`) and model, the ONNX Runtime
/// threads shared out among them; joined into one extraction, the
/// thumbnails of each frame from the piece whose frames it is.
pub(crate) fn pose_people_in_pieces(
    info: &VideoInfo,
    pieces: &[(usize, usize)],
    side: usize,
    copies: Option<FrameCopies>,
    params: &Params,
    cancel: &CancelToken,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(Posed, mp_pose::Decoded)> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let lm = params.pose.model.landmark_model().ok_or_else(|| {
        PipelineError::param(
            "pose.model",
            "several people need BlazePose (full, lite or heavy)",
        )
    })?;
    let session = SessionParams {
        intra_threads: (cpu_cores() / pieces.len()).max(1),
        ..params.pose.session()
    };
    let fps = info.fps;
    let total: usize = pieces.last().map_or(0, |&(s, l)| s + l);
    let done: Vec<AtomicUsize> = pieces.iter().map(|_| AtomicUsize::new(0)).collect();
    type PieceOut = Result<(
        mp_pose::PeopleExtraction,
        mp_pose::Decoded,
        String,
        mp_geom::Skeleton,
    )>;
    let outs: Vec<PieceOut> = std::thread::scope(|scope| {
        let handles: Vec<_> = pieces
            .iter()
            .enumerate()
            .map(|(i, &(start, len))| {
                let (session, done) = (session.clone(), &done);
                let copies = copies.clone().map(|c| FrameCopies { first: start, ..c });
                // The last piece reads to the end, wherever the container's
                // frame count put it.
                let limit = if i + 1 == pieces.len() {
                    params.pose.max_frames.map(|m| m.saturating_sub(start))
                } else {
                    Some(len)
                };
                scope.spawn(move || -> PieceOut {
                    let reader = VideoReader::from_frame(info.clone(), start)?;
                    let (source, decoder) = decode_ahead(
                        reader,
                        &DecodeOptions {
                            limit,
                            keep_full: false,
                            thumbnail_size: Some(side),
                            copies,
                            ..DecodeOptions::default()
                        },
                        cancel.clone(),
                    )?;
                    let mut est = MultiPose::new(multi_params(lm, session, None, params))?;
                    let options = ExtractOptions {
                        max_frames: limit,
                        ..extract_options(params, fps)
                    };
                    let ex = extract_people(source, &mut est, &options, |d, _| {
                        done[i].store(d, Ordering::Relaxed);
                        let all: usize = done.iter().map(|d| d.load(Ordering::Relaxed)).sum();
                        progress(all.min(total));
                    });
                    let decoded = decoder.join().map_err(|_| {
                        PipelineError::stage("decoding", "the decoding thread panicked")
                    })?;
                    Ok((ex?, decoded, est.name().to_string(), est.skeleton()))
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(PipelineError::stage(
                        "pose",
                        "a piece's pose thread panicked",
                    ))
                })
            })
            .collect()
    });
    check(cancel)?;
    let mut joined = Vec::with_capacity(pieces.len());
    let cells = side * side;
    let mut thumbnails: Vec<f32> = Vec::new();
    let mut copies: Vec<(usize, Vec<u8>)> = Vec::new();
    let (mut decode, mut copying) = (std::time::Duration::ZERO, std::time::Duration::ZERO);
    let mut model = (String::new(), None);
    for (&(start, _), out) in pieces.iter().zip(outs) {
        let (ex, decoded, name, skeleton) = out?;
        // Each frame's thumbnail from the piece whose frames it is: the
        // earlier piece's up to its end.
        let skip = (thumbnails.len() / cells).saturating_sub(start) * cells;
        thumbnails.extend_from_slice(decoded.thumbnails.get(skip..).unwrap_or_default());
        let next = copies.last().map_or(0, |(i, _)| i + 1);
        copies.extend(decoded.copies.into_iter().filter(|(i, _)| *i >= next));
        decode += decoded.decode;
        copying += decoded.copying;
        model = (name, Some(skeleton));
        joined.push((start, ex));
    }
    let ex = mp_pose::join_pieces(joined)?;
    let (name, skeleton) = model;
    let skeleton = skeleton.ok_or_else(|| PipelineError::stage("pose", "no piece"))?;
    let decoded = mp_pose::Decoded {
        kept: None,
        thumbnails,
        copies,
        decode,
        copying,
    };
    Ok((posed_people(ex, &name, skeleton, fps)?, decoded))
}
