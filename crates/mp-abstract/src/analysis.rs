//! From a track to an abstract program in one call, reading and writing
//! abstract programs, and prediction by unrolling loops.

use std::path::Path;

use mp_concrete::{Program, SynthParams};
use mp_geom::{Checked, Validate};
use mp_geom::{Track, Units};
use ndarray::Array3;
use serde::{Deserialize, Serialize};

use crate::error::{AbstractError, Result};
use crate::exec::{render, unroll_loop, LoopReplay};
use crate::loops::{DetectedLoop, LoopParams};
use crate::model::{AbstractProgram, DetPrim, Loop, Stmt};
use crate::repetition::{
    estimate_period, intervals, PeriodEstimate, PeriodParams, RepetitiveInterval,
};
pub use crate::selfmatch::{SelfMatch, SelfMatchFallback};
use crate::synth::{synthesize, translate};

/// Parameters of the whole track → abstract-program analysis.
///
/// The default segmentation ([`SynthParams::default`]) chooses λ from the motion (paper §3.1: "in
/// practice, we adaptively choose λ at runtime to match the range of the
/// keypoint motion"): with the fixed reference λ, short or small repetitions
/// (a rope jump of a dozen frames) are swallowed by a single primitive and no
/// loop can be seen. The rule is [`Lambda::Spread`](mp_concrete::Lambda::Spread)
/// with one second ([`SynthParams::DEFAULT_SPREAD_SECONDS`]): a new segment is worth
/// the local spread of the keypoints held for one second, so λ keeps its
/// meaning across frame rates and body sizes. The C0 refit minimises the
/// Euclidean error ([`RefitNorm::Euclidean`](mp_concrete::RefitNorm::Euclidean)),
/// the norm the segmentation itself minimises.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct AbstractParams {
    /// Concrete synthesis (segmentation, fitting, scale rule).
    pub synth: SynthParams,
    /// Loop detection; its `unit_scale` is replaced by the one synthesis found for the track.
    pub loops: LoopParams,
}

impl Validate for AbstractParams {
    type Error = AbstractError;

    fn validate(&self) -> Result<()> {
        AbstractParams::validate(self)
    }
}

impl AbstractParams {
    /// Checks every field: the synthesis parameters ([`SynthParams::validate`])
    /// and the loop parameters ([`LoopParams::validate`]; their `unit_scale`
    /// is not checked since the analysis replaces it).
    pub fn validate(&self) -> Result<()> {
        self.synth.validate()?;
        LoopParams {
            unit_scale: 1.0,
            ..self.loops.clone()
        }
        .validate()
    }
}

/// Everything the analysis of one track produces.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Analysis {
    /// The concrete program.
    pub concrete: Program,
    /// Its deterministic abstract primitives (one per segment).
    pub prims: Vec<DetPrim>,
    /// The abstract program (loops rolled up).
    pub program: AbstractProgram,
    /// Detected loops (in primitive indices).
    pub loops: Vec<DetectedLoop>,
    /// Detected loops as frame intervals with counts.
    pub intervals: Vec<RepetitiveInterval>,
    /// Track units per reference pixel used throughout.
    pub unit_scale: f64,
}

impl AbstractProgram {
    /// The abstract program of a concrete program (loop detection at the
    /// given `unit_scale`), with the loops found and the deterministic
    /// primitives (one per segment) they were found in.
    pub fn from_concrete(
        program: &Program,
        loops: &LoopParams,
    ) -> Result<(AbstractProgram, Vec<DetectedLoop>, Vec<DetPrim>)> {
        let segs: Vec<(usize, Vec<mp_geom::Primitive>)> = program
            .segments
            .iter()
            .map(|s| (s.duration_frames, s.primitives.clone()))
            .collect();
        let prims = translate(&segs)?;
        let (prog, found) = synthesize(
            &prims,
            loops,
            program.fps,
            program.units.as_str(),
            program.joints.clone(),
        )?;
        Ok((prog, found, prims))
    }

