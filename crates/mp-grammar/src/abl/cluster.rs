//! Clustering: hypothesis labels into nonterminals (`Equivalence` by
//! union-find, or `FirstMapping`), and, for `Equivalence`, the merging of
//! nonterminals with identical rule sets once the grammar is read.

use std::collections::HashMap;

use super::{Constituents, HypothesisStore};
use crate::grammar::{Grammar, Rule, Sym, Tree};

/// Union-find over labels: all labels of a hypothesis, and all labels of
/// hypotheses with the same words, are one class, named by its smallest
/// label.
pub(super) fn cluster_union_find(corpus: &[Vec<u32>], store: &mut HypothesisStore) {
    let mut parent: HashMap<u32, u32> = HashMap::new();
    fn find(parent: &mut HashMap<u32, u32>, x: u32) -> u32 {
        let mut root = x;
        while let Some(&p) = parent.get(&root) {
            if p == root {
                break;
            }
            root = p;
        }
        // Path compression.
        let mut cur = x;
        while let Some(&p) = parent.get(&cur) {
            if p == root {
                break;
            }
            parent.insert(cur, root);
            cur = p;
        }
        root
    }
    // First label seen on each phrase.
    let mut phrase_label: HashMap<&[u32], u32> = HashMap::new();
    for (s, hyps) in store.sentences.iter().enumerate() {
        for h in hyps {
            for &l in &h.labels {
                parent.entry(l).or_insert(l);
            }
            let Some(&l0) = h.labels.first() else {
                continue;
            };
            let phrase = corpus.get(s).and_then(|w| w.get(h.b..h.e)).unwrap_or(&[]);
            let same_words = *phrase_label.entry(phrase).or_insert(l0);
            for &l in h.labels[1..].iter().chain(std::iter::once(&same_words)) {
                let (a, b) = (find(&mut parent, l0), find(&mut parent, l));
                if a != b {
                    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                    parent.insert(hi, lo);
                }
            }
        }
    }
    for hyps in &mut store.sentences {
        for h in hyps.iter_mut() {
            let mut v: Vec<u32> = Vec::new();
            for &l in &h.labels {
                let m = find(&mut parent, l);
                if !v.contains(&m) {
                    v.push(m);
                }
            }
            h.labels = v;
        }
    }
}

pub(super) fn cluster(store: &mut HypothesisStore) {
    let mut map: HashMap<u32, u32> = HashMap::new();
    for hyps in &store.sentences {
        for h in hyps {
            let Some(&l0) = h.labels.first() else {
                continue;
            };
            let target = *map.get(&l0).unwrap_or(&l0);
            for &l in &h.labels {
                map.entry(l).or_insert(target);
            }
        }
    }
    for hyps in &mut store.sentences {
        for h in hyps.iter_mut() {
            let mut v: Vec<u32> = Vec::new();
            for &l in &h.labels {
                let m = *map.get(&l).unwrap_or(&l);
                if !v.contains(&m) {
                    v.push(m);
                }
            }
            h.labels = v;
        }
    }
}

/// Merges nonterminals with identical rule sets until none are left;
/// returns how many nonterminals were removed. Trees and constituents are
/// renamed to match.
pub(super) fn merge_equivalent_nonterminals(
    g: &mut Grammar,
    trees: &mut [Tree],
    constituents: &mut Constituents,
) -> usize {
    let before = g.nonterminals.len();
    // Each round removes at least one nonterminal, so this terminates.
    for _ in 0..before {
        let n = g.nonterminals.len();
        let mut sets: Vec<Vec<Vec<Sym>>> = vec![Vec::new(); n];
        for r in &g.rules {
            if let Some(v) = sets.get_mut(r.lhs as usize) {
                v.push(r.rhs.clone());
            }
        }
        for v in sets.iter_mut() {
            v.sort();
            v.dedup();
        }
        let mut first: HashMap<&[Vec<Sym>], u32> = HashMap::new();
        let mut rep: Vec<u32> = (0..n as u32).collect();
        for (x, set) in sets.iter().enumerate() {
            if set.is_empty() {
                continue;
            }
            rep[x] = *first.entry(set.as_slice()).or_insert(x as u32);
        }
        if rep.iter().enumerate().all(|(i, &r)| r as usize == i) {
            break;
        }
        apply_nonterminal_map(g, trees, constituents, &rep);
    }
    before - g.nonterminals.len()
}

