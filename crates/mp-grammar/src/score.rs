//! Code length of a symbol string (e.g. a held-out take) under a learned
//! grammar, the first-order finite-state machine and a unigram model, all
//! with the same additive smoothing: how well each model *generalises*.
//!
//! All three are estimated from the training data of a model (the symbol
//! string, its sentences and the grammar's rule counts) over the same `K`
//! symbols, with add-`α` smoothing on every count table (`α` = 0.5 by
//! default, the Krichevsky–Trofimov estimator):
//!
//! * **unigram**: `p(a) = (c(a) + α) / (N + α K)` per symbol;
//! * **FSM**: the first symbol by the unigram, then
//!   `p(b | a) = (c(a, b) + α) / (c(a, ·) + α K)` with the transition counts
//!   of the training string;
//! * **grammar**: the string is coded as a sequence of *pieces*, each either
//!   a sentence derived from the start symbol or one *escaped* symbol. A
//!   piece costs `−log2 p(kind)` with `p(sentence) = (n + α) / (n + 2α)` and
//!   `p(escape) = α / (n + 2α)` (`n` = training sentences, none of which was
//!   escaped); a sentence then costs `−log2` of its derivation's
//!   probability, rule `r` of nonterminal `X` having
//!   `p(r | X) = (count(r) + α) / (Σ_X count + α h_X)` (`h_X` = rules of `X`;
//!   with no counts this is the paper's `log2 h_X` per node, §5.1), and an
//!   escaped symbol costs its unigram code. The pieces and derivations are
//!   the ones that minimise the total: a chart over every span of at most
//!   `max_sentence_len` symbols (the cheapest derivation of each span, as in
//!   [`Grammar::parse`]), then dynamic programming over the cut points.
//!
//! Code lengths are reported in bits and in bits per symbol. The model with
//! the lower code length on strings it was not trained on predicts them
//! better.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{GrammarError, Result};
use crate::grammar::{Grammar, Sym, Tree};
use crate::model::{GrammarModel, SymbolsFile, SYMBOLS_FORMAT};

/// Longest sentence a parse may cover ([`ScoreParams::max_sentence_len`]).
pub const MAX_SCORE_SENTENCE_LEN: usize = 1_000;
/// Longest string that can be scored, symbols.
pub(crate) const MAX_SCORED_SYMBOLS: usize = 1_000_000;
/// Largest parse chart (nonterminals × positions × span lengths).
pub const MAX_CHART_CELLS: usize = 1 << 27;

/// Parameters of `score_string`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoreParams {
    /// Additive smoothing `α` of every count table, in `(0, 1000]`.
    /// Default 0.5.
    pub alpha: f64,
    /// Longest sentence a grammar parse may cover, symbols, in
    /// `1..=MAX_SCORE_SENTENCE_LEN`. Default 24 (twice the partition's
    /// preferred longest sentence).
    pub max_sentence_len: usize,
}

impl Default for ScoreParams {
    fn default() -> Self {
        ScoreParams {
            alpha: 0.5,
            max_sentence_len: 24,
        }
    }
}

impl ScoreParams {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        if !(self.alpha.is_finite() && self.alpha > 0.0 && self.alpha <= 1000.0) {
            return Err(GrammarError::param(
                "alpha",
                format!("must be in (0, 1000], got {}", self.alpha),
            ));
        }
        if self.max_sentence_len == 0 || self.max_sentence_len > MAX_SCORE_SENTENCE_LEN {
            return Err(GrammarError::param(
                "max_sentence_len",
                format!(
                    "must be in 1..={MAX_SCORE_SENTENCE_LEN}, got {}",
                    self.max_sentence_len
                ),
            ));
        }
        Ok(())
    }
}

/// A code length.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CodeLength {
    /// Total bits.
    pub bits: f64,
    /// Symbols coded.
    pub symbols: usize,
    /// `bits / symbols`.
    pub bits_per_symbol: f64,
}

impl CodeLength {
    fn new(bits: f64, symbols: usize) -> Self {
        CodeLength {
            bits,
            symbols,
            bits_per_symbol: bits / symbols.max(1) as f64,
        }
    }
}