    /// Reads an abstract program from `.json` or the text form (any other extension).
    pub fn read(path: impl AsRef<Path>) -> Result<AbstractProgram> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| AbstractError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        AbstractProgram::read_str(&text, path)
    }

    /// Parses and validates an abstract program as [`AbstractProgram::read`]
    /// does: JSON when `path` ends in `.json`, the text form otherwise;
    /// `path` names the source in errors.
    pub fn read_str(text: &str, path: &Path) -> Result<AbstractProgram> {
        let prog: AbstractProgram = if path.extension().is_some_and(|e| e == "json") {
            serde_json::from_str(text).map_err(|source| AbstractError::Json {
                path: path.to_path_buf(),
                source,
            })?
        } else {
            AbstractProgram::from_dsl(text).map_err(|e| match e {
                AbstractError::Parse {
                    line,
                    column,
                    message,
                } => AbstractError::Parse {
                    line,
                    column,
                    message: format!("{}: {message}", path.display()),
                },
                other => other,
            })?
        };
        prog.validate().map_err(|e| {
            let at = |m: String| format!("{}: {m}", path.display());
            match e {
                AbstractError::Shape(m) => AbstractError::Shape(at(m)),
                AbstractError::NonFinite(m) => AbstractError::NonFinite(at(m)),
                AbstractError::InvalidLoop(m) => AbstractError::InvalidLoop(at(m)),
                AbstractError::InvalidParam { name, reason } => AbstractError::InvalidParam {
                    name,
                    reason: at(reason),
                },
                other => other,
            }
        })?;
        Ok(prog)
    }

    /// Writes the program as `.json` or the text form, through a temporary
    /// file and a rename.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let text = if path.extension().is_some_and(|e| e == "json") {
            serde_json::to_string_pretty(self).map_err(|source| AbstractError::Json {
                path: path.to_path_buf(),
                source,
            })?
        } else {
            self.to_dsl()
        };
        let tmp = path.with_extension(format!(
            "{}.tmp",
            path.extension().and_then(|e| e.to_str()).unwrap_or("out")
        ));
        let io = |source| AbstractError::Io {
            path: path.to_path_buf(),
            source,
        };
        std::fs::write(&tmp, text).map_err(io)?;
        std::fs::rename(&tmp, path).map_err(io)
    }
}

/// Track → concrete program → abstract program, loops and repetition intervals.
///
/// Errors on parameters that [`AbstractParams::validate`] rejects.
pub fn analyse(track: &Track, params: &AbstractParams) -> Result<Analysis> {
    analyse_valid(track, &params.check()?)
}

/// [`analyse`] with its parameters checked.
fn analyse_valid(track: &Track, params: &Checked<&AbstractParams>) -> Result<Analysis> {
    let syn = Program::synthesize_detailed(track, &params.synth)?;
    Analysis::from_synthesis(syn, &params.loops)
}

impl Analysis {
    /// A concrete synthesis → abstract program, loops and repetition
    /// intervals; the loop thresholds use the synthesis' `unit_scale`.
    pub fn from_synthesis(syn: mp_concrete::Synthesis, loops: &LoopParams) -> Result<Analysis> {
        let loops = LoopParams {
            unit_scale: syn.unit_scale,
            ..loops.clone()
        };
        let (program, found, prims) = AbstractProgram::from_concrete(&syn.program, &loops)?;
        let intervals = intervals(&prims, &found, 0);
        Ok(Analysis {
            concrete: syn.program,
            prims,
            program,
            loops: found,
            intervals,
            unit_scale: syn.unit_scale,
        })
    }
}

/// Parameters of prediction by unrolling loops.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PredictParams {
    /// Analysis of the observed frames.
    pub analysis: AbstractParams,
    /// A loop is used only when the frames observed after its end amount to at
    /// most this many iteration periods (otherwise the motion has moved on).
    /// Finite and ≥ 0. Default 1.5.
    pub max_tail_periods: f64,
    /// The offset between the last observed pose and the unrolled loop decays
    /// to zero over this many periods (at least one frame). Finite and ≥ 0. Default 1.
    pub offset_decay_periods: f64,
    /// What an unrolled iteration executes. Default `UnrollSource::LastIteration`.
    pub source: UnrollSource,
    /// Where no usable loop is found: unroll the last period of the observed
    /// motion measured by autocorrelation ([`PeriodFallback`]); `None` holds
    /// the last pose instead. Default on.
    pub period_fallback: Option<PeriodFallback>,
    /// Where neither a loop nor the autocorrelation period is found (the
    /// period needs three observed cycles): replay the observed motion with the
    /// lag at which its most recent frames best match an earlier part
    /// ([`SelfMatchFallback`]), which works from about one observed cycle;
    /// `None` holds the last pose instead. Default on.
    #[serde(default = "default_self_match")]
    pub self_match: Option<SelfMatchFallback>,
}

