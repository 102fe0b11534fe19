//! Step 0, flaw detection: the flaw detector's probabilities per canonical
//! frame and joint, their mapping to the input's own frames with
//! hysteresis, frame promotion and dilation, the held-pose rule, and the
//! refill of what was flagged ([`super::refill`]).

use ndarray::{Array2, Array3, ArrayView3};

use super::foot_contact::{guard_refills, hold_slides};
use super::refill::repair_flagged;
use super::{check_finite, sigmoid, FlawCell, NetRefiner, RefineReport, RepairedRun};
use crate::baseline::held_frames;
use crate::error::{RefineError, Result};
use crate::motion::{to_features, MSR_JOINTS, NET_FRAMES};

impl NetRefiner<'_> {
    /// Flaw probabilities (`60 × 20`: canonical frame, joint) of a
    /// canonical clip's features (`60 × 60`).
    pub fn flaw_probabilities(&self, feats: &Array2<f32>) -> Result<Array2<f64>> {
        let flat: Vec<f32> = feats.iter().copied().collect();
        let logits = self.nets.flaw_logits(&flat)?;
        check_finite("flaw detector", &logits)?;
        Array2::from_shape_vec(
            (NET_FRAMES, MSR_JOINTS),
            logits.iter().map(|&l| sigmoid(l)).collect(),
        )
        .map_err(|e| RefineError::Shape(format!("flaw detector output: {e}")))
    }

    /// Step 0: runs the detector on `clip` (canonical) and refills the
    /// flagged frames of `pos` (`T × 20 × 3`, the frames `clip` was
    /// resampled from) in place. Returns the flagged cells, the flagged
    /// source frames and the refilled runs.
    ///
    /// With `feet` (the track's foot joints by leg and its frame rate) and
    /// [`super::NetRefineParams::foot_contact`], refills of planted feet are
    /// guarded and slides of planted feet held ([`super::foot_contact`]).
    pub(super) fn detect_and_repair(
        &self,
        clip: ArrayView3<'_, f64>,
        pos: &mut Array3<f64>,
        feet: Option<&FeetOf>,
    ) -> Result<FlawFindings> {
        let p = self.params;
        let prob = self.flaw_probabilities(&to_features(clip))?;
        let mut cells = Vec::new();
        for f in 0..NET_FRAMES {
            for j in 0..MSR_JOINTS {
                if prob[[f, j]] > p.flaw_probability {
                    cells.push(FlawCell {
                        frame: f,
                        joint: j,
                        probability: prob[[f, j]],
                    });
                }
            }
        }
        let t = pos.dim().0;
        let mut flags = hysteresis_flags(
            &source_probabilities(&prob, t),
            p.flaw_probability,
            p.flaw_extend_probability,
        );
        promote_frames(&mut flags, p.flaw_frame_share);
        let held = match p.held_pose_tolerance {
            Some(tol) => held_frames(pos.view(), tol),
            None => Vec::new(),
        };
        for &f in &held {
            flags.row_mut(f).fill(true);
        }
        let flagged_frames: Vec<usize> = (0..t)
            .filter(|&f| flags.row(f).iter().any(|&v| v))
            .collect();
        let flags = if p.flaw_dilation_frames > 0 {
            dilate_flags(&flags, p.flaw_dilation_frames)
        } else {
            flags
        };
        let input = pos.clone();
        let mut runs = repair_flagged(pos, &flags, p.flaw_repair, p.max_repair_run_frames)?;
        if let (Some(fc), Some(feet)) = (&p.foot_contact, feet) {
            let all: Vec<usize> = feet.legs.iter().flatten().copied().collect();
            if !all.is_empty() && t >= 2 {
                guard_refills(input.view(), pos, &runs, &all, fc.up_axis);
                runs.extend(hold_slides(pos, &feet.legs, feet.fps, fc)?);
            }
        }
        Ok(FlawFindings {
            cells,
            frames: flagged_frames,
            held,
            runs,
        })
    }
}

/// The foot joints of a track, by leg, and its frame rate.
#[derive(Debug)]
pub(super) struct FeetOf {
    pub(super) legs: Vec<Vec<usize>>,
    pub(super) fps: f64,
}

