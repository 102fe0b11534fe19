//! Context-free grammars over symbol ids, derivation trees, a parser that
//! finds the cheapest derivation, and the description length of §5.1.
//!
//! # Description length (paper eq. 6)
//!
//! `DL(Z) = B(G) + B(Z | G)`:
//!
//! * `B(G)`: the rules are written as one sequence, each rule as its
//!   left-hand side followed by its right-hand side, with a separator between
//!   rules (`S a b A c d @ A x @ A y`); every symbol costs
//!   `log2(|V| + |Σ| + 1)` bits (a nonterminal, a terminal or the separator),
//!   where `|V|` counts the nonterminals and `|Σ|` the terminals used by the
//!   grammar.
//! * `B(Z | G)`: each sentence is encoded by its derivation tree traversed in
//!   pre-order, each nonterminal node costing `log2 h` bits where `h` is the
//!   number of rules with that left-hand side.
//!
//! [`Grammar::encoding_bits`] parses each sentence and uses the cheapest
//! derivation; a learner that knows its trees can use
//! [`Grammar::tree_bits`] on them instead.

use std::collections::HashMap;
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::{GrammarError, Result};

/// A grammar symbol: terminal or nonterminal id.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Sym {
    /// Terminal (index into [`Grammar::terminals`]).
    T(u32),
    /// Nonterminal (index into [`Grammar::nonterminals`]).
    N(u32),
}

/// A production `lhs → rhs` (an empty `rhs` is ε) with its use count in the
/// training corpus.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Rule {
    /// Left-hand side nonterminal.
    pub lhs: u32,
    /// Right-hand side.
    pub rhs: Vec<Sym>,
    /// How many times the rule was used to derive the training sentences.
    pub count: usize,
}

/// A context-free grammar.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Grammar {
    /// Terminal names.
    pub terminals: Vec<String>,
    /// Nonterminal names.
    pub nonterminals: Vec<String>,
    /// Start nonterminal.
    pub start: u32,
    /// Productions, grouped by left-hand side in first-appearance order.
    pub rules: Vec<Rule>,
}

/// A derivation tree.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Tree {
    /// A terminal.
    Leaf(u32),
    /// A nonterminal expanded by rule `rule` (index into [`Grammar::rules`]).
    Node {
        /// The nonterminal.
        nt: u32,
        /// The rule used.
        rule: usize,
        /// Children in order.
        children: Vec<Tree>,
    },
}

impl Tree {
    /// Terminals of the tree, left to right.
    pub fn yield_terminals(&self) -> Vec<u32> {
        let mut out = Vec::new();
        self.collect(&mut out);
        out
    }
    fn collect(&self, out: &mut Vec<u32>) {
        match self {
            Tree::Leaf(t) => out.push(*t),
            Tree::Node { children, .. } => children.iter().for_each(|c| c.collect(out)),
        }
    }
}

impl Grammar {
    /// Number of rules.
    pub fn n_rules(&self) -> usize {
        self.rules.len()
    }
    /// Number of nonterminals (including the start symbol).
    pub fn n_nonterminals(&self) -> usize {
        self.nonterminals.len()
    }
    /// Number of rules per nonterminal.
    pub fn rules_per_nonterminal(&self) -> Vec<usize> {
        let mut c = vec![0; self.nonterminals.len()];
        for r in &self.rules {
            if let Some(v) = c.get_mut(r.lhs as usize) {
                *v += 1;
            }
        }
        c
    }
    /// Indices of the rules of nonterminal `nt`.
    pub fn rules_of(&self, nt: u32) -> Vec<usize> {
        (0..self.rules.len())
            .filter(|&i| self.rules[i].lhs == nt)
            .collect()
    }

