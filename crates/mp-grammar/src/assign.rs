//! Learned symbols on new motion: segment a motion that the symbols were not
//! found on and label every segment with the nearest learned medoid, so that
//! a held-out take can be written as a string over the same `K` symbols and
//! scored ([`crate::score`]).
//!
//! The segmentation uses the learned parameters ([`SymbolParams`]): segment
//! boundaries on the genetic algorithm's grid of candidate cuts (every
//! `candidate_step_frames` frames, the last segment at least
//! `min_segment_frames` long), segments of at most `max_segment_frames`
//! frames. Among all such segmentations, dynamic programming picks the one
//! with the least total *clarity cost* `Σ_i L(s_i) · min_k D(s_i, m_k)`
//! (eq. 4's numerator: frames times the segment distance of eq. 1 to the
//! nearest medoid `m_k`, a segment of the training motion); each segment
//! gets the symbol of that medoid. Poses are compared with the training
//! motion's pose distance and body size ([`PoseFeatures::from_track_with_scale`]),
//! so distances are in the same units as during learning.
//!
//! The result is a [`SymbolString`] over the learned `K` symbols. Its
//! `medoids` are empty (the medoids lie in the training motion), and its
//! quality has `E′` measured against the learned medoids with the training
//! `d_max`; `R` (the medoids' share of the motion) is not defined here and
//! is 0.

use std::time::Instant;

use crate::data::Motion;
use crate::distance::{FrameSpan, PoseFeatures};
use crate::error::{GrammarError, Result};
use crate::model::{GrammarModel, SourceInfo, SymbolsFile, MODEL_FORMAT, SYMBOLS_FORMAT};
use crate::objective::ClusterQuality;
use crate::symbols::{SymbolParams, SymbolSearchStats, SymbolSegment, SymbolString};

/// Largest number of grid segments (positions × widths) the segmentation
/// considers.
pub(crate) const MAX_ASSIGN_CANDIDATES: usize = 50_000_000;

/// Labels `new` with the symbols of `learned` (found on `train`): see the
/// module documentation. `params` are the parameters the symbols were
/// learned with.
///
/// Errors: invalid parameters; medoids outside `learned` or `train`;
/// features of different dimensions; a motion shorter than
/// `min_segment_frames`.
pub fn assign_symbols(
    train: &PoseFeatures,
    learned: &SymbolString,
    params: &SymbolParams,
    new: &PoseFeatures,
) -> Result<SymbolString> {
    params.validate()?;
    if train.dim() != new.dim() {
        return Err(GrammarError::Invalid(format!(
            "the new motion has {} feature values per frame, the training motion {}",
            new.dim(),
            train.dim()
        )));
    }
    if learned.medoids.len() != learned.k || learned.k == 0 {
        return Err(GrammarError::Invalid(format!(
            "{} medoids for k = {} symbols",
            learned.medoids.len(),
            learned.k
        )));
    }
    let mut medoids: Vec<(FrameSpan, usize)> = Vec::with_capacity(learned.k);
    for (k, &m) in learned.medoids.iter().enumerate() {
        let seg = learned.segments.get(m).ok_or_else(|| {
            GrammarError::Invalid(format!(
                "medoid of symbol {k}: segment {m} of {}",
                learned.segments.len()
            ))
        })?;
        train.check_segment(seg.segment())?;
        medoids.push((seg.segment(), k));
    }
    let t = new.n_frames();
    if t < params.min_segment_frames {
        return Err(GrammarError::too_short(
            "motion (frames) for one segment",
            params.min_segment_frames,
            t,
        ));
    }
    // Grid of candidate cuts, as the GA's.
    let step = params.candidate_step_frames;
    let mut points = vec![0usize];
    let mut c = step;
    while c + params.min_segment_frames <= t {
        points.push(c);
        c += step;
    }
    points.push(t);
    let widths = params.max_segment_frames / step + 1;
    if points.len().saturating_mul(widths) > MAX_ASSIGN_CANDIDATES {
        return Err(GrammarError::param(
            "max_segment_frames",
            format!(
                "{} grid points × {widths} segment widths is too many: at most \
                 {MAX_ASSIGN_CANDIDATES}",
                points.len()
            ),
        ));
    }
    let nearest = |s: FrameSpan| -> Result<(f64, usize)> {
        let mut best = (f64::INFINITY, 0);
        for &(m, k) in &medoids {
            let d = new.segment_distance_to(s, train, m)?;
            if d < best.0 {
                best = (d, k);
            }
        }
        Ok(best)
    };
    // best[b]: least cost of frames 0..points[b]; from[b]: previous point.
    let n = points.len();
    let mut best = vec![f64::INFINITY; n];
    let mut from = vec![(usize::MAX, 0usize, 0f64); n];
    best[0] = 0.0;
    for b in 1..n {
        for a in (0..b).rev() {
            let len = points[b] - points[a];
            if len > params.max_segment_frames {
                break;
            }
            if !best[a].is_finite() || len < params.min_segment_frames {
                continue;
            }
            let (d, k) = nearest(FrameSpan::new(points[a], points[b]))?;
            let cost = best[a] + len as f64 * d;
            if cost < best[b] {
                best[b] = cost;
                from[b] = (a, k, d);
            }
        }
    }
    if !best[n - 1].is_finite() {
        return Err(GrammarError::Invalid(format!(
            "no segmentation of {t} frames into segments of {}–{} frames on cuts every {step} frames",
            params.min_segment_frames, params.max_segment_frames
        )));
    }
    let mut segments = Vec::new();
    let mut e = 0.0;
    let mut b = n - 1;
    while b > 0 {
        let (a, k, d) = from[b];
        if a == usize::MAX {
            return Err(GrammarError::Invalid(
                "segmentation back-pointers are inconsistent".into(),
            ));
        }
        segments.push(SymbolSegment {
            start: points[a],
            end: points[b],
            symbol: k,
        });
        e += (points[b] - points[a]) as f64 * d;
        b = a;
    }
    segments.reverse();
    let e_prime = if learned.d_max > 0.0 {
        e / (t as f64 * learned.d_max)
    } else {
        0.0
    };
    Ok(SymbolString {
        k: learned.k,
        n_frames: t,
        fps: new.fps(),
        segments,
        medoids: Vec::new(),
        quality: ClusterQuality::from_terms(0.0, e_prime, params.omega),
        d_max: learned.d_max,
        stats: SymbolSearchStats::default(),
    })
}

