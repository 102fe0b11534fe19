//! Sequitur (Nevill-Manning & Witten 1997): one hierarchical grammar for a
//! single string, the "single global parse tree" baseline.
//!
//! Symbols are appended one at a time while two constraints are kept:
//! *digram uniqueness* (no pair of adjacent symbols occurs twice without
//! overlapping) and *rule utility* (every rule is used at least twice). When
//! the newest digram repeats an earlier one, the earlier occurrence is
//! replaced by a rule — an existing rule if that occurrence is a whole rule
//! body, otherwise a new rule — then the newer one; a rule whose use count
//! drops to one is expanded back in place. The earlier occurrence is the
//! first non-overlapping one in rule order (rules by creation, positions left
//! to right). This implementation keeps rule bodies as vectors and finds
//! digrams by scanning, which is quadratic but simple and exact; it is meant
//! for symbol strings of motions (hundreds of symbols).
//!
//! Rules are numbered for output as the original program prints them: rule 0
//! is the start, and other rules get numbers in the order they are first
//! referenced while printing rules in number order.

use crate::error::{GrammarError, Result};
use crate::grammar::{Grammar, Rule, Sym};

struct Seq {
    rules: Vec<Option<Vec<Sym>>>,
    refs: Vec<usize>,
}

impl Seq {
    fn body(&self, r: usize) -> &[Sym] {
        self.rules[r].as_deref().unwrap_or(&[])
    }

    fn find_other(&self, d: (Sym, Sym), at: (usize, usize)) -> Option<(usize, usize)> {
        for (r, body) in self.rules.iter().enumerate() {
            let Some(body) = body else { continue };
            for j in 0..body.len().saturating_sub(1) {
                if (body[j], body[j + 1]) != d {
                    continue;
                }
                if r == at.0 && (j + 1 >= at.1 && j <= at.1 + 1) {
                    continue; // same or overlapping occurrence
                }
                return Some((r, j));
            }
        }
        None
    }

    /// Checks the digram starting at `(r, i)`; true when something changed.
    fn check(&mut self, r: usize, i: usize) -> bool {
        let body = self.body(r);
        if i + 1 >= body.len() {
            return false;
        }
        let d = (body[i], body[i + 1]);
        match self.find_other(d, (r, i)) {
            Some(m) => {
                self.matched((r, i), m);
                true
            }
            None => false,
        }
    }

    fn matched(&mut self, ss: (usize, usize), m: (usize, usize)) {
        let whole = |s: &Seq, (r, _): (usize, usize)| r != 0 && s.body(r).len() == 2;
        let new_rule = if whole(self, m) {
            let r = m.0;
            self.substitute(ss.0, ss.1, r);
            r
        } else {
            let body = self.body(ss.0);
            let pair = vec![body[ss.1], body[ss.1 + 1]];
            for s in &pair {
                if let Sym::N(x) = *s {
                    self.refs[x as usize] += 1;
                }
            }
            self.rules.push(Some(pair));
            self.refs.push(0);
            let r = self.rules.len() - 1;
            // Replace the earlier occurrence, then the newer one (its index
            // shifts left by one when it follows the earlier one in the same rule).
            self.substitute(m.0, m.1, r);
            let ss_i = if ss.0 == m.0 && ss.1 > m.1 {
                ss.1 - 1
            } else {
                ss.1
            };
            // The earlier substitution may have changed the rule of `ss`;
            // substitute only if the digram is still there.
            let body = self.body(ss.0);
            if ss_i + 1 < body.len() {
                let rb = self.body(r).to_vec();
                if body[ss_i] == rb[0] && body[ss_i + 1] == rb[1] {
                    self.substitute(ss.0, ss_i, r);
                }
            }
            r
        };
        // Rule utility for the symbols of the (new or reused) rule.
        for k in [0usize, 1] {
            let body = self.body(new_rule);
            if let Some(&Sym::N(x)) = body.get(k) {
                if self.refs[x as usize] == 1 {
                    self.expand(x as usize);
                }
            }
        }
    }

    /// Replaces `body[i], body[i + 1]` of rule `r` with `N(new)`.
    fn substitute(&mut self, r: usize, i: usize, new: usize) {
        let Some(body) = self.rules[r].as_mut() else {
            return;
        };
        if i + 1 >= body.len() {
            return;
        }
        let removed = [body[i], body[i + 1]];
        body.splice(i..i + 2, [Sym::N(new as u32)]);
        for s in removed {
            if let Sym::N(x) = s {
                self.refs[x as usize] -= 1;
            }
        }
        self.refs[new] += 1;
        let changed = i > 0 && self.check(r, i - 1);
        if !changed {
            // The symbol may have moved if the left check changed the rule;
            // re-locate it conservatively at `i`.
            if self.body(r).get(i) == Some(&Sym::N(new as u32)) {
                self.check(r, i);
            }
        }
    }