/// One piece of the grammar's parse of a string.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Piece {
    /// Symbols `start..end` derived from the start symbol.
    Sentence {
        /// First symbol.
        start: usize,
        /// One past the last symbol.
        end: usize,
        /// Bits of this piece (kind + derivation).
        bits: f64,
        /// The derivation.
        tree: Tree,
    },
    /// One symbol coded by the unigram model.
    Escape {
        /// Position.
        at: usize,
        /// The symbol.
        symbol: u32,
        /// Bits of this piece (kind + symbol).
        bits: f64,
    },
}

/// Code lengths of one string under the three models.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StringScore {
    /// The grammar (with escapes).
    pub grammar: CodeLength,
    /// The first-order FSM.
    pub fsm: CodeLength,
    /// The unigram model.
    pub unigram: CodeLength,
    /// The grammar's cheapest parse, pieces in order.
    pub parse: Vec<Piece>,
    /// Symbols inside derived sentences (the rest were escaped).
    pub symbols_in_sentences: usize,
    /// Parameters used.
    pub params: ScoreParams,
}

impl StringScore {
    /// The parse as text: sentences in brackets, escaped symbols as `<a>`.
    pub fn parse_text(&self, g: &Grammar) -> String {
        let name = |t: u32| {
            g.terminals
                .get(t as usize)
                .cloned()
                .unwrap_or_else(|| format!("#{t}"))
        };
        self.parse
            .iter()
            .map(|p| match p {
                Piece::Sentence { tree, .. } => format!(
                    "[{}]",
                    tree.yield_terminals()
                        .into_iter()
                        .map(name)
                        .collect::<Vec<_>>()
                        .join(" ")
                ),
                Piece::Escape { symbol, .. } => format!("<{}>", name(*symbol)),
            })
            .collect::<Vec<_>>()
            .join(" ")
    }
}

fn check_string(what: &str, s: &[u32], k: usize) -> Result<()> {
    if let Some((i, &x)) = s.iter().enumerate().find(|(_, &x)| x as usize >= k) {
        return Err(GrammarError::Invalid(format!(
            "{what}: symbol {x} at position {i} is outside 0..{k}"
        )));
    }
    Ok(())
}