fn default_self_match() -> Option<SelfMatchFallback> {
    Some(SelfMatchFallback::default())
}

/// Unrolling of the last observed period when the program has no usable loop:
/// future frame `h` (1-based) repeats observed frame `n − P + ((h − 1) mod P)`
/// for a period of `P` frames found by [`estimate_period`] over the observed
/// frames (which requires [`PeriodParams::min_cycles`] cycles).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PeriodFallback {
    /// Period estimation (defaults of [`PeriodParams`]).
    pub period: PeriodParams,
    /// Smallest normalised autocorrelation at the period for the motion to
    /// count as repetitive, in [0, 1]. Default 0.5.
    pub min_strength: f64,
}

impl Default for PeriodFallback {
    fn default() -> Self {
        PeriodFallback {
            period: PeriodParams::default(),
            min_strength: 0.5,
        }
    }
}

impl PredictParams {
    /// Checks every field: the analysis ([`AbstractParams::validate`]),
    /// `max_tail_periods` and `offset_decay_periods` finite and ≥ 0, and the
    /// fallbacks when enabled.
    pub fn validate(&self) -> Result<()> {
        self.analysis.validate()?;
        AbstractError::check_non_negative("max_tail_periods", self.max_tail_periods)?;
        AbstractError::check_non_negative("offset_decay_periods", self.offset_decay_periods)?;
        if let Some(fb) = &self.period_fallback {
            fb.validate()?;
        }
        if let Some(sm) = &self.self_match {
            sm.validate()?;
        }
        Ok(())
    }
}

impl PeriodFallback {
    /// Checks every field: `min_strength` in [0, 1] and the period parameters.
    pub fn validate(&self) -> Result<()> {
        if !(self.min_strength.is_finite() && (0.0..=1.0).contains(&self.min_strength)) {
            return Err(AbstractError::param(
                "min_strength",
                format!("must be in [0, 1], got {}", self.min_strength),
            ));
        }
        self.period.validate()
    }

    /// The `horizon` frames after `obs` by repeating its last period, with
    /// the estimate used; `None` when the motion is not clearly periodic.
    pub fn unroll(&self, obs: &Track, horizon: usize) -> Result<Option<(Track, PeriodEstimate)>> {
        if !(self.min_strength.is_finite() && (0.0..=1.0).contains(&self.min_strength)) {
            return Err(AbstractError::param(
                "min_strength",
                format!("must be in [0, 1], got {}", self.min_strength),
            ));
        }
        let n = obs.n_frames();
        let Some(est) = estimate_period(obs, 0, n, &self.period)? else {
            return Ok(None);
        };
        let p = est.period_frames;
        if est.strength < self.min_strength || p == 0 || p >= n || horizon == 0 {
            return Ok(None);
        }
        let mut filled = obs.clone();
        filled.fill_missing();
        let src = filled.positions();
        let (_, j, d) = src.dim();
        let mut pos = Array3::zeros((horizon, j, d));
        for h in 1..=horizon {
            let f = n - p + (h - 1) % p;
            pos.index_axis_mut(ndarray::Axis(0), h - 1)
                .assign(&src.index_axis(ndarray::Axis(0), f));
        }
        Ok(Some((future_track(obs, pos)?, est)))
    }
}

/// What each unrolled iteration of a loop executes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[non_exhaustive]
pub enum UnrollSource {
    /// The concrete primitives of the last observed iteration, repeated.
    #[default]
    LastIteration,
    /// The loop body's mean start/mid/end primitives (the abstract program's deterministic execution).
    Mean,
}

impl Default for PredictParams {
    fn default() -> Self {
        PredictParams {
            analysis: AbstractParams::default(),
            max_tail_periods: 1.5,
            offset_decay_periods: 1.0,
            source: UnrollSource::LastIteration,
            period_fallback: Some(PeriodFallback::default()),
            self_match: default_self_match(),
        }
    }
}