    /// Replaces the single use of rule `x` by its body and deletes `x`.
    fn expand(&mut self, x: usize) {
        let Some(xb) = self.rules[x].clone() else {
            return;
        };
        for r in 0..self.rules.len() {
            if r == x {
                continue;
            }
            if let Some(body) = self.rules[r].as_mut() {
                if let Some(p) = body.iter().position(|&s| s == Sym::N(x as u32)) {
                    body.splice(p..p + 1, xb.iter().copied());
                    self.rules[x] = None;
                    self.refs[x] = 0;
                    return;
                }
            }
        }
    }
}

/// Runs Sequitur on a string of terminal ids named by `terminals`.
/// Nonterminals are named `0`, `1`, … in print order (`0` = start); rule
/// counts are reference counts (1 for the start rule).
pub fn sequitur(input: &[u32], terminals: &[String]) -> Result<Grammar> {
    if input.is_empty() {
        return Err(GrammarError::Empty(
            "Sequitur needs a non-empty string".into(),
        ));
    }
    if let Some(&w) = input.iter().find(|&&w| w as usize >= terminals.len()) {
        return Err(GrammarError::Invalid(format!(
            "symbol id {w} has no name ({} terminals)",
            terminals.len()
        )));
    }
    let mut s = Seq {
        rules: vec![Some(Vec::new())],
        refs: vec![1],
    };
    for &t in input {
        if let Some(b) = s.rules[0].as_mut() {
            b.push(Sym::T(t));
        }
        let n = s.body(0).len();
        if n >= 2 {
            s.check(0, n - 2);
        }
    }
    // Number rules in print order.
    let mut number: Vec<Option<u32>> = vec![None; s.rules.len()];
    let mut order = vec![0usize];
    number[0] = Some(0);
    let mut k = 0;
    while k < order.len() {
        let r = order[k];
        for sym in s.body(r) {
            if let Sym::N(x) = *sym {
                if number[x as usize].is_none() {
                    number[x as usize] = Some(order.len() as u32);
                    order.push(x as usize);
                }
            }
        }
        k += 1;
    }
    let rules = order
        .iter()
        .map(|&r| Rule {
            lhs: number[r].unwrap_or(0),
            rhs: s
                .body(r)
                .iter()
                .map(|sym| match *sym {
                    Sym::N(x) => Sym::N(number[x as usize].unwrap_or(0)),
                    t => t,
                })
                .collect(),
            count: s.refs[r],
        })
        .collect();
    Ok(Grammar {
        terminals: terminals.to_vec(),
        nonterminals: (0..order.len()).map(|i| i.to_string()).collect(),
        start: 0,
        rules,
    })
}

/// Compact one-line form `0 → 1 2; 1 → a b; …` (the notation of the
/// Sequitur documentation).
pub fn compact(g: &Grammar) -> String {
    g.rules
        .iter()
        .map(|r| {
            let rhs: Vec<String> = r
                .rhs
                .iter()
                .map(|s| match *s {
                    Sym::T(t) => g.terminals.get(t as usize).cloned().unwrap_or_default(),
                    Sym::N(n) => g.nonterminals.get(n as usize).cloned().unwrap_or_default(),
                })
                .collect();
            format!(
                "{} → {}",
                g.nonterminals
                    .get(r.lhs as usize)
                    .cloned()
                    .unwrap_or_default(),
                rhs.join(" ")
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::abl::Corpus;

    fn run(s: &str) -> String {
        let c = Corpus::from_sentences(&[s.chars().map(|c| c.to_string()).collect::<Vec<_>>()]);
        compact(&sequitur(&c.sentences[0], &c.vocab).unwrap())
    }

    #[test]
    fn documented_outputs() {
        assert_eq!(run("abbbabcbb"), "0 → 1 2 1 c 2; 1 → a b; 2 → b b");
        assert_eq!(run("aaaaaa"), "0 → 1 1 1; 1 → a a");
        assert_eq!(
            run("aacaacbcbdaacbcbdebcbd"),
            "0 → 1 2 2 e 3; 1 → a a c; 2 → 1 3; 3 → b c b d"
        );
    }

    #[test]
    fn regenerates_input() {
        for s in ["abcabcabcabc", "abracadabra", "x", "aaaaaaaaaaab"] {
            let c = Corpus::from_sentences(&[s.chars().map(|c| c.to_string()).collect::<Vec<_>>()]);
            let g = sequitur(&c.sentences[0], &c.vocab).unwrap();
            fn expand(g: &Grammar, nt: u32, out: &mut Vec<u32>) {
                for r in g.rules.iter().filter(|r| r.lhs == nt) {
                    for s in &r.rhs {
                        match *s {
                            Sym::T(t) => out.push(t),
                            Sym::N(n) => expand(g, n, out),
                        }
                    }
                }
            }
            let mut out = Vec::new();
            expand(&g, 0, &mut out);
            assert_eq!(out, c.sentences[0], "{s}");
            // Rule utility: every non-start rule is used at least twice.
            assert!(
                g.rules.iter().skip(1).all(|r| r.count >= 2),
                "{s}: {}",
                compact(&g)
            );
        }
    }

    #[test]
    fn empty_is_an_error() {
        assert!(sequitur(&[], &[]).is_err());
    }
}