/// Scores `string` under `grammar`, and under the FSM and unigram model of
/// `training` (the training symbol string), over the grammar's terminals
/// (see the module documentation).
///
/// Errors: invalid parameters or grammar, an empty or too long string, a
/// symbol outside the grammar's terminals, a chart over
/// [`MAX_CHART_CELLS`].
pub fn score_string(
    grammar: &Grammar,
    training: &[u32],
    string: &[u32],
    params: &ScoreParams,
) -> Result<StringScore> {
    params.validate()?;
    grammar.validate()?;
    let k = grammar.terminals.len();
    if k == 0 {
        return Err(GrammarError::Empty("grammar has no terminal".into()));
    }
    if string.is_empty() {
        return Err(GrammarError::Empty(
            "symbol string to score is empty".into(),
        ));
    }
    if string.len() > MAX_SCORED_SYMBOLS {
        return Err(GrammarError::param(
            "string",
            format!(
                "{} symbols is too long: at most {MAX_SCORED_SYMBOLS}",
                string.len()
            ),
        ));
    }
    if training.is_empty() {
        return Err(GrammarError::Empty(
            "training symbol string is empty".into(),
        ));
    }
    check_string("symbol string", string, k)?;
    check_string("training string", training, k)?;
    let a = params.alpha;
    let kf = k as f64;

    // Unigram and FSM.
    let mut uni = vec![0usize; k];
    let mut trans = vec![vec![0usize; k]; k];
    for &x in training {
        uni[x as usize] += 1;
    }
    for w in training.windows(2) {
        trans[w[0] as usize][w[1] as usize] += 1;
    }
    let n_train = training.len() as f64;
    let uni_bits = |x: u32| -((uni[x as usize] as f64 + a) / (n_train + a * kf)).log2();
    let unigram: f64 = string.iter().map(|&x| uni_bits(x)).sum();
    let mut fsm = uni_bits(string[0]);
    for w in string.windows(2) {
        let row = &trans[w[0] as usize];
        let total: usize = row.iter().sum();
        fsm -= ((row[w[1] as usize] as f64 + a) / (total as f64 + a * kf)).log2();
    }

    // Grammar: rule costs.
    let nv = grammar.nonterminals.len();
    let mut totals = vec![0f64; nv];
    let mut per = vec![0f64; nv];
    for r in &grammar.rules {
        totals[r.lhs as usize] += r.count as f64;
        per[r.lhs as usize] += 1.0;
    }
    let rule_cost: Vec<f64> = grammar
        .rules
        .iter()
        .map(|r| {
            let x = r.lhs as usize;
            -((r.count as f64 + a) / (totals[x] + a * per[x])).log2()
        })
        .collect();
    let n_sent = totals[grammar.start as usize];
    let sent_kind = -((n_sent + a) / (n_sent + 2.0 * a)).log2();
    let esc_kind = -(a / (n_sent + 2.0 * a)).log2();

    let n = string.len();
    let lmax = params.max_sentence_len.min(n);
    let cells = nv.saturating_mul(n + 1).saturating_mul(lmax + 1);
    if cells > MAX_CHART_CELLS {
        return Err(GrammarError::param(
            "max_sentence_len",
            format!(
                "chart of {nv} nonterminals × {} positions × {} lengths is too large: \
                 at most {MAX_CHART_CELLS} cells",
                n + 1,
                lmax + 1
            ),
        ));
    }
    let chart = Chart::fill(grammar, &rule_cost, string, lmax);

    // Cheapest pieces: g[j] = bits of string[..j].
    let s = grammar.start as usize;
    let mut g = vec![f64::INFINITY; n + 1];
    let mut from = vec![(0usize, false); n + 1];
    g[0] = 0.0;
    for j in 1..=n {
        let esc = g[j - 1] + esc_kind + uni_bits(string[j - 1]);
        g[j] = esc;
        from[j] = (j - 1, false);
        for len in 1..=lmax.min(j) {
            let i = j - len;
            let c = chart.best[chart.idx(s, i, len)];
            if c.is_finite() {
                let total = g[i] + sent_kind + c;
                if total < g[j] {
                    g[j] = total;
                    from[j] = (i, true);
                }
            }
        }
    }
    let mut parse = Vec::new();
    let mut j = n;
    let mut in_sentences = 0;
    while j > 0 {
        let (i, sentence) = from[j];
        if sentence {
            let tree = chart
                .build(grammar, grammar.start, i, j - i, string, 0)
                .ok_or_else(|| {
                    GrammarError::Invalid(format!(
                        "no derivation rebuilt for symbols {i}..{j} (inconsistent chart)"
                    ))
                })?;
            parse.push(Piece::Sentence {
                start: i,
                end: j,
                bits: g[j] - g[i],
                tree,
            });
            in_sentences += j - i;
        } else {
            parse.push(Piece::Escape {
                at: i,
                symbol: string[i],
                bits: g[j] - g[i],
            });
        }
        j = i;
    }
    parse.reverse();
    Ok(StringScore {
        grammar: CodeLength::new(g[n], n),
        fsm: CodeLength::new(fsm, n),
        unigram: CodeLength::new(unigram, n),
        parse,
        symbols_in_sentences: in_sentences,
        params: *params,
    })
}

/// Cheapest derivation cost of every nonterminal over every span of at most
/// `lmax` symbols.
struct Chart<'a> {
    n: usize,
    lmax: usize,
    best: Vec<f64>,
    back: Vec<usize>,
    rule_cost: &'a [f64],
}

impl<'a> Chart<'a> {
    fn idx(&self, x: usize, i: usize, len: usize) -> usize {
        (x * (self.n + 1) + i) * (self.lmax + 1) + len
    }

    fn fill(g: &Grammar, rule_cost: &'a [f64], w: &[u32], lmax: usize) -> Self {
        let n = w.len();
        let nv = g.nonterminals.len();
        let size = nv * (n + 1) * (lmax + 1);
        let mut c = Chart {
            n,
            lmax,
            best: vec![f64::INFINITY; size],
            back: vec![usize::MAX; size],
            rule_cost,
        };
        for len in 0..=lmax {
            // Fixpoint for this span length (unit and ε chains).
            for _round in 0..=nv {
                let mut changed = false;
                for i in 0..=(n - len) {
                    for (ri, r) in g.rules.iter().enumerate() {
                        let seq = c.seq_table(&r.rhs, w, i, len);
                        let Some(&cost) = seq.last().and_then(|row| row.get(len)) else {
                            continue;
                        };
                        let total = cost + rule_cost[ri];
                        let k = c.idx(r.lhs as usize, i, len);
                        if total < c.best[k] {
                            c.best[k] = total;
                            c.back[k] = ri;
                            changed = true;
                        }
                    }
                }
                if !changed {
                    break;
                }
            }
        }
        c
    }