    /// Checks that every symbol id is in range.
    pub fn validate(&self) -> Result<()> {
        let nt = self.nonterminals.len() as u32;
        let t = self.terminals.len() as u32;
        if self.start >= nt {
            return Err(GrammarError::Invalid(format!(
                "start nonterminal {} outside 0..{nt}",
                self.start
            )));
        }
        for (i, r) in self.rules.iter().enumerate() {
            if r.lhs >= nt {
                return Err(GrammarError::Invalid(format!(
                    "rule {i}: left-hand side {} outside 0..{nt}",
                    r.lhs
                )));
            }
            for s in &r.rhs {
                let ok = match *s {
                    Sym::T(x) => x < t,
                    Sym::N(x) => x < nt,
                };
                if !ok {
                    return Err(GrammarError::Invalid(format!(
                        "rule {i}: symbol {s:?} out of range"
                    )));
                }
            }
        }
        Ok(())
    }

    /// Number of distinct terminals used by the rules.
    pub fn used_terminals(&self) -> usize {
        let mut seen = vec![false; self.terminals.len()];
        for r in &self.rules {
            for s in &r.rhs {
                if let Sym::T(t) = *s {
                    if let Some(v) = seen.get_mut(t as usize) {
                        *v = true;
                    }
                }
            }
        }
        seen.iter().filter(|&&b| b).count()
    }

    /// `B(G)` in bits (see the module documentation).
    pub fn grammar_bits(&self) -> f64 {
        if self.rules.is_empty() {
            return 0.0;
        }
        let symbols: usize =
            self.rules.iter().map(|r| 1 + r.rhs.len()).sum::<usize>() + self.rules.len() - 1;
        let alphabet = self.nonterminals.len() + self.used_terminals() + 1;
        symbols as f64 * (alphabet as f64).log2()
    }

    /// Bits of one derivation tree: `Σ_nodes log2(#rules of the node's nonterminal)`.
    pub fn tree_bits(&self, tree: &Tree) -> f64 {
        let per = self.rules_per_nonterminal();
        fn walk(t: &Tree, per: &[usize]) -> f64 {
            match t {
                Tree::Leaf(_) => 0.0,
                Tree::Node { nt, children, .. } => {
                    let h = per.get(*nt as usize).copied().unwrap_or(1).max(1);
                    (h as f64).log2() + children.iter().map(|c| walk(c, per)).sum::<f64>()
                }
            }
        }
        walk(tree, &per)
    }

    /// `B(Z | G)` in bits: the cheapest derivation of every sentence.
    /// Errors when a sentence cannot be derived.
    pub fn encoding_bits(&self, sentences: &[Vec<u32>]) -> Result<f64> {
        let mut total = 0.0;
        for (i, s) in sentences.iter().enumerate() {
            let tree = self.parse(s).ok_or_else(|| GrammarError::NotDerivable {
                index: i,
                sentence: self.sentence_text(s),
            })?;
            total += self.tree_bits(&tree);
        }
        Ok(total)
    }

    /// `DL(Z) = B(G) + B(Z | G)` with parsed derivations.
    pub fn description_length(&self, sentences: &[Vec<u32>]) -> Result<DescriptionLength> {
        let g = self.grammar_bits();
        let z = self.encoding_bits(sentences)?;
        Ok(DescriptionLength {
            grammar_bits: g,
            data_bits: z,
            total_bits: g + z,
        })
    }