/// The predicted frames `pos` (`H × J × D`) after `obs` as a track with
/// `obs`'s frame rate, units and skeleton; joints never observed in `obs`
/// cannot be placed and get confidence 0.
pub(crate) fn future_track(obs: &Track, pos: Array3<f64>) -> Result<Track> {
    let (horizon, j, _) = pos.dim();
    let n = obs.n_frames();
    let mut conf = ndarray::Array2::ones((horizon, j));
    for ji in 0..j {
        if (0..n).all(|f| obs.confidence()[[f, ji]] <= 0.0) {
            conf.column_mut(ji).fill(0.0);
        }
    }
    Ok(Track::new(
        pos,
        Some(conf),
        obs.fps(),
        obs.units(),
        obs.skeleton().clone(),
    )?)
}

/// The result of [`unroll`].
#[derive(Debug, Clone, PartialEq)]
pub struct Unrolled {
    /// The predicted frames (`horizon` frames after the observed ones).
    pub track: Track,
    /// The loop that was unrolled, or `None` when no usable loop was found.
    pub used: Option<RepetitiveInterval>,
    /// Without a loop: the period whose last cycle was repeated
    /// ([`PredictParams::period_fallback`]); `None` with `used` also `None`
    /// means the last observed pose is held.
    pub period: Option<PeriodEstimate>,
    /// Without a loop or a period: the lag with which self-match unrolling
    /// ([`PredictParams::self_match`]) replayed the observed motion.
    pub self_match: Option<SelfMatch>,
}

/// Which path of [`unroll`] produced a prediction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum PredictMethod {
    /// A loop of the abstract program was unrolled.
    Loop,
    /// The last autocorrelation period was repeated ([`PeriodFallback`]).
    Period,
    /// The observed motion was replayed with its self-match lag ([`SelfMatchFallback`]).
    SelfMatch,
    /// The last observed pose was held.
    Constant,
}

impl PredictMethod {
    /// Lower-case name (`loop`, `period`, `self_match`, `constant`).
    pub fn as_str(&self) -> &'static str {
        match self {
            PredictMethod::Loop => "loop",
            PredictMethod::Period => "period",
            PredictMethod::SelfMatch => "self_match",
            PredictMethod::Constant => "constant",
        }
    }
}

impl Unrolled {
    /// The path that produced this prediction.
    pub fn method(&self) -> PredictMethod {
        if self.used.is_some() {
            PredictMethod::Loop
        } else if self.period.is_some() {
            PredictMethod::Period
        } else if self.self_match.is_some() {
            PredictMethod::SelfMatch
        } else {
            PredictMethod::Constant
        }
    }
}

fn prims_start_frame(prims: &[DetPrim], i: usize) -> usize {
    prims.iter().take(i).map(|p| p.duration).sum()
}

/// Holds the last observed pose of every joint for `horizon` frames.
pub fn predict_constant(observed: &Track, horizon: usize) -> Result<Track> {
    observed.require_frames("prediction", 1)?;
    let (_, j, d) = observed.positions().dim();
    let last = observed.n_frames() - 1;
    let mut pos = Array3::zeros((horizon.max(1), j, d));
    let mut conf = ndarray::Array2::zeros((horizon.max(1), j));
    // Last valid position of each joint.
    for ji in 0..j {
        let t = (0..=last)
            .rev()
            .find(|&t| observed.confidence()[[t, ji]] > 0.0)
            .unwrap_or(last);
        for h in 0..horizon.max(1) {
            for k in 0..d {
                pos[[h, ji, k]] = observed.positions()[[t, ji, k]];
            }
            conf[[h, ji]] = observed.confidence()[[t, ji]];
        }
    }
    let pos = pos.slice_move(ndarray::s![..horizon, .., ..]);
    let conf = conf.slice_move(ndarray::s![..horizon, ..]);
    Ok(Track::new(
        pos,
        Some(conf),
        observed.fps(),
        observed.units(),
        observed.skeleton().clone(),
    )?)
}

