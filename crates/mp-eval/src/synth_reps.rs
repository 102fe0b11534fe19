//! Synthetic repetition-counting cases built from real motion, after RepNet's
//! recipe on keypoints: a cycle of a real clip (a natural near-loop of
//! 0.5–3 s, its seam cross-faded) repeated N times (2..=20) with per-repetition
//! jitter of speed (±15 %), amplitude (±10 %, and ±15 % per joint), a smooth
//! warp of the phase inside each repetition (±10 %) and a slow drift, with
//! keypoint noise (σ up to 3 % of the body scale), between 0–3 s
//! of non-repeating motion of the same source; a share of cases (15 %) hold
//! no repetition (N = 0: motion played once) or one (N = 1). The truth is N,
//! with the frames where each repetition starts. Seeded and deterministic:
//! case `i` depends only on the seed, `i` and the sources.

use ndarray::{s, Array2, Array3};

use crate::synth_select::{find_cycle, find_padding, Cycle, Padding};
use mp_geom::{Skeleton, Track, Units};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The cases' random numbers: ChaCha8, one stream per case, so a case is
/// the same whatever the number of cases or threads.
#[derive(Debug, Clone)]
pub struct Rng(ChaCha8Rng);

impl Rng {
    /// The generator of case `index` under `seed`.
    pub fn for_case(seed: u64, index: usize) -> Self {
        let mut r = ChaCha8Rng::seed_from_u64(seed);
        r.set_stream(index as u64);
        Rng(r)
    }
    /// Uniform in [0, 1).
    pub fn f64(&mut self) -> f64 {
        self.0.random::<f64>()
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }
    /// Uniform in 0..n (0 for n = 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            self.0.random_range(0..n)
        }
    }
}

/// A stretch of real motion where a person is found (gaps filled).
#[derive(Debug, Clone)]
pub struct SourceClip {
    pub name: String,
    /// `T × J × D`, finite.
    pub pos: Array3<f64>,
    pub conf: Array2<f64>,
    pub fps: f64,
    /// Body scale (median diagonal of the pose's bounding box).
    pub scale: f64,
    /// Joints seen in most frames: the ones distances use.
    pub joints: Vec<usize>,
}

/// The clips of one data set (one skeleton, one unit).
#[derive(Debug, Clone)]
pub struct Source {
    pub name: String,
    pub units: Units,
    pub skeleton: Skeleton,
    pub clips: Vec<SourceClip>,
}

/// Settings of the recipe.
#[derive(Debug, Clone)]
pub struct SynthOpts {
    pub min_cycle_s: f64,
    pub max_cycle_s: f64,
    pub max_reps: usize,
    /// Share of cases with N = 0 or 1.
    pub non_rep_share: f64,
    pub max_pad_s: f64,
    pub max_len_s: f64,
    /// Relative speed change of a repetition, ±.
    pub speed_jitter: f64,
    /// Relative amplitude change, ±.
    pub amp_jitter: f64,
    /// Largest drift over the repetitions, body scales.
    pub drift: f64,
    /// Length of the seam cross-fades, seconds (at least 3 frames).
    pub blend_s: f64,
    /// Relative amplitude change of each joint in each repetition, ± (on
    /// top of the repetition's own): no two real repetitions move every
    /// limb alike.
    pub joint_amp_jitter: f64,
    /// Largest shift of a repetition's phase inside it, a fraction of the
    /// repetition (a smooth warp that is 0 at its ends): one part of a
    /// real cycle is hurried, another lingered on.
    pub phase_warp: f64,
    /// Largest keypoint noise, body scales: each case draws its σ in
    /// 0..this (as a pose model's jitter), smoothed over 3 frames.
    pub noise: f64,
}

impl Default for SynthOpts {
    fn default() -> Self {
        SynthOpts {
            min_cycle_s: 0.5,
            max_cycle_s: 3.0,
            max_reps: 20,
            non_rep_share: 0.15,
            max_pad_s: 3.0,
            max_len_s: 60.0,
            speed_jitter: 0.15,
            amp_jitter: 0.10,
            drift: 0.1,
            blend_s: 0.1,
            joint_amp_jitter: 0.15,
            phase_warp: 0.1,
            noise: 0.03,
        }
    }
}