/// What step 0 (flaw detector and held poses) found and refilled.
#[derive(Debug, Default)]
pub(super) struct FlawFindings {
    cells: Vec<FlawCell>,
    frames: Vec<usize>,
    held: Vec<usize>,
    pub(super) runs: Vec<RepairedRun>,
}

impl FlawFindings {
    pub(super) fn into_report(self, report: &mut RefineReport) {
        report.flaw_cells = self.cells;
        report.flagged_frames = self.frames;
        report.held_frames = self.held;
        report.repaired_runs = self.runs;
    }
}

/// Source-frame probabilities (`t × J`) from canonical ones (`60 × J`).
///
/// Canonical frame `f` interpolates the source frames within one frame of
/// `u = f·(t − 1)/59` (its support), and the training labels
/// ([`crate::motion::canonical_mask`]) flag it when any frame of its
/// support is flawed — so a flawed source frame has *every* canonical frame
/// of its support flagged, while a clean neighbour has only some. A source
/// frame therefore takes the smallest probability of the canonical frames
/// whose support contains it, or, where none does (clips longer than 60
/// frames), the linear interpolation of the two nearest.
pub fn source_probabilities(prob: &Array2<f64>, t: usize) -> Array2<f64> {
    let (n, j) = prob.dim();
    let mut out = Array2::<f64>::zeros((t, j));
    if t == 0 || n == 0 {
        return out;
    }
    let scale = if n > 1 && t > 1 {
        (n - 1) as f64 / (t - 1) as f64
    } else {
        0.0
    };
    let back = if scale > 0.0 { 1.0 / scale } else { 0.0 };
    for s in 0..t {
        // Canonical position of source frame s.
        let v = s as f64 * scale;
        let lo = ((v - scale) - 1e-9).ceil().max(0.0) as usize;
        let hi = (((v + scale) + 1e-9).floor() as usize).min(n - 1);
        let support: Vec<usize> = (lo..=hi)
            .filter(|&f| (f as f64 * back - s as f64).abs() < 1.0 - 1e-9)
            .collect();
        for a in 0..j {
            out[[s, a]] = if support.is_empty() {
                let f0 = (v.floor() as usize).min(n - 1);
                let f1 = (f0 + 1).min(n - 1);
                let w = v - f0 as f64;
                (1.0 - w) * prob[[f0, a]] + w * prob[[f1, a]]
            } else {
                support
                    .iter()
                    .map(|&f| prob[[f, a]])
                    .fold(f64::INFINITY, f64::min)
            };
        }
    }
    out
}

/// Hysteresis flags (`t × J`) of source probabilities: per joint, runs of
/// frames above `extend` that contain a frame above `seed`.
pub fn hysteresis_flags(p: &Array2<f64>, seed: f64, extend: f64) -> Array2<bool> {
    let (t, j) = p.dim();
    let mut out = Array2::from_elem((t, j), false);
    for a in 0..j {
        let mut f = 0;
        while f < t {
            if p[[f, a]] <= extend {
                f += 1;
                continue;
            }
            let r0 = f;
            let mut hit = false;
            while f < t && p[[f, a]] > extend {
                hit |= p[[f, a]] > seed;
                f += 1;
            }
            if hit {
                for g in r0..f {
                    out[[g, a]] = true;
                }
            }
        }
    }
    out
}

/// Source-frame flags (`t × J`) from canonical probabilities (`60 × J`):
/// [`source_probabilities`] above `thr`, widened by `dilate` frames.
#[cfg(test)]
pub fn source_flags(prob: &Array2<f64>, t: usize, thr: f64, dilate: usize) -> Array2<bool> {
    let out = source_probabilities(prob, t).mapv(|v| v > thr);
    if dilate > 0 {
        dilate_flags(&out, dilate)
    } else {
        out
    }
}

/// Flags every joint of the frames (rows) where at least `share` of the
/// joints are flagged.
pub fn promote_frames(flags: &mut Array2<bool>, share: f64) {
    let j = flags.ncols();
    let need = ((share * j as f64).ceil() as usize).max(1);
    for mut row in flags.outer_iter_mut() {
        if row.iter().filter(|&&v| v).count() >= need {
            row.fill(true);
        }
    }
}