impl SymbolsFile {
    /// Labels `motion` with these symbols (`assign_symbols`); `train` is
    /// the motion they were found on (read it with
    /// [`SourceInfo::load`](crate::model::SourceInfo::load)).
    pub fn assign(&self, train: &Motion, motion: &Motion) -> Result<SymbolsFile> {
        let t0 = Instant::now();
        let train_feat = PoseFeatures::from_track(&train.track, &self.distance)?;
        if train_feat.n_frames() != self.symbols.n_frames {
            return Err(GrammarError::Invalid(format!(
                "the training motion has {} frames, the symbols were found on {}",
                train_feat.n_frames(),
                self.symbols.n_frames
            )));
        }
        let feat = PoseFeatures::from_track_with_scale(
            &motion.track,
            &self.distance,
            Some(train_feat.body_scale()),
        )?;
        let symbols = assign_symbols(&train_feat, &self.symbols, &self.params, &feat)?;
        Ok(SymbolsFile {
            format: SYMBOLS_FORMAT.into(),
            source: SourceInfo::of(motion),
            text: symbols.text(),
            symbols,
            params: self.params.clone(),
            distance: self.distance.clone(),
            seconds: t0.elapsed().as_secs_f64(),
        })
    }
}

/// Reads learned symbols from a grammar model JSON ([`GrammarModel`],
/// checked with [`GrammarModel::load_checked`]) or a symbols JSON
/// ([`SymbolsFile`]), whichever the file's `format` names.
pub fn load_learned_symbols(path: impl AsRef<std::path::Path>) -> Result<SymbolsFile> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| GrammarError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| GrammarError::Json {
        what: path.display().to_string(),
        source: e,
    })?;
    match v.get("format").and_then(|f| f.as_str()) {
        Some(MODEL_FORMAT) => Ok(GrammarModel::load_checked(path)?.symbols_file()),
        Some(SYMBOLS_FORMAT) => SymbolsFile::load(path),
        other => Err(GrammarError::file(
            path,
            "format",
            format!(
                "`{}`, expected `{MODEL_FORMAT}` or `{SYMBOLS_FORMAT}`",
                other.unwrap_or("")
            ),
        )),
    }
}