/// One case.
#[derive(Debug, Clone)]
pub struct Case {
    pub id: usize,
    pub source: String,
    pub track: Track,
    /// Number of repetitions.
    pub truth: usize,
    /// Frames of the repetitions: `rep_start..rep_end`.
    pub rep_start: usize,
    pub rep_end: usize,
    /// Frame where each repetition starts, then `rep_end` (N + 1 entries; empty for N = 0).
    pub boundaries: Vec<usize>,
    /// Clip and frames of the cycle (N ≥ 1), its length in frames and seam.
    pub cycle: Option<(String, Cycle)>,
    /// What was played before and after.
    pub padding: Vec<String>,
    /// Largest [`crate::synth_select::periodicity`] of the padding.
    pub pad_periodicity: f64,
}

fn blend_frames(fps: f64, opts: &SynthOpts) -> usize {
    ((opts.blend_s * fps).round() as usize).max(3)
}

/// The cycle's frames with the seam cross-faded, plus a closing frame equal
/// to the first (`n + 1` frames): the last `w` frames fade into the frames
/// before `a` (which lead into the pose at `a`) when the clip has them, else
/// into an offset ramp that ends at the pose at `a`.
fn cycle_buffer(c: &SourceClip, cy: &Cycle, w: usize) -> (Array3<f64>, Array2<f64>) {
    let n = cy.b - cy.a;
    let w = w.min(n / 3).max(1);
    let mut pos = c.pos.slice(s![cy.a..cy.b + 1, .., ..]).to_owned();
    let conf = c.conf.slice(s![cy.a..cy.b + 1, ..]).to_owned();
    for i in 0..w {
        let alpha = (i + 1) as f64 / (w + 1) as f64;
        let t = n - w + i;
        let mut dst = pos.slice_mut(s![t, .., ..]);
        if cy.a >= w {
            let before = c.pos.slice(s![cy.a - w + i, .., ..]);
            dst.zip_mut_with(&before, |v, &p| *v = (1.0 - alpha) * *v + alpha * p);
        } else {
            let off = &c.pos.slice(s![cy.a, .., ..]) - &c.pos.slice(s![cy.b, .., ..]);
            dst.zip_mut_with(&off, |v, &o| *v += alpha * o);
        }
    }
    let first = pos.slice(s![0, .., ..]).to_owned();
    pos.slice_mut(s![n, .., ..]).assign(&first);
    (pos, conf)
}

/// Positions and confidence of the repetitions, and each one's first frame.
struct Reps {
    pos: Array3<f64>,
    conf: Array2<f64>,
    starts: Vec<usize>,
}

/// `n_reps` plays of the cycle buffer (`n + 1` frames), each resampled to its
/// own speed, scaled around the cycle's mean pose by an amplitude that
/// changes linearly from one repetition's start to the next, and drifting.
fn repeat(
    buf: &(Array3<f64>, Array2<f64>),
    n_reps: usize,
    rng: &mut Rng,
    opts: &SynthOpts,
    scale: f64,
) -> Reps {
    let (bp, bc) = buf;
    let (n1, j, d) = bp.dim();
    let n = n1 - 1;
    let mean = bp.slice(s![..n, .., ..]).mean_axis(ndarray::Axis(0));
    let lens: Vec<usize> = (0..n_reps)
        .map(|_| {
            ((n as f64 * (1.0 + rng.uniform(-opts.speed_jitter, opts.speed_jitter))).round()
                as usize)
                .max(2)
        })
        .collect();
    let gains: Vec<f64> = (0..=n_reps)
        .map(|_| 1.0 + rng.uniform(-opts.amp_jitter, opts.amp_jitter))
        .collect();
    let joint_gains: Vec<Vec<f64>> = (0..n_reps)
        .map(|_| {
            (0..j)
                .map(|_| 1.0 + rng.uniform(-opts.joint_amp_jitter, opts.joint_amp_jitter))
                .collect()
        })
        .collect();
    let warps: Vec<f64> = (0..n_reps)
        .map(|_| rng.uniform(-opts.phase_warp, opts.phase_warp))
        .collect();
    let total: usize = lens.iter().sum();
    let dir: Vec<f64> = (0..d).map(|_| rng.uniform(-1.0, 1.0)).collect();
    let norm = dir.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-9);
    let speed = rng.uniform(0.0, opts.drift) * scale / total.max(1) as f64;
    let drift: Vec<f64> = dir.iter().map(|v| v / norm * speed).collect();
    let mut pos = Array3::zeros((total, j, d));
    let mut conf = Array2::zeros((total, j));
    let mut starts = Vec::with_capacity(n_reps);
    let mut t = 0;
    for (r, &m) in lens.iter().enumerate() {
        starts.push(t);
        for q in 0..m {
            // Phase in 0..1, warped smoothly (monotone for |warp| < 1/π).
            let v = q as f64 / m as f64;
            let v = (v + warps[r] * (std::f64::consts::PI * v).sin()).clamp(0.0, 1.0);
            let u = (v * n as f64).min(n as f64 - 1e-9);
            let (i0, f) = (u.floor() as usize, u - u.floor());
            let g = gains[r] + (gains[r + 1] - gains[r]) * q as f64 / m as f64;
            for jj in 0..j {
                let g = g * joint_gains[r][jj];
                for k in 0..d {
                    let p = (1.0 - f) * bp[[i0, jj, k]] + f * bp[[i0 + 1, jj, k]];
                    let mk = mean.as_ref().map_or(0.0, |m| m[[jj, k]]);
                    pos[[t, jj, k]] = mk + g * (p - mk) + drift[k] * t as f64;
                }
                conf[[t, jj]] = (1.0 - f) * bc[[i0, jj]] + f * bc[[i0 + 1, jj]];
            }
            t += 1;
        }
    }
    Reps { pos, conf, starts }
}