/// Renames nonterminal `x` to `rep[x]` (a representative `≤ x`), then
/// renumbers the remaining ones compactly in order.
fn apply_nonterminal_map(
    g: &mut Grammar,
    trees: &mut [Tree],
    constituents: &mut Constituents,
    rep: &[u32],
) {
    let n = rep.len();
    let mut new_id = vec![0u32; n];
    let mut names = Vec::new();
    let mut next = 0u32;
    for x in 0..n {
        if rep[x] as usize == x {
            new_id[x] = next;
            names.push(if next == 0 {
                "S".to_string()
            } else {
                format!("X{next}")
            });
            next += 1;
        }
    }
    for x in 0..n {
        new_id[x] = new_id[rep[x] as usize];
    }
    let map_sym = |s: Sym| match s {
        Sym::N(x) => Sym::N(new_id[x as usize]),
        t => t,
    };
    // Rewritten rules, duplicates joined; `None` for a dropped `X → X`.
    let mut rules: Vec<Rule> = Vec::new();
    let mut index: HashMap<(u32, Vec<Sym>), usize> = HashMap::new();
    let mut rule_map: Vec<Option<usize>> = Vec::with_capacity(g.rules.len());
    for r in &g.rules {
        let lhs = new_id[r.lhs as usize];
        let rhs: Vec<Sym> = r.rhs.iter().map(|&s| map_sym(s)).collect();
        if rhs == [Sym::N(lhs)] {
            rule_map.push(None);
            continue;
        }
        let i = *index.entry((lhs, rhs.clone())).or_insert_with(|| {
            rules.push(Rule { lhs, rhs, count: 0 });
            rules.len() - 1
        });
        rules[i].count += r.count;
        rule_map.push(Some(i));
    }
    // Group by left-hand side again (stable).
    let mut order: Vec<usize> = (0..rules.len()).collect();
    order.sort_by_key(|&i| (rules[i].lhs, i));
    let mut pos = vec![0; rules.len()];
    for (new, &old) in order.iter().enumerate() {
        pos[old] = new;
    }
    let rule_map: Vec<Option<usize>> = rule_map.iter().map(|m| m.map(|i| pos[i])).collect();
    g.rules = order.iter().map(|&i| rules[i].clone()).collect();
    g.nonterminals = names;
    g.start = new_id[g.start as usize];

    fn fix(t: &mut Tree, new_id: &[u32], rule_map: &[Option<usize>]) {
        loop {
            let collapse = match t {
                Tree::Leaf(_) => return,
                Tree::Node { rule, children, .. } => {
                    rule_map.get(*rule).copied().flatten().is_none() && children.len() == 1
                }
            };
            if !collapse {
                break;
            }
            let child = match t {
                Tree::Node { children, .. } => children.pop(),
                Tree::Leaf(_) => None,
            };
            match child {
                Some(c) => *t = c,
                None => break,
            }
        }
        if let Tree::Node { nt, rule, children } = t {
            *nt = new_id.get(*nt as usize).copied().unwrap_or(*nt);
            if let Some(Some(r)) = rule_map.get(*rule) {
                *rule = *r;
            }
            for c in children.iter_mut() {
                fix(c, new_id, rule_map);
            }
        }
    }
    for t in trees.iter_mut() {
        fix(t, &new_id, &rule_map);
    }
    for c in constituents.iter_mut() {
        for x in c.iter_mut() {
            x.2 = new_id.get(x.2 as usize).copied().unwrap_or(x.2);
        }
        let mut seen = std::collections::HashSet::new();
        c.retain(|x| seen.insert(*x));
    }
}
