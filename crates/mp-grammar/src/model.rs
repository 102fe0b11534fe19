//! The whole pipeline as files: motion → terminal symbols
//! ([`SymbolsFile`]) → sentences and grammar ([`GrammarModel`]) →
//! synthesis ([`GrammarModel::stitcher`]).
//!
//! Both files are JSON. They record where the motion came from (the files,
//! joined in order, and the frame step applied when reading them) so that
//! synthesis can read the same frames again, and every parameter used.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use mp_geom::Units;
use serde::{Deserialize, Serialize};

use crate::abl::AblStats;
use crate::data::{read_motions, Motion};
use crate::distance::{PoseDistanceParams, PoseFeatures};
use crate::error::{GrammarError, Result};
use crate::grammar::{DescriptionLength, Grammar};
use crate::sentences::{search_partition, PartitionParams};
use crate::symbols::{identify_symbols, symbol_name, SymbolParams, SymbolString};
use crate::synth::{StitchParams, Stitcher};

/// `format` field of a [`SymbolsFile`].
pub const SYMBOLS_FORMAT: &str = "mp-grammar-symbols/1";
/// `format` field of a [`GrammarModel`].
pub const MODEL_FORMAT: &str = "mp-grammar-model/1";

/// What kind of motion the symbols were found on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum SourceKind {
    /// BVH files (synthesis can write BVH).
    Bvh,
    /// Joint positions (pixels or metres).
    Positions,
    /// Unitless feature channels (e.g. the CMU joint-angle features).
    Features,
}

/// Where a motion came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SourceInfo {
    /// Files, joined in this order (absolute when they could be resolved).
    pub paths: Vec<PathBuf>,
    /// Kind of motion.
    pub kind: SourceKind,
    /// Every `frame_step`-th frame of each file was kept.
    pub frame_step: usize,
    /// Frames after joining and sub-sampling.
    pub n_frames: usize,
    /// Frame rate after sub-sampling.
    pub fps: f64,
    /// Joints (channels for features).
    pub n_joints: usize,
    /// Dimensions per joint.
    pub dims: usize,
}

impl SourceInfo {
    /// Describes a motion.
    pub fn of(motion: &Motion) -> Self {
        let t = &motion.track;
        SourceInfo {
            paths: motion
                .paths
                .iter()
                .map(|p| std::fs::canonicalize(p).unwrap_or_else(|_| p.clone()))
                .collect(),
            kind: if motion.bvh.is_some() {
                SourceKind::Bvh
            } else if t.units() == Units::Unitless {
                SourceKind::Features
            } else {
                SourceKind::Positions
            },
            frame_step: motion.frame_step,
            n_frames: t.n_frames(),
            fps: t.fps(),
            n_joints: t.n_joints(),
            dims: t.dims(),
        }
    }

    /// Reads the motion again (from `paths`, or from `override_paths` when
    /// given) and checks that it has the recorded frames and joints.
    pub fn load(&self, override_paths: Option<&[PathBuf]>) -> Result<Motion> {
        let paths = override_paths.unwrap_or(&self.paths);
        if paths.is_empty() {
            return Err(GrammarError::Empty(
                "no source motion path recorded; give one".into(),
            ));
        }
        let m = read_motions(paths, self.frame_step)?;
        let names = paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ");
        if m.track.n_frames() != self.n_frames
            || m.track.n_joints() != self.n_joints
            || m.track.dims() != self.dims
        {
            return Err(GrammarError::Invalid(format!(
                "{names}: {} frames × {} joints × {} dims after taking every {} frame(s), \
                 the symbols were found on {} × {} × {}",
                m.track.n_frames(),
                m.track.n_joints(),
                m.track.dims(),
                self.frame_step,
                self.n_frames,
                self.n_joints,
                self.dims
            )));
        }
        Ok(m)
    }
}

/// Terminal symbols of a motion, as written by `mp grammar symbols`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SymbolsFile {
    /// `SYMBOLS_FORMAT`.
    pub format: String,
    /// The motion.
    pub source: SourceInfo,
    /// The symbol string, space-separated.
    pub text: String,
    /// Segments with their symbols, medoids, objective and search counters.
    pub symbols: SymbolString,
    /// Parameters of the search.
    pub params: SymbolParams,
    /// Pose distance used.
    pub distance: PoseDistanceParams,
    /// Wall time of the search, seconds.
    pub seconds: f64,
}

/// All parameters of the pipeline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct PipelineParams {
    /// Pose distance.
    pub distance: PoseDistanceParams,
    /// Symbol identification.
    pub symbols: SymbolParams,
    /// Sentence partition and grammar induction.
    pub partition: PartitionParams,
}