/// Adds keypoint noise of standard deviation about `sigma` to every
/// coordinate: Gaussian (Box–Muller) white noise averaged over 3 frames and
/// scaled back to `sigma`, so that it wobbles as a pose model's does.
fn add_noise(pos: &mut Array3<f64>, sigma: f64, rng: &mut Rng) {
    let (n, j, d) = pos.dim();
    if sigma <= 0.0 || n == 0 {
        return;
    }
    let mut gauss = || {
        let (u1, u2) = (rng.f64().max(1e-12), rng.f64());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    };
    let white: Vec<f64> = (0..(n + 2) * j * d).map(|_| gauss()).collect();
    let at = |t: usize, jj: usize, k: usize| white[(t * j + jj) * d + k];
    // The mean of 3 independent draws has σ 1/√3: scaled back by √3.
    let g = sigma * 3f64.sqrt() / 3.0;
    for t in 0..n {
        for jj in 0..j {
            for k in 0..d {
                pos[[t, jj, k]] += g * (at(t, jj, k) + at(t + 1, jj, k) + at(t + 2, jj, k));
            }
        }
    }
}

/// Cross-fades the last `w` frames of `pos` into `target` (a pose `J × D`).
fn fade_tail(pos: &mut Array3<f64>, target: ndarray::ArrayView2<f64>, w: usize) {
    let t = pos.dim().0;
    let w = w.min(t);
    for i in 0..w {
        let alpha = (i + 1) as f64 / (w + 1) as f64;
        pos.slice_mut(s![t - w + i, .., ..])
            .zip_mut_with(&target, |v, &p| *v = (1.0 - alpha) * *v + alpha * p);
    }
}

/// Cross-fades the first `w` frames of `pos` out of `from`.
fn fade_head(pos: &mut Array3<f64>, from: ndarray::ArrayView2<f64>, w: usize) {
    let w = w.min(pos.dim().0);
    for i in 0..w {
        let alpha = (i + 1) as f64 / (w + 1) as f64;
        pos.slice_mut(s![i, .., ..])
            .zip_mut_with(&from, |v, &p| *v = alpha * *v + (1.0 - alpha) * p);
    }
}