/// Predicts the `horizon` frames after the first `observe` frames of `track`
/// by unrolling the last detected loop (paper §4.4): the loop body is executed
/// at its means, in phase with the partial iteration observed after the loop,
/// and the offset between the last observed pose and the unrolled motion fades
/// out over `offset_decay_periods`. Without a usable loop, the last observed
/// period is repeated when the motion holds three clear cycles
/// ([`PeriodFallback`]), else the observed motion is replayed with the lag at
/// which its recent frames match an earlier part ([`SelfMatchFallback`], from
/// about one cycle), else the last pose is held. [`Unrolled::method`] says
/// which path was taken.
pub fn unroll(
    track: &Track,
    observe: usize,
    horizon: usize,
    params: &PredictParams,
) -> Result<Unrolled> {
    params.validate()?;
    if horizon == 0 {
        return Err(AbstractError::param("horizon", "must be ≥ 1"));
    }
    if observe < 2 || observe > track.n_frames() {
        return Err(AbstractError::param(
            "observe",
            format!(
                "must be in 2..={} (the track's length), got {observe}",
                track.n_frames()
            ),
        ));
    }
    let obs = track.slice_frames(0, observe)?;
    let analysis = match analyse_valid(&obs, &(&params.analysis).check()?) {
        Ok(a) => a,
        Err(AbstractError::Empty(_)) => return fallback_prediction(&obs, horizon, params),
        Err(e) => return Err(e),
    };
    let Some((l, interval)) = last_loop(&analysis) else {
        return fallback_prediction(&obs, horizon, params);
    };
    let period =
        (interval.end_frame - interval.start_frame) as f64 / interval.iterations.max(1) as f64;
    let tail = observe.saturating_sub(interval.end_frame) as f64;
    if period <= 0.0 || tail > params.max_tail_periods * period {
        return fallback_prediction(&obs, horizon, params);
    }
    // Unroll enough iterations from the loop's end to cover the tail and the horizon.
    let needed = tail + horizon as f64;
    let iters = ((needed / period).ceil() as usize + 1).max(1);
    let future = unrolled_motion(&analysis, l, interval, iters, params)?;
    let start = best_phase(&obs, &future, period, horizon);
    if future.n_frames() < start + horizon {
        return fallback_prediction(&obs, horizon, params);
    }
    let track = join_offset(&obs, &future, start, horizon, period, params)?;
    Ok(Unrolled {
        track,
        used: Some(interval.clone()),
        period: None,
        self_match: None,
    })
}

/// The prediction without a usable loop: the last observed period repeated
/// ([`PeriodFallback`]), else the observed motion replayed from where its
/// recent frames match ([`SelfMatchFallback`]), else the last pose held.
fn fallback_prediction(obs: &Track, horizon: usize, params: &PredictParams) -> Result<Unrolled> {
    if let Some(fb) = &params.period_fallback {
        if let Some((track, est)) = fb.unroll(obs, horizon)? {
            return Ok(Unrolled {
                track,
                used: None,
                period: Some(est),
                self_match: None,
            });
        }
    }
    if let Some(sm) = &params.self_match {
        if let Some((track, m)) = sm.unroll(obs, horizon)? {
            return Ok(Unrolled {
                track,
                used: None,
                period: None,
                self_match: Some(m),
            });
        }
    }
    Ok(Unrolled {
        track: predict_constant(obs, horizon)?,
        used: None,
        period: None,
        self_match: None,
    })
}

/// The program's last loop and its repetitive interval.
fn last_loop(analysis: &Analysis) -> Option<(&Loop, &RepetitiveInterval)> {
    let (li, interval) = analysis
        .program
        .stmts
        .iter()
        .enumerate()
        .filter(|(_, s)| matches!(s, Stmt::Loop(_)))
        .map(|(i, _)| i)
        .zip(analysis.intervals.iter())
        .last()?;
    match &analysis.program.stmts[li] {
        Stmt::Loop(l) => Some((l, interval)),
        _ => None,
    }
}