/// A learned motion grammar with everything needed to synthesise from it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GrammarModel {
    /// `MODEL_FORMAT`.
    pub format: String,
    /// The motion.
    pub source: SourceInfo,
    /// The terminal symbols: segments (frame ranges) and their symbols.
    pub symbols: SymbolString,
    /// Cuts of the symbol string into sentences (a cut before symbol `c`).
    pub cuts: Vec<usize>,
    /// The sentences (terminal ids = symbol indices).
    pub sentences: Vec<Vec<u32>>,
    /// The grammar (terminal `i` is symbol `i`, named by [`symbol_name`]).
    pub grammar: Grammar,
    /// `DL = B(G) + B(Z | G)` of the sentences.
    pub description_length: DescriptionLength,
    /// ABL counters.
    pub abl: AblStats,
    /// Symbol identification parameters.
    pub symbol_params: SymbolParams,
    /// Partition and ABL parameters.
    pub partition_params: PartitionParams,
    /// Pose distance used.
    pub distance: PoseDistanceParams,
    /// Wall time of symbol identification, seconds.
    pub seconds_symbols: f64,
    /// Wall time of the partition search and grammar induction, seconds.
    pub seconds_grammar: f64,
}

fn write_json<T: Serialize>(path: &Path, v: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(v).map_err(|e| GrammarError::Json {
        what: path.display().to_string(),
        source: e,
    })?;
    mp_geom::write_atomic(path, text.as_bytes())?;
    Ok(())
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path, format: &str) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| GrammarError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    parse_json(&text, path, format)
}

fn parse_json<T: for<'de> Deserialize<'de>>(text: &str, path: &Path, format: &str) -> Result<T> {
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| GrammarError::Json {
        what: path.display().to_string(),
        source: e,
    })?;
    let found = v.get("format").and_then(|f| f.as_str()).unwrap_or("");
    if found != format {
        return Err(GrammarError::Invalid(format!(
            "{}: format `{found}`, expected `{format}`",
            path.display()
        )));
    }
    serde_json::from_value(v).map_err(|e| GrammarError::Json {
        what: path.display().to_string(),
        source: e,
    })
}

/// Checks that the segments of `s` tile `0..n_frames` with symbols in
/// `0..k`, that there are at least `k` segments and that the medoids are
/// segments.
fn check_symbols(s: &SymbolString, n_frames: usize) -> Result<()> {
    let mut pos = 0;
    for (i, seg) in s.segments.iter().enumerate() {
        if seg.start != pos || seg.end <= seg.start || seg.symbol >= s.k {
            return Err(GrammarError::Invalid(format!(
                "segment {i} ({}..{}, symbol {}) does not continue at frame {pos} \
                 with a symbol in 0..{}",
                seg.start, seg.end, seg.symbol, s.k
            )));
        }
        pos = seg.end;
    }
    if pos != s.n_frames || s.n_frames != n_frames {
        return Err(GrammarError::Invalid(format!(
            "segments end at frame {pos}, the motion has {n_frames} frames"
        )));
    }
    if s.k > s.segments.len() {
        return Err(GrammarError::Invalid(format!(
            "{} symbols for {} segments",
            s.k,
            s.segments.len()
        )));
    }
    if let Some(m) = s.medoids.iter().find(|&&m| m >= s.segments.len()) {
        return Err(GrammarError::Invalid(format!(
            "medoid segment {m} outside 0..{}",
            s.segments.len()
        )));
    }
    Ok(())
}

impl SymbolsFile {
    /// Writes the file (JSON, atomic).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        write_json(path.as_ref(), self)
    }
    /// Reads a file written by [`save`](Self::save).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let s: SymbolsFile = read_json(path.as_ref(), SYMBOLS_FORMAT)?;
        s.check()
            .map_err(|e| GrammarError::Invalid(format!("{}: {e}", path.as_ref().display())))?;
        Ok(s)
    }
    /// Checks that the segments tile the motion with symbols in range.
    pub fn check(&self) -> Result<()> {
        check_symbols(&self.symbols, self.source.n_frames)
    }
    /// Symbol index of each segment.
    pub fn string(&self) -> Vec<u32> {
        self.symbols
            .segments
            .iter()
            .map(|s| s.symbol as u32)
            .collect()
    }
}