/// Widens every run of flags (per column) by `d` frames on each side.
pub fn dilate_flags(flags: &Array2<bool>, d: usize) -> Array2<bool> {
    let (t, j) = flags.dim();
    let mut out = flags.clone();
    for a in 0..j {
        for f in 0..t {
            if flags[[f, a]] {
                let lo = f.saturating_sub(d);
                let hi = (f + d).min(t.saturating_sub(1));
                for g in lo..=hi {
                    out[[g, a]] = true;
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::s;

    #[test]
    fn flags_map_to_source_frames_with_hysteresis() {
        let mut prob = Array2::<f64>::zeros((NET_FRAMES, 2));
        prob[[30, 0]] = 0.95;
        prob[[29, 0]] = 0.6;
        prob[[31, 0]] = 0.6;
        prob[[10, 1]] = 0.6; // never above the seed threshold
                             // Same frame count: identity.
        let sp = source_probabilities(&prob, NET_FRAMES);
        assert_eq!(sp, prob);
        let h = hysteresis_flags(&sp, 0.9, 0.5);
        let on: Vec<(usize, usize)> = (0..NET_FRAMES)
            .flat_map(|f| (0..2).map(move |j| (f, j)))
            .filter(|&(f, j)| h[[f, j]])
            .collect();
        assert_eq!(on, vec![(29, 0), (30, 0), (31, 0)]);
        assert_eq!(
            hysteresis_flags(&sp, 0.9, 0.9)
                .iter()
                .filter(|&&v| v)
                .count(),
            1
        );
        // More source frames (t = 89): canonical 29, 30, 31 sit at source
        // 43.25, 44.75, 46.24. Source 45 is interpolated by canonical 30
        // only (0.95); source 44 also by canonical 29 (0.6), so it stays
        // below 0.9.
        let sp2 = source_probabilities(&prob, 89);
        assert!((sp2[[44, 0]] - 0.6).abs() < 1e-12);
        let f2 = sp2.mapv(|v| v > 0.9);
        let on: Vec<usize> = (0..89).filter(|&f| f2[[f, 0]]).collect();
        assert_eq!(on, vec![45]);
        let d = dilate_flags(&f2, 2);
        assert_eq!((0..89).filter(|&f| d[[f, 0]]).count(), 5);
        assert_eq!(source_flags(&prob, 89, 0.9, 2), d);
        // Fewer canonical frames than source frames in a support (t = 180):
        // source frames between canonical frames are interpolated.
        let sp3 = source_probabilities(&prob, 178);
        // Canonical 30 sits exactly at source 90; source 91 is between 30 and 31.
        assert!((sp3[[90, 0]] - 0.95).abs() < 1e-12);
        assert!(sp3[[91, 0]] < 0.95 && sp3[[91, 0]] >= 0.6);
    }

    #[test]
    fn held_frames_are_exact_repeats() {
        let mut pos = Array3::<f64>::zeros((6, 2, 3));
        for f in 0..6 {
            pos[[f, 0, 0]] = f as f64 * 0.01;
            pos[[f, 1, 2]] = -(f as f64) * 0.02;
        }
        assert!(held_frames(pos.view(), 1e-4).is_empty());
        // Frames 3 and 4 hold frame 2's pose; frame 5 moves on.
        let two = pos.slice(s![2, .., ..]).to_owned();
        pos.slice_mut(s![3, .., ..]).assign(&two);
        pos.slice_mut(s![4, .., ..]).assign(&two);
        assert_eq!(held_frames(pos.view(), 1e-4), vec![3, 4]);
        // One joint moving by more than the tolerance breaks the hold.
        pos[[4, 1, 1]] += 2e-4;
        assert_eq!(held_frames(pos.view(), 1e-4), vec![3]);
        // A non-finite frame never counts.
        pos[[3, 0, 0]] = f64::NAN;
        assert!(held_frames(pos.view(), 1e-4).is_empty());
    }
}