    /// `f[p][b]`: cost of `rhs[..p]` over `w[i..i + b]`.
    fn seq_table(&self, rhs: &[Sym], w: &[u32], i: usize, span: usize) -> Vec<Vec<f64>> {
        crate::grammar::rhs_span_costs(rhs, w, i, span, |x, s, e| self.best[self.idx(x, s, e - s)])
    }

    fn build(
        &self,
        g: &Grammar,
        x: u32,
        i: usize,
        len: usize,
        w: &[u32],
        depth: usize,
    ) -> Option<Tree> {
        if depth > 4 * (self.lmax + 1) * (g.nonterminals.len() + 1) {
            return None;
        }
        let ri = *self.back.get(self.idx(x as usize, i, len))?;
        let rule = g.rules.get(ri)?;
        let f = self.seq_table(&rule.rhs, w, i, len);
        let target_total = self.best[self.idx(x as usize, i, len)] - self.rule_cost[ri];
        let mut children = Vec::with_capacity(rule.rhs.len());
        let mut b = len;
        let mut target = target_total;
        for p in (0..rule.rhs.len()).rev() {
            match rule.rhs[p] {
                Sym::T(t) => {
                    children.push(Tree::Leaf(t));
                    b = b.checked_sub(1)?;
                    target = f[p][b];
                }
                Sym::N(y) => {
                    let mut found = None;
                    for a in (0..=b).rev() {
                        let sub = self.best[self.idx(y as usize, i + a, b - a)];
                        let c = f[p][a] + sub;
                        if f[p][a].is_finite()
                            && sub.is_finite()
                            && (c - target).abs() <= 1e-9 * target.abs().max(1.0)
                        {
                            found = Some(a);
                            break;
                        }
                    }
                    let a = found?;
                    children.push(self.build(g, y, i + a, b - a, w, depth + 1)?);
                    target = f[p][a];
                    b = a;
                }
            }
        }
        children.reverse();
        Some(Tree::Node {
            nt: x,
            rule: ri,
            children,
        })
    }
}

impl GrammarModel {
    /// Scores a symbol string under this model's grammar, and the FSM and
    /// unigram model of its training string (`score_string`).
    pub fn score(&self, string: &[u32], params: &ScoreParams) -> Result<StringScore> {
        let training: Vec<u32> = self.training_string().iter().map(|&s| s as u32).collect();
        score_string(&self.grammar, &training, string, params)
    }
}

/// Reads a symbol string to score against `grammar`: a symbols JSON file
/// (`mp grammar symbols`, format `SYMBOLS_FORMAT`) or a text file of
/// symbol names separated by whitespace (lines are joined).
///
/// Errors ([`GrammarError::File`], naming the file and the field or
/// position): unreadable file, malformed JSON, a symbol count `k` other than
/// the grammar's, an unknown symbol name, an empty string.
pub fn load_symbol_string(path: impl AsRef<Path>, grammar: &Grammar) -> Result<Vec<u32>> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| GrammarError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let k = grammar.terminals.len();
    if text.trim_start().starts_with('{') {
        let s = parse_symbols_file(&text, path)?;
        if s.symbols.k != k {
            return Err(GrammarError::file(
                path,
                "symbols.k",
                format!("{} symbols, the grammar has {k} terminals", s.symbols.k),
            ));
        }
        let string = s.string();
        if string.is_empty() {
            return Err(GrammarError::file(path, "symbols.segments", "no segment"));
        }
        return Ok(string);
    }
    let mut out = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        for (wi, w) in line.split_whitespace().enumerate() {
            let id = grammar
                .terminals
                .iter()
                .position(|t| t == w)
                .ok_or_else(|| {
                    GrammarError::file(
                        path,
                        format!("line {}, symbol {}", ln + 1, wi + 1),
                        format!("`{w}` is not a terminal of the grammar ({k} terminals)"),
                    )
                })?;
            out.push(id as u32);
        }
    }
    if out.is_empty() {
        return Err(GrammarError::file(path, "symbols", "no symbol in the file"));
    }
    Ok(out)
}