/// Identifies the terminal symbols of a motion.
pub fn find_symbols(
    motion: &Motion,
    distance: &PoseDistanceParams,
    params: &SymbolParams,
) -> Result<SymbolsFile> {
    let t0 = Instant::now();
    let feat = PoseFeatures::from_track(&motion.track, distance)?;
    let symbols = identify_symbols(&feat, params)?;
    Ok(SymbolsFile {
        format: SYMBOLS_FORMAT.into(),
        source: SourceInfo::of(motion),
        text: symbols.text(),
        symbols,
        params: params.clone(),
        distance: distance.clone(),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Partitions the symbol string into sentences (MDL search) and learns
/// their grammar with ABL.
pub fn learn_grammar(symbols: &SymbolsFile, params: &PartitionParams) -> Result<GrammarModel> {
    symbols.check()?;
    let t0 = Instant::now();
    let terminals: Vec<String> = (0..symbols.symbols.k).map(symbol_name).collect();
    let string = symbols.string();
    let best = search_partition(&string, &terminals, params)?;
    Ok(GrammarModel {
        format: MODEL_FORMAT.into(),
        source: symbols.source.clone(),
        symbols: symbols.symbols.clone(),
        cuts: best.cuts,
        sentences: best.sentences,
        grammar: best.learned.grammar,
        description_length: best.dl,
        abl: best.learned.stats,
        symbol_params: symbols.params.clone(),
        partition_params: *params,
        distance: symbols.distance.clone(),
        seconds_symbols: symbols.seconds,
        seconds_grammar: t0.elapsed().as_secs_f64(),
    })
}

/// The whole pipeline: symbols, sentences, grammar.
pub fn learn_model(motion: &Motion, params: &PipelineParams) -> Result<GrammarModel> {
    let s = find_symbols(motion, &params.distance, &params.symbols)?;
    learn_grammar(&s, &params.partition)
}

impl GrammarModel {
    /// Writes the model (JSON, atomic).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        write_json(path.as_ref(), self)
    }
    /// Reads a model written by [`save`](Self::save).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| GrammarError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        Self::from_json(&text, path)
    }
    /// Parses model JSON text and checks it as [`load`](Self::load) does;
    /// `path` names the source in errors.
    pub fn from_json(text: &str, path: &Path) -> Result<Self> {
        let m: GrammarModel = parse_json(text, path, MODEL_FORMAT)?;
        m.grammar
            .validate()
            .and_then(|()| check_symbols(&m.symbols, m.source.n_frames))
            .map_err(|e| GrammarError::Invalid(format!("{}: {e}", path.display())))?;
        Ok(m)
    }

    /// The training symbol string (one symbol per segment).
    pub fn training_string(&self) -> Vec<usize> {
        self.symbols.segments.iter().map(|s| s.symbol).collect()
    }

    /// Readable summary: the rules (`LHS -> rhs  (uses)`), the sentences and
    /// a legend of the symbols (segments and lengths).
    pub fn rules_text(&self) -> String {
        let g = &self.grammar;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# {} nonterminals, {} rules, {} terminals; DL = {:.1} bits \
             (grammar {:.1} + sentences {:.1})",
            g.n_nonterminals(),
            g.n_rules(),
            g.used_terminals(),
            self.description_length.total_bits,
            self.description_length.grammar_bits,
            self.description_length.data_bits
        );
        s.push_str(&g.to_string());
        let _ = writeln!(s, "# {} sentences:", self.sentences.len());
        for z in &self.sentences {
            let _ = writeln!(s, "#   {}", g.sentence_text(z));
        }
        let _ = writeln!(s, "# symbols (segments, frames min–max, medoid frames):");
        for (k, mem) in self.symbols.members().iter().enumerate() {
            if mem.is_empty() {
                continue;
            }
            let lens: Vec<usize> = mem
                .iter()
                .map(|&i| self.symbols.segments[i].end - self.symbols.segments[i].start)
                .collect();
            let med = self
                .symbols
                .medoids
                .get(k)
                .and_then(|&m| self.symbols.segments.get(m))
                .map(|m| format!("{}..{}", m.start, m.end))
                .unwrap_or_default();
            let _ = writeln!(
                s,
                "#   {}: {} segments, {}–{} frames, medoid {}",
                symbol_name(k),
                mem.len(),
                lens.iter().min().copied().unwrap_or(0),
                lens.iter().max().copied().unwrap_or(0),
                med
            );
        }
        s
    }

    /// A stitcher over the source motion (read with [`SourceInfo::load`]),
    /// with the model's pose distance.
    pub fn stitcher(&self, motion: &Motion, params: &StitchParams) -> Result<Stitcher> {
        let p = StitchParams {
            distance: self.distance.clone(),
            ..params.clone()
        };
        Stitcher::new(&motion.track, motion.bvh.as_ref(), &self.symbols, &p)
    }
}