impl GrammarModel {
    /// The model's symbols as a symbols file (as `mp grammar symbols`
    /// wrote it).
    pub fn symbols_file(&self) -> SymbolsFile {
        SymbolsFile {
            format: SYMBOLS_FORMAT.into(),
            source: self.source.clone(),
            text: self.symbols.text(),
            symbols: self.symbols.clone(),
            params: self.symbol_params.clone(),
            distance: self.distance.clone(),
            seconds: self.seconds_symbols,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    /// A 1-D feature track made of blocks of constant values.
    fn feats(blocks: &[(usize, f64)]) -> PoseFeatures {
        let t: usize = blocks.iter().map(|b| b.0).sum();
        let mut rows = Array2::<f64>::zeros((t, 1));
        let mut i = 0;
        for &(len, v) in blocks {
            for _ in 0..len {
                rows[[i, 0]] = v;
                i += 1;
            }
        }
        PoseFeatures::from_rows(rows.view(), 10.0).unwrap()
    }

    fn params() -> SymbolParams {
        SymbolParams {
            k: 2,
            candidate_step_frames: 10,
            min_segment_frames: 10,
            max_segment_frames: 20,
            ..Default::default()
        }
    }

    #[test]
    fn nearest_medoid_labels_and_grid_segmentation() {
        // Training: symbol 0 = value 0 (frames 0..10), symbol 1 = value 5.
        let train = feats(&[(10, 0.0), (10, 5.0)]);
        let learned = SymbolString {
            k: 2,
            n_frames: 20,
            fps: 10.0,
            segments: vec![
                SymbolSegment {
                    start: 0,
                    end: 10,
                    symbol: 0,
                },
                SymbolSegment {
                    start: 10,
                    end: 20,
                    symbol: 1,
                },
            ],
            medoids: vec![0, 1],
            quality: ClusterQuality::from_terms(1.0, 0.0, 0.5),
            d_max: 5.0,
            stats: SymbolSearchStats::default(),
        };
        let new = feats(&[(10, 5.0), (20, 0.0), (10, 4.0)]);
        let s = assign_symbols(&train, &learned, &params(), &new).unwrap();
        assert_eq!(s.k, 2);
        assert_eq!(s.n_frames, 40);
        assert_eq!(s.segments.first().map(|x| x.start), Some(0));
        assert_eq!(s.segments.last().map(|x| x.end), Some(40));
        assert!(s.segments.windows(2).all(|w| w[0].end == w[1].start));
        // Per frame: 5 → symbol 1, 0 → symbol 0, 4 → symbol 1.
        let fs = s.frame_symbols();
        assert!(fs[..10].iter().all(|&x| x == 1), "{fs:?}");
        assert!(fs[10..30].iter().all(|&x| x == 0), "{fs:?}");
        assert!(fs[30..].iter().all(|&x| x == 1), "{fs:?}");
        // Only the last block differs from its medoid: 10 frames × 1.
        assert!((s.quality.e_prime - 10.0 / (40.0 * 5.0)).abs() < 1e-6);
    }

    #[test]
    fn cross_track_distance_matches_the_single_track_one() {
        let f = feats(&[(7, 0.0), (5, 3.0), (9, 1.0)]);
        for (a, b) in [((0, 7), (7, 12)), ((2, 20), (5, 9)), ((3, 4), (0, 21))] {
            let (a, b) = (FrameSpan::new(a.0, a.1), FrameSpan::new(b.0, b.1));
            let d1 = f.segment_distance(a, b).unwrap();
            let d2 = f.segment_distance_to(a, &f, b).unwrap();
            let d3 = f.segment_distance_to(b, &f, a).unwrap();
            assert!(
                (d1 - d2).abs() < 1e-9 && (d1 - d3).abs() < 1e-9,
                "{d1} {d2} {d3}"
            );
        }
        assert!(f
            .segment_distance_to(FrameSpan::new(0, 30), &f, FrameSpan::new(0, 3))
            .is_err());
    }

    #[test]
    fn bad_input_is_an_error() {
        let train = feats(&[(10, 0.0), (10, 5.0)]);
        let mut learned = SymbolString {
            k: 2,
            n_frames: 20,
            fps: 10.0,
            segments: vec![SymbolSegment {
                start: 0,
                end: 20,
                symbol: 0,
            }],
            medoids: vec![0, 3],
            quality: ClusterQuality::from_terms(1.0, 0.0, 0.5),
            d_max: 5.0,
            stats: SymbolSearchStats::default(),
        };
        let new = feats(&[(30, 0.0)]);
        assert!(assign_symbols(&train, &learned, &params(), &new).is_err());
        learned.medoids = vec![0];
        assert!(assign_symbols(&train, &learned, &params(), &new).is_err());
        learned.medoids = vec![0, 0];
        let short = feats(&[(5, 0.0)]);
        assert!(assign_symbols(&train, &learned, &params(), &short).is_err());
        let p = SymbolParams { k: 0, ..params() };
        assert!(assign_symbols(&train, &learned, &p, &new).is_err());
        assert!(assign_symbols(&train, &learned, &params(), &new).is_ok());
    }
}