/// Parses symbols JSON text and checks it as [`SymbolsFile::load`] does;
/// `path` names the source in errors.
fn parse_symbols_file(text: &str, path: &Path) -> Result<SymbolsFile> {
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| GrammarError::Json {
        what: path.display().to_string(),
        source: e,
    })?;
    let found = v.get("format").and_then(|f| f.as_str()).unwrap_or("");
    if found != SYMBOLS_FORMAT {
        return Err(GrammarError::file(
            path,
            "format",
            format!("`{found}`, expected `{SYMBOLS_FORMAT}`"),
        ));
    }
    let s: SymbolsFile = serde_json::from_value(v).map_err(|e| GrammarError::Json {
        what: path.display().to_string(),
        source: e,
    })?;
    s.check()
        .map_err(|e| GrammarError::file(path, "symbols.segments", e.to_string()))?;
    Ok(s)
}

impl GrammarModel {
    /// Reads a model ([`GrammarModel::load`]) and checks that its parts
    /// agree: the segments tile the motion with symbols below `k`, one
    /// terminal per symbol, the sentences use known terminals, the medoids
    /// are segments. Errors name the file and the field.
    pub fn load_checked(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let m = GrammarModel::load(path)?;
        let k = m.symbols.k;
        if m.grammar.terminals.len() != k {
            return Err(GrammarError::file(
                path,
                "grammar.terminals",
                format!(
                    "{} terminals, the symbols have k = {k}",
                    m.grammar.terminals.len()
                ),
            ));
        }
        let mut pos = 0;
        for (i, seg) in m.symbols.segments.iter().enumerate() {
            if seg.start != pos || seg.end <= seg.start || seg.symbol >= k {
                return Err(GrammarError::file(
                    path,
                    format!("symbols.segments[{i}]"),
                    format!(
                        "{}..{} with symbol {} does not continue at frame {pos} \
                         with a symbol in 0..{k}",
                        seg.start, seg.end, seg.symbol
                    ),
                ));
            }
            pos = seg.end;
        }
        if m.symbols.segments.is_empty() || pos != m.symbols.n_frames {
            return Err(GrammarError::file(
                path,
                "symbols.segments",
                format!("end at frame {pos}, the motion has {}", m.symbols.n_frames),
            ));
        }
        if let Some((i, &md)) = m
            .symbols
            .medoids
            .iter()
            .enumerate()
            .find(|(_, &md)| md >= m.symbols.segments.len())
        {
            return Err(GrammarError::file(
                path,
                format!("symbols.medoids[{i}]"),
                format!("segment {md} of {}", m.symbols.segments.len()),
            ));
        }
        for (i, z) in m.sentences.iter().enumerate() {
            if let Some(&t) = z.iter().find(|&&t| t as usize >= k) {
                return Err(GrammarError::file(
                    path,
                    format!("sentences[{i}]"),
                    format!("symbol {t} outside 0..{k}"),
                ));
            }
        }
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.chars().map(|c| c.to_string()).collect()
    }

    fn basketball() -> Grammar {
        Grammar::from_text(
            "S -> r X1 X2 m\nX1 -> X3 X4 X3\nX2 -> p | s\nX3 -> f | ε\nX4 -> d | ε",
            Some(&words("rfdpsm")),
        )
        .unwrap()
    }

    #[test]
    fn derivable_string_is_one_sentence_per_sentence() {
        let g = basketball();
        let z = g.encode_sentences(&[words("rdpmrfdsm")]).unwrap();
        let training = g.encode_sentences(&[words("rdpmrpm")]).unwrap();
        let s = score_string(&g, &training[0], &z[0], &ScoreParams::default()).unwrap();
        assert_eq!(s.symbols_in_sentences, 9);
        assert_eq!(s.parse.len(), 2, "{}", s.parse_text(&g));
        assert_eq!(s.parse_text(&g), "[r d p m] [r f d s m]");
        // No rule counts: p(r | X) = 1 / h_X and p(sentence) = 1/2.
        // rdpm: X2 → p, X3 → ε, X4 → d, X3 → ε, one bit each (two rules
        // each) = 4 bits; rfdsm likewise; plus one bit per piece.
        assert!((s.grammar.bits - 10.0).abs() < 1e-9, "{:?}", s.grammar);
        // Sum of pieces is the total.
        let sum: f64 = s
            .parse
            .iter()
            .map(|p| match p {
                Piece::Sentence { bits, .. } | Piece::Escape { bits, .. } => *bits,
            })
            .sum();
        assert!((sum - s.grammar.bits).abs() < 1e-9);
        // Trees yield their spans.
        for p in &s.parse {
            if let Piece::Sentence {
                start, end, tree, ..
            } = p
            {
                assert_eq!(tree.yield_terminals(), z[0][*start..*end].to_vec());
            }
        }
    }