/// Builds case `id` of source `src`; `None` when the source has no usable cycle.
pub fn make_case(src: &Source, id: usize, seed: u64, opts: &SynthOpts) -> Option<Case> {
    let mut rng = Rng::for_case(seed, id);
    let truth = if rng.f64() < opts.non_rep_share {
        rng.below(2)
    } else {
        2 + rng.below(opts.max_reps - 1)
    };
    let (mut pre_s, mut post_s) = (
        rng.uniform(0.0, opts.max_pad_s),
        rng.uniform(0.0, opts.max_pad_s),
    );
    if truth == 0 {
        // Motion played once: 2–6 s in one or two stretches.
        let len = rng.uniform(2.0, 6.0);
        let share = if rng.f64() < 0.5 {
            1.0
        } else {
            rng.uniform(0.3, 0.7)
        };
        (pre_s, post_s) = (len * share, len * (1.0 - share));
    }
    let cycle = if truth == 0 {
        None
    } else {
        let room =
            (opts.max_len_s - pre_s - post_s) / (truth as f64 * (1.0 + opts.speed_jitter) + 1.0);
        Some(find_cycle(
            src,
            &mut rng,
            opts.min_cycle_s,
            opts.max_cycle_s.min(room),
        )?)
    };
    let home = cycle
        .as_ref()
        .map_or_else(|| rng.below(src.clips.len()), |c| c.clip);
    let clip = &src.clips[home];
    let fps = clip.fps;
    let w = blend_frames(fps, opts);
    let pad = |rng: &mut Rng, secs: f64| {
        find_padding(
            src,
            rng,
            (secs * fps).round() as usize,
            fps,
            cycle.as_ref(),
            home,
        )
    };
    let pre: Option<Padding> = pad(&mut rng, pre_s);
    let post: Option<Padding> = pad(&mut rng, post_s);
    let (j, d) = (clip.pos.dim().1, clip.pos.dim().2);
    let empty = || (Array3::zeros((0, j, d)), Array2::zeros((0, j)));
    let (mut pre_p, pre_c) = pre
        .as_ref()
        .map_or_else(empty, |p| (p.pos.clone(), p.conf.clone()));
    let (mut post_p, post_c) = post
        .as_ref()
        .map_or_else(empty, |p| (p.pos.clone(), p.conf.clone()));
    let reps = match &cycle {
        Some(cy) => repeat(
            &cycle_buffer(clip, cy, w),
            truth,
            &mut rng,
            opts,
            clip.scale,
        ),
        None => Reps {
            pos: Array3::zeros((0, j, d)),
            conf: Array2::zeros((0, j)),
            starts: Vec::new(),
        },
    };
    let nr = reps.pos.dim().0;
    if nr > 0 {
        fade_tail(&mut pre_p, reps.pos.slice(s![0, .., ..]), w);
        let last = reps.pos.slice(s![nr - 1, .., ..]).to_owned();
        fade_head(&mut post_p, last.view(), w);
    } else if post_p.dim().0 > 0 {
        let first = post_p.slice(s![0, .., ..]).to_owned();
        fade_tail(&mut pre_p, first.view(), w);
    }
    let rep_start = pre_p.dim().0;
    let rep_end = rep_start + nr;
    let max_frames = (opts.max_len_s * fps).floor() as usize;
    let mut pos = ndarray::concatenate(
        ndarray::Axis(0),
        &[pre_p.view(), reps.pos.view(), post_p.view()],
    )
    .ok()?;
    let mut conf = ndarray::concatenate(
        ndarray::Axis(0),
        &[pre_c.view(), reps.conf.view(), post_c.view()],
    )
    .ok()?;
    if pos.dim().0 > max_frames {
        if rep_end > max_frames {
            return None;
        }
        pos = pos.slice(s![..max_frames, .., ..]).to_owned();
        conf = conf.slice(s![..max_frames, ..]).to_owned();
    }
    if pos.dim().0 < 4 {
        return None;
    }
    add_noise(
        &mut pos,
        rng.uniform(0.0, opts.noise) * clip.scale,
        &mut rng,
    );
    let track = Track::new(pos, Some(conf), fps, src.units, src.skeleton.clone()).ok()?;
    let mut boundaries: Vec<usize> = reps.starts.iter().map(|s| s + rep_start).collect();
    if truth > 0 {
        boundaries.push(rep_end);
    }
    let padding: Vec<String> = [("before", &pre), ("after", &post)]
        .iter()
        .filter_map(|(k, p)| p.as_ref().map(|p| format!("{k}: {}", p.what)))
        .collect();
    let pad_periodicity = [&pre, &post]
        .iter()
        .filter_map(|p| p.as_ref().map(|p| p.periodicity))
        .fold(0.0, f64::max);
    Some(Case {
        id,
        source: src.name.clone(),
        track,
        truth,
        rep_start,
        rep_end,
        boundaries,
        cycle: cycle.map(|c| (clip.name.clone(), c)),
        padding,
        pad_periodicity,
    })
}

/// `n` cases over the sources in turn (case `i` from source `i mod S`); a
/// case its source cannot make is drawn again under the next seed stream.
pub fn generate(sources: &[Source], n: usize, seed: u64, opts: &SynthOpts) -> Vec<Case> {
    use rayon::prelude::*;
    (0..n)
        .into_par_iter()
        .filter_map(|i| {
            let src = &sources[i % sources.len().max(1)];
            (0..8u64).find_map(|retry| {
                let mut c = make_case(
                    src,
                    i,
                    seed.wrapping_add(retry.wrapping_mul(0x5851_F42D_4C95_7F2D)),
                    opts,
                )?;
                c.id = i;
                Some(c)
            })
        })
        .collect()
}

#[cfg(test)]
#[path = "synth_reps_tests.rs"]
mod tests;
