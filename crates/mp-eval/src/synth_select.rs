//! Choosing the motion of a synthetic repetition case ([`crate::synth_reps`]):
//! pose distances on a body scale, the cycle (a natural near-loop of a real
//! clip), and padding that does not repeat.

use ndarray::{s, Array2, Array3, ArrayView2};

use crate::synth_reps::{Rng, Source, SourceClip};

/// Mean distance between the joints `joints` of two poses (`J × D`), over `scale`.
pub fn pose_dist(a: ArrayView2<f64>, b: ArrayView2<f64>, joints: &[usize], scale: f64) -> f64 {
    if joints.is_empty() || scale <= 0.0 {
        return 0.0;
    }
    let d = a.ncols();
    let sum: f64 = joints
        .iter()
        .map(|&j| {
            (0..d)
                .map(|k| (a[[j, k]] - b[[j, k]]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .sum();
    sum / joints.len() as f64 / scale
}

/// Distance between frames `i` and `j` of a clip.
pub fn frame_dist(c: &SourceClip, i: usize, j: usize) -> f64 {
    pose_dist(
        c.pos.slice(s![i, .., ..]),
        c.pos.slice(s![j, .., ..]),
        &c.joints,
        c.scale,
    )
}

/// A cycle: frames `a..b` of clip `clip`, whose pose at `b` is close to that at `a`.
#[derive(Debug, Clone, PartialEq)]
pub struct Cycle {
    pub clip: usize,
    pub a: usize,
    pub b: usize,
    /// Distance between the poses at `a` and `b` (body scale).
    pub seam: f64,
    /// Largest distance from the pose at `a` within the cycle (body scale).
    pub amp: f64,
    /// [`sub_period_ratio`] of the cycle.
    pub sub_period: f64,
}

/// A cycle must move at least this much (largest distance from its first
/// pose, body scale): a still stretch has no countable repetition.
pub const MIN_AMP: f64 = 0.05;

/// How close frames `a..b` come to holding a shorter period, 0..: the
/// smallest circular mean distance between the cycle and itself shifted by a
/// quarter to three quarters of its length, over the largest at any lag.
/// One cycle of a sine scores 0.71, two cycles 0.
pub fn sub_period_ratio(c: &SourceClip, a: usize, b: usize) -> f64 {
    let n = b - a;
    if n < 8 {
        return 1.0;
    }
    let lag_dist: Vec<f64> = (1..n)
        .map(|l| {
            (0..n)
                .map(|t| frame_dist(c, a + t, a + (t + l) % n))
                .sum::<f64>()
                / n as f64
        })
        .collect();
    let top = lag_dist.iter().cloned().fold(0.0, f64::max);
    if top <= 0.0 {
        return 1.0;
    }
    let (lo, hi) = (n.div_ceil(4), 3 * n / 4);
    (lo..=hi)
        .map(|l| lag_dist[l - 1])
        .fold(f64::INFINITY, f64::min)
        / top
}

/// Cycles whose [`sub_period_ratio`] is below this hold a shorter period, or
/// two halves alike enough (a salsa basic step: forward, then back) that a
/// count of twice N would be as right, and are refused.
pub const MAX_SUB_PERIOD: f64 = 0.5;

/// The near-loops of clip `k` of length `lmin..=lmax` frames: for each start
/// `a` (every `step` frames), the first local minimum `b` of the distance to
/// the pose at `a` whose seam is at most `ratio` of the motion so far.
fn near_loops(c: &SourceClip, k: usize, lmin: usize, lmax: usize, ratio: f64) -> Vec<Cycle> {
    let n = c.pos.dim().0;
    let step = ((c.fps / 15.0).round() as usize).max(1);
    let mut out = Vec::new();
    for a in (0..n).step_by(step) {
        if a + lmin + 1 >= n {
            break;
        }
        let last = (a + lmax).min(n - 2);
        let d: Vec<f64> = (a..=last + 1).map(|t| frame_dist(c, a, t)).collect();
        let mut amp = d[..lmin].iter().cloned().fold(0.0, f64::max);
        for b in a + lmin..=last {
            let db = d[b - a];
            if db <= d[b - a - 1] && db <= d[b - a + 1] && amp >= MIN_AMP && db <= ratio * amp {
                out.push(Cycle {
                    clip: k,
                    a,
                    b,
                    seam: db,
                    amp,
                    sub_period: 1.0,
                });
                break;
            }
            amp = amp.max(db);
        }
    }
    out
}

/// A cycle of `lmin_s..=lmax_s` seconds from a random clip of `src`:
/// among the near-loops of a few clips, a random one of the best quarter
/// (seam over motion), without a shorter period inside. Seams of at most a
/// fifth of the motion are preferred; half is accepted when no clip has
/// better. `None` when no clip of the source holds such a cycle.
pub fn find_cycle(src: &Source, rng: &mut Rng, lmin_s: f64, lmax_s: f64) -> Option<Cycle> {
    for ratio in [0.2, 0.5] {
        for _ in 0..12 {
            let k = rng.below(src.clips.len());
            let c = &src.clips[k];
            let lmin = (lmin_s * c.fps).ceil() as usize;
            let lmax = (lmax_s * c.fps).floor() as usize;
            if lmin < 3 || lmax < lmin {
                continue;
            }
            let mut cands = near_loops(c, k, lmin, lmax, ratio);
            if cands.is_empty() {
                continue;
            }
            cands.sort_by(|x, y| (x.seam / x.amp).total_cmp(&(y.seam / y.amp)));
            cands.truncate(cands.len().div_ceil(4));
            // Random order among the best; the first without a sub-period wins.
            for _ in 0..cands.len().min(6) {
                let i = rng.below(cands.len());
                let mut cy = cands.swap_remove(i);
                cy.sub_period = sub_period_ratio(c, cy.a, cy.b);
                if cy.sub_period >= MAX_SUB_PERIOD {
                    return Some(cy);
                }
            }
        }
    }
    None
}

/// How periodic a stretch of poses (`T × J × D`) is, 0..1: the deepest dip of
/// the mean distance between the stretch and itself shifted by a lag (of at
/// least `0.3 s`, at most `T / 1.5`: one and a half cycles in view) below the
/// highest value at a shorter lag, over the highest value at any lag. A still
/// or steadily changing stretch scores 0, a repeated movement near 1.
pub fn periodicity(pos: &Array3<f64>, joints: &[usize], scale: f64, fps: f64) -> f64 {
    let t = pos.dim().0;
    let lo = ((0.3 * fps).ceil() as usize).max(1);
    let hi = (t as f64 / 1.5).floor() as usize;
    if hi < lo || t < 2 {
        return 0.0;
    }
    let lag_dist: Vec<f64> = (1..t)
        .map(|l| {
            (0..t - l)
                .map(|i| {
                    pose_dist(
                        pos.slice(s![i, .., ..]),
                        pos.slice(s![i + l, .., ..]),
                        joints,
                        scale,
                    )
                })
                .sum::<f64>()
                / (t - l) as f64
        })
        .collect();
    let top = lag_dist.iter().cloned().fold(0.0, f64::max);
    if top < 0.02 {
        return 0.0;
    }
    let mut best = 0.0f64;
    let mut rise = 0.0f64;
    for l in 1..=hi {
        rise = rise.max(lag_dist[l - 1]);
        if l >= lo {
            best = best.max(rise - lag_dist[l - 1]);
        }
    }
    (best / top).clamp(0.0, 1.0)
}

/// Frames `start .. start + n_src` of clip `c` resampled in time from the
/// clip's rate to `fps` (linear interpolation): `(positions, confidence)`.
pub fn resample_cycle(
    c: &SourceClip,
    start: usize,
    n_src: usize,
    fps: f64,
) -> (Array3<f64>, Array2<f64>) {
    let (_, j, d) = c.pos.dim();
    let n_out = (((n_src.max(1) - 1) as f64 * fps / c.fps).floor() as usize + 1).max(1);
    let mut pos = Array3::zeros((n_out, j, d));
    let mut conf = Array2::zeros((n_out, j));
    for o in 0..n_out {
        let u = (o as f64 * c.fps / fps).min((n_src - 1) as f64);
        let i0 = u.floor() as usize;
        let i1 = (i0 + 1).min(n_src - 1);
        let f = u - i0 as f64;
        for jj in 0..j {
            for k in 0..d {
                pos[[o, jj, k]] =
                    (1.0 - f) * c.pos[[start + i0, jj, k]] + f * c.pos[[start + i1, jj, k]];
            }
            conf[[o, jj]] = (1.0 - f) * c.conf[[start + i0, jj]] + f * c.conf[[start + i1, jj]];
        }
    }
    (pos, conf)
}

/// A stretch of motion played once, for before/after the repetitions.
#[derive(Debug, Clone)]
pub struct Padding {
    pub pos: Array3<f64>,
    pub conf: Array2<f64>,
    /// `clip name [start, end)` in the clip's frames.
    pub what: String,
    /// [`periodicity`] of the stretch.
    pub periodicity: f64,
}

/// About `len` frames (at `fps`) of motion from `src` that repeats as little
/// as possible: the least periodic of six random stretches (half from the
/// cycle's clip outside the cycle, half from other clips; a stretch the
/// cycle's poses run through counts as periodic too). A stretch from
/// another clip is moved and scaled onto the cycle clip's place and body
/// size. Shorter when the clips are shorter; `None` for `len` 0.
pub fn find_padding(
    src: &Source,
    rng: &mut Rng,
    len: usize,
    fps: f64,
    cycle: Option<&Cycle>,
    home: usize,
) -> Option<Padding> {
    if len == 0 {
        return None;
    }
    let hc = &src.clips[home];
    let mut best: Option<(f64, Padding)> = None;
    for attempt in 0..6 {
        let k = if attempt % 2 == 0 {
            home
        } else {
            rng.below(src.clips.len())
        };
        let c = &src.clips[k];
        let n = c.pos.dim().0;
        let want = ((len as f64 * c.fps / fps).round() as usize).max(2);
        // Frames allowed: the whole clip, or for the cycle's clip the longer side of the cycle.
        let (lo, hi) = match cycle {
            Some(cy) if cy.clip == k => {
                if cy.a >= n - cy.b {
                    (0, cy.a)
                } else {
                    (cy.b, n)
                }
            }
            _ => (0, n),
        };
        if hi < lo + 2 {
            continue;
        }
        let take = want.min(hi - lo);
        let start = lo + rng.below(hi - lo - take + 1);
        let (mut pos, conf) = resample_cycle(c, start, take, fps);
        if k != home {
            align(&mut pos, c.scale, hc, cycle);
        }
        let mut score = periodicity(&pos, &hc.joints, hc.scale, fps);
        if let Some(cy) = cycle {
            score += 0.5 * resemblance(&pos, hc, cy);
        }
        let what = format!("{} [{start}, {})", c.name, start + take);
        let better = best.as_ref().is_none_or(|(b, _)| score < *b);
        if better {
            best = Some((
                score,
                Padding {
                    periodicity: periodicity(&pos, &hc.joints, hc.scale, fps),
                    pos,
                    conf,
                    what,
                },
            ));
        }
    }
    best.map(|(_, p)| p)
}

/// Moves and scales poses of another clip (body scale `scale`) onto the
/// place (mean over the cycle, or the whole clip) and body size of `home`.
fn align(pos: &mut Array3<f64>, scale: f64, home: &SourceClip, cycle: Option<&Cycle>) {
    let (a, b) = cycle.map_or((0, home.pos.dim().0), |c| (c.a, c.b));
    let d = pos.dim().2;
    let centre = |p: ArrayView2Frames| -> Vec<f64> {
        (0..d)
            .map(|k| p.slice(s![.., .., k]).mean().unwrap_or(0.0))
            .collect()
    };
    let from = centre(pos.view());
    let to = centre(home.pos.slice(s![a..b, .., ..]));
    let g = if scale > 0.0 { home.scale / scale } else { 1.0 };
    for ((_, _, k), v) in pos.indexed_iter_mut() {
        *v = (*v - from[k]) * g + to[k];
    }
}

type ArrayView2Frames<'a> = ndarray::ArrayView3<'a, f64>;

/// How closely a stretch runs through the cycle's poses, 0..1: 1 − (mean over
/// its frames of the distance to the nearest cycle pose) / (half the cycle's
/// motion), floored at 0.
fn resemblance(pos: &Array3<f64>, c: &SourceClip, cy: &Cycle) -> f64 {
    let t = pos.dim().0;
    let mean = (0..t)
        .map(|i| {
            (cy.a..cy.b)
                .map(|f| {
                    pose_dist(
                        pos.slice(s![i, .., ..]),
                        c.pos.slice(s![f, .., ..]),
                        &c.joints,
                        c.scale,
                    )
                })
                .fold(f64::INFINITY, f64::min)
        })
        .sum::<f64>()
        / t.max(1) as f64;
    (1.0 - mean / (0.5 * cy.amp).max(1e-9)).max(0.0)
}