    /// A sentence as space-separated terminal names.
    pub fn sentence_text(&self, s: &[u32]) -> String {
        s.iter()
            .map(|&t| {
                self.terminals
                    .get(t as usize)
                    .cloned()
                    .unwrap_or_else(|| format!("#{t}"))
            })
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The cheapest derivation of `sentence` from the start symbol (cost of a
    /// rule = `log2` of the number of rules of its left-hand side), or `None`
    /// when the sentence is not in the language. Handles ε-rules and unit
    /// rules; `O(|R| · L · n³)` for a sentence of `n` symbols.
    pub fn parse(&self, sentence: &[u32]) -> Option<Tree> {
        if self.validate().is_err() {
            return None;
        }
        let n = sentence.len();
        let nv = self.nonterminals.len();
        let per = self.rules_per_nonterminal();
        let rule_cost: Vec<f64> = self
            .rules
            .iter()
            .map(|r| (per[r.lhs as usize].max(1) as f64).log2())
            .collect();
        let idx = |x: usize, i: usize, j: usize| (x * (n + 1) + i) * (n + 1) + j;
        let mut best = vec![f64::INFINITY; nv * (n + 1) * (n + 1)];
        let mut back = vec![usize::MAX; nv * (n + 1) * (n + 1)];
        for len in 0..=n {
            // Fixpoint for this span length (unit and ε chains).
            for _round in 0..=nv {
                let mut changed = false;
                for i in 0..=(n - len) {
                    let j = i + len;
                    for (ri, r) in self.rules.iter().enumerate() {
                        let c = self.seq_cost(&r.rhs, sentence, i, j, &best, &idx);
                        let total = c + rule_cost[ri];
                        let k = idx(r.lhs as usize, i, j);
                        if total < best[k] {
                            best[k] = total;
                            back[k] = ri;
                            changed = true;
                        }
                    }
                }
                if !changed {
                    break;
                }
            }
        }
        let root = idx(self.start as usize, 0, n);
        if !best[root].is_finite() {
            return None;
        }
        self.build(self.start, 0, n, sentence, &best, &back, &idx, 0)
    }

    /// Minimal cost of deriving `rhs` over `sentence[i..j]`.
    fn seq_cost(
        &self,
        rhs: &[Sym],
        w: &[u32],
        i: usize,
        j: usize,
        best: &[f64],
        idx: &dyn Fn(usize, usize, usize) -> usize,
    ) -> f64 {
        self.seq_table(rhs, w, i, j, best, idx)
            .last()
            .and_then(|row| row.get(j - i).copied())
            .unwrap_or(f64::INFINITY)
    }

    /// `f[p][k − i]`: cost of `rhs[..p]` over `w[i..k]`.
    fn seq_table(
        &self,
        rhs: &[Sym],
        w: &[u32],
        i: usize,
        j: usize,
        best: &[f64],
        idx: &dyn Fn(usize, usize, usize) -> usize,
    ) -> Vec<Vec<f64>> {
        rhs_span_costs(rhs, w, i, j - i, |x, s, e| best[idx(x, s, e)])
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        &self,
        x: u32,
        i: usize,
        j: usize,
        w: &[u32],
        best: &[f64],
        back: &[usize],
        idx: &dyn Fn(usize, usize, usize) -> usize,
        depth: usize,
    ) -> Option<Tree> {
        if depth > 4 * (w.len() + 1) * (self.nonterminals.len() + 1) {
            return None;
        }
        let ri = *back.get(idx(x as usize, i, j))?;
        let rule = self.rules.get(ri)?;
        let f = self.seq_table(&rule.rhs, w, i, j, best, idx);
        // Walk back through the table to find the split points.
        let mut children = Vec::with_capacity(rule.rhs.len());
        let mut b = j - i;
        for p in (0..rule.rhs.len()).rev() {
            match rule.rhs[p] {
                Sym::T(t) => {
                    children.push(Tree::Leaf(t));
                    b = b.checked_sub(1)?;
                }
                Sym::N(y) => {
                    let target = f[p + 1][b];
                    let mut found = None;
                    for a in (0..=b).rev() {
                        let c = f[p][a] + best[idx(y as usize, i + a, i + b)];
                        if f[p][a].is_finite() && (c - target).abs() <= 1e-9 * target.max(1.0) {
                            found = Some(a);
                            break;
                        }
                    }
                    let a = found?;
                    children.push(self.build(y, i + a, i + b, w, best, back, idx, depth + 1)?);
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

    /// Reads rules written one per line as `LHS -> sym sym …` (also `→`);
    /// alternatives may be separated by `|`; `ε` or nothing is the empty
    /// right-hand side. Symbols that appear on a left-hand side are
    /// nonterminals, all others terminals. The first left-hand side is the
    /// start symbol. Lines starting with `#` are ignored. Terminal ids follow
    /// `terminals` when given (unknown terminals are appended).
    pub fn from_text(text: &str, terminals: Option<&[String]>) -> Result<Self> {
        let mut lines = Vec::new();
        for (ln, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let (lhs, rhs) = line
                .split_once("->")
                .or_else(|| line.split_once('→'))
                .ok_or_else(|| {
                    GrammarError::Invalid(format!("grammar line {}: no `->` in `{line}`", ln + 1))
                })?;
            let lhs = lhs.trim();
            if lhs.is_empty() || lhs.contains(char::is_whitespace) {
                return Err(GrammarError::Invalid(format!(
                    "grammar line {}: left-hand side `{lhs}` must be one symbol",
                    ln + 1
                )));
            }
            for alt in rhs.split('|') {
                let syms: Vec<String> = alt
                    .split_whitespace()
                    .filter(|s| *s != "ε" && *s != "∅")
                    .map(|s| s.to_string())
                    .collect();
                lines.push((lhs.to_string(), syms));
            }
        }
        if lines.is_empty() {
            return Err(GrammarError::Empty("grammar text has no rule".into()));
        }
        let mut nonterminals: Vec<String> = Vec::new();
        let mut nt_id: HashMap<String, u32> = HashMap::new();
        for (l, _) in &lines {
            if !nt_id.contains_key(l) {
                nt_id.insert(l.clone(), nonterminals.len() as u32);
                nonterminals.push(l.clone());
            }
        }
        let mut terms: Vec<String> = terminals.map(|t| t.to_vec()).unwrap_or_default();
        let mut t_id: HashMap<String, u32> = terms
            .iter()
            .enumerate()
            .map(|(i, t)| (t.clone(), i as u32))
            .collect();
        let mut rules: Vec<Rule> = Vec::new();
        for (l, syms) in lines {
            let rhs = syms
                .into_iter()
                .map(|s| match nt_id.get(&s) {
                    Some(&n) => Sym::N(n),
                    None => {
                        let id = *t_id.entry(s.clone()).or_insert_with(|| {
                            terms.push(s.clone());
                            (terms.len() - 1) as u32
                        });
                        Sym::T(id)
                    }
                })
                .collect();
            let r = Rule {
                lhs: nt_id[&l],
                rhs,
                count: 0,
            };
            if !rules.iter().any(|x| x.lhs == r.lhs && x.rhs == r.rhs) {
                rules.push(r);
            }
        }
        Ok(Grammar {
            terminals: terms,
            nonterminals,
            start: 0,
            rules,
        })
    }

    /// Sentences of terminal names → ids (unknown names are an error).
    pub fn encode_sentences(&self, sentences: &[Vec<String>]) -> Result<Vec<Vec<u32>>> {
        let ids: HashMap<&str, u32> = self
            .terminals
            .iter()
            .enumerate()
            .map(|(i, t)| (t.as_str(), i as u32))
            .collect();
        sentences
            .iter()
            .enumerate()
            .map(|(si, s)| {
                s.iter()
                    .map(|w| {
                        ids.get(w.as_str()).copied().ok_or_else(|| {
                            GrammarError::Invalid(format!(
                                "sentence {si}: symbol `{w}` is not a terminal of the grammar"
                            ))
                        })
                    })
                    .collect()
            })
            .collect()
    }

    fn sym_name(&self, s: Sym) -> String {
        match s {
            Sym::T(t) => self
                .terminals
                .get(t as usize)
                .cloned()
                .unwrap_or_else(|| format!("#{t}")),
            Sym::N(n) => self
                .nonterminals
                .get(n as usize)
                .cloned()
                .unwrap_or_else(|| format!("N{n}")),
        }
    }
}

impl fmt::Display for Grammar {
    /// One rule per line, `LHS -> rhs  (count)`; ε for an empty right side.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for r in &self.rules {
            let rhs = if r.rhs.is_empty() {
                "ε".to_string()
            } else {
                r.rhs
                    .iter()
                    .map(|s| self.sym_name(*s))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            writeln!(
                f,
                "{} -> {}  ({})",
                self.sym_name(Sym::N(r.lhs)),
                rhs,
                r.count
            )?;
        }
        Ok(())
    }
}

/// The two parts of a description length, in bits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DescriptionLength {
    /// `B(G)`.
    pub grammar_bits: f64,
    /// `B(Z | G)`.
    pub data_bits: f64,
    /// `B(G) + B(Z | G)`.
    pub total_bits: f64,
}

/// `f[p][b]`: the least cost of `rhs[..p]` deriving `w[i..i + b]` for
/// `b ≤ span` (∞ where it cannot): terminals must match and cost nothing, a
/// nonterminal `x` deriving `w[s..e]` costs `span_cost(x, s, e)`. The inner
/// step of the chart parsers ([`Grammar::parse`] and the scorer's).
pub(crate) fn rhs_span_costs(
    rhs: &[Sym],
    w: &[u32],
    i: usize,
    span: usize,
    span_cost: impl Fn(usize, usize, usize) -> f64,
) -> Vec<Vec<f64>> {
    let mut f = vec![vec![f64::INFINITY; span + 1]; rhs.len() + 1];
    f[0][0] = 0.0;
    for (p, s) in rhs.iter().enumerate() {
        for a in 0..=span {
            let base = f[p][a];
            if !base.is_finite() {
                continue;
            }
            match *s {
                Sym::T(t) => {
                    if a < span && w[i + a] == t && base < f[p + 1][a + 1] {
                        f[p + 1][a + 1] = base;
                    }
                }
                Sym::N(x) => {
                    for (b, slot) in f[p + 1].iter_mut().enumerate().skip(a) {
                        let v = base + span_cost(x as usize, i + a, i + b);
                        if v < *slot {
                            *slot = v;
                        }
                    }
                }
            }
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.chars().map(|c| c.to_string()).collect()
    }

    #[test]
    fn paper_example_three_bits() {
        let g = Grammar::from_text("S -> a b A c d\nA -> x | y", None).unwrap();
        assert_eq!(g.n_rules(), 3);
        let z = g
            .encode_sentences(&[words("abxcd"), words("abycd"), words("abxcd")])
            .unwrap();
        assert_eq!(g.encoding_bits(&z).unwrap(), 3.0);
        // B(G): "S a b A c d @ A x @ A y" = 12 symbols × log2(2 + 6 + 1).
        assert!((g.grammar_bits() - 12.0 * 9f64.log2()).abs() < 1e-12);
        let t = g.parse(&z[1]).unwrap();
        assert_eq!(t.yield_terminals(), z[1]);
    }

    #[test]
    fn parse_handles_epsilon_and_units() {
        let g = Grammar::from_text(
            "S -> r X1 X2 m\nX1 -> X3 X4 X3\nX2 -> p | s\nX3 -> f | ε\nX4 -> d | ε",
            None,
        )
        .unwrap();
        for s in ["rfdpm", "rfdsm", "rdfsm", "rdpm", "rdsm", "rpm", "rm"] {
            let z = g.encode_sentences(&[words(s)]).unwrap();
            // "rm" is not in the language (X2 is required).
            let t = g.parse(&z[0]);
            if s == "rm" {
                assert!(t.is_none());
            } else {
                assert_eq!(t.unwrap().yield_terminals(), z[0], "{s}");
            }
        }
        let z = g.encode_sentences(&[words("rm")]).unwrap();
        assert!(matches!(
            g.encoding_bits(&z),
            Err(GrammarError::NotDerivable { .. })
        ));
    }

    #[test]
    fn bad_text_is_an_error() {
        assert!(Grammar::from_text("", None).is_err());
        assert!(Grammar::from_text("S a b", None).is_err());
        assert!(Grammar::from_text("S T -> a", None).is_err());
    }
}