    #[test]
    fn underivable_symbols_are_escaped_and_fsm_unigram_match_hand_values() {
        let g = basketball();
        let z = g.encode_sentences(&[words("ffrpm")]).unwrap();
        let training = g.encode_sentences(&[words("rpmrpm")]).unwrap();
        let p = ScoreParams::default();
        let s = score_string(&g, &training[0], &z[0], &p).unwrap();
        assert_eq!(s.parse_text(&g), "<f> <f> [r p m]");
        assert_eq!(s.symbols_in_sentences, 3);
        // Unigram: k = 6, N = 6, α = 0.5: p(f) = 0.5/9, p(r) = p(p) = p(m) = 2.5/9.
        let pf = 0.5f64 / 9.0;
        let pr = 2.5f64 / 9.0;
        let uni = -2.0 * pf.log2() - 3.0 * pr.log2();
        assert!((s.unigram.bits - uni).abs() < 1e-9);
        // FSM: f first (unigram), f→f (row f empty: 0.5/3), f→r (0.5/3),
        // r→p (2.5/5), p→m (2.5/5).
        let fsm = -pf.log2() - 2.0 * (0.5f64 / 3.0).log2() - 2.0 * 0.5f64.log2();
        assert!((s.fsm.bits - fsm).abs() < 1e-9, "{} vs {fsm}", s.fsm.bits);
        assert!((s.fsm.bits_per_symbol - fsm / 5.0).abs() < 1e-12);
    }

    #[test]
    fn bad_input_is_an_error() {
        let g = basketball();
        let p = ScoreParams::default();
        assert!(score_string(&g, &[0], &[], &p).is_err());
        assert!(score_string(&g, &[], &[0], &p).is_err());
        assert!(score_string(&g, &[0], &[9], &p).is_err());
        for bad in [
            ScoreParams { alpha: 0.0, ..p },
            ScoreParams {
                alpha: f64::NAN,
                ..p
            },
            ScoreParams {
                max_sentence_len: 0,
                ..p
            },
            ScoreParams {
                max_sentence_len: MAX_SCORE_SENTENCE_LEN + 1,
                ..p
            },
        ] {
            let e = score_string(&g, &[0], &[0], &bad).unwrap_err();
            assert!(matches!(e, GrammarError::InvalidParam { .. }), "{e}");
        }
    }

    #[test]
    fn symbol_text_files_are_checked() {
        let g = basketball();
        let dir = tempfile::tempdir().unwrap();
        let ok = dir.path().join("ok.txt");
        std::fs::write(&ok, "r d p m\nr p m\n").unwrap();
        assert_eq!(load_symbol_string(&ok, &g).unwrap().len(), 7);
        let bad = dir.path().join("bad.txt");
        std::fs::write(&bad, "r d\nr x m\n").unwrap();
        let e = load_symbol_string(&bad, &g).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, GrammarError::File { .. }));
        assert!(
            msg.contains("bad.txt") && msg.contains("line 2, symbol 2"),
            "{msg}"
        );
        let empty = dir.path().join("empty.txt");
        std::fs::write(&empty, "\n").unwrap();
        assert!(load_symbol_string(&empty, &g).is_err());
        let json = dir.path().join("bad.json");
        std::fs::write(&json, "{\"format\": \"other\"}").unwrap();
        let e = load_symbol_string(&json, &g).unwrap_err().to_string();
        assert!(e.contains("bad.json") && e.contains("format"), "{e}");
        assert!(load_symbol_string(dir.path().join("missing"), &g).is_err());
    }
}