/// `iters` iterations of the loop from its end: the body at its means
/// ([`UnrollSource::Mean`]) or the latest typical observed iteration
/// repeated ([`UnrollSource::LastIteration`]).
fn unrolled_motion(
    analysis: &Analysis,
    l: &Loop,
    interval: &RepetitiveInterval,
    iters: usize,
    params: &PredictParams,
) -> Result<Track> {
    match params.source {
        UnrollSource::Mean => {
            let mut unrolled = l.clone();
            unrolled.iterations = iters;
            unrolled.observed.clear();
            let prims = unroll_loop(&unrolled, LoopReplay::Mean)?;
            let fit = mp_geom::FitParams {
                unit_scale: analysis.unit_scale,
                ..params.analysis.synth.fit.clone()
            };
            render(&prims, &analysis.program, &fit)
        }
        UnrollSource::LastIteration => {
            let k = interval.body_size;
            let det = analysis
                .loops
                .iter()
                .find(|d| {
                    d.body == k
                        && prims_start_frame(&analysis.prims, d.start) == interval.start_frame
                })
                .ok_or_else(|| AbstractError::NotFound("the unrolled loop's primitives".into()))?;
            let seg0 = det.start + typical_iteration(interval) * k;
            let one = &analysis.concrete.segments[seg0..seg0 + k];
            let mut prog = analysis.concrete.clone();
            prog.segments = (0..iters + 2).flat_map(|_| one.iter().cloned()).collect();
            Ok(prog.execute()?)
        }
    }
}

/// The latest iteration whose length is typical (within 15 % of the median
/// of the complete ones). The last iteration often absorbs the frames
/// observed after the loop, so with three or more it is not a candidate.
fn typical_iteration(interval: &RepetitiveInterval) -> usize {
    let lens: Vec<usize> = interval
        .boundaries
        .windows(2)
        .map(|w| w[1] - w[0])
        .collect();
    let candidates = if lens.len() >= 3 {
        lens.len() - 1
    } else {
        lens.len()
    };
    let mut sorted = lens[..candidates].to_vec();
    sorted.sort_unstable();
    let median = sorted[(sorted.len() - 1) / 2] as f64;
    (0..candidates)
        .rev()
        .find(|&i| (lens[i] as f64 - median).abs() <= 0.15 * median)
        .unwrap_or(candidates - 1)
}

/// Phase: the offset into the unrolled motion whose recent frames best match
/// the last observed frames (mean joint distance over a window of a third of
/// a period).
fn best_phase(obs: &Track, future: &Track, period: f64, horizon: usize) -> usize {
    let observe = obs.n_frames();
    let period_frames = (period.round() as usize).max(1);
    let m = (period_frames / 3).clamp(1, observe);
    let (_, j, d) = obs.positions().dim();
    let mut best = (f64::INFINITY, m);
    for s0 in m..(m + period_frames).min(future.n_frames().saturating_sub(horizon) + 1) {
        let mut cost = 0.0;
        let mut n = 0usize;
        for q in 0..m {
            let (fo, fu) = (observe - m + q, s0 - m + q);
            for ji in 0..j {
                if obs.confidence()[[fo, ji]] <= 0.0 {
                    continue;
                }
                let mut e = 0.0;
                for kk in 0..d {
                    e += (obs.positions()[[fo, ji, kk]] - future.positions()[[fu, ji, kk]]).powi(2);
                }
                cost += e.sqrt();
                n += 1;
            }
        }
        let cost = if n > 0 {
            cost / n as f64
        } else {
            f64::INFINITY
        };
        if cost < best.0 {
            best = (cost, s0);
        }
    }
    best.1
}

/// The `horizon` frames of `future` from `start`, plus the offset between the
/// last observed pose and the unrolled motion at that frame, fading out over
/// `offset_decay_periods` periods.
fn join_offset(
    obs: &Track,
    future: &Track,
    start: usize,
    horizon: usize,
    period: f64,
    params: &PredictParams,
) -> Result<Track> {
    let (observe, j, d) = obs.positions().dim();
    let mut pos = Array3::zeros((horizon, j, d));
    let last = observe - 1;
    let anchor = start - 1;
    let decay = (params.offset_decay_periods * period).max(1.0);
    for ji in 0..j {
        let valid = obs.confidence()[[last, ji]] > 0.0;
        for h in 0..horizon {
            let w = if valid {
                (1.0 - (h + 1) as f64 / decay).max(0.0)
            } else {
                0.0
            };
            for kk in 0..d {
                let off = obs.positions()[[last, ji, kk]] - future.positions()[[anchor, ji, kk]];
                pos[[h, ji, kk]] = future.positions()[[start + h, ji, kk]] + w * off;
            }
        }
    }
    let units = obs.units();
    let track = Track::new(pos, None, obs.fps(), units, obs.skeleton().clone())?;
    debug_assert!(units != Units::Unitless || d >= 1);
    Ok(track)
}
