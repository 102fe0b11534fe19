//! Reading the grammar: the selected constituents of each sentence nest
//! into a tree, whose nodes give the rules.

use std::collections::HashMap;

use super::Constituents;
use crate::grammar::{Grammar, Rule, Sym, Tree};

/// Builds trees and rules from the selected constituents.
pub(super) fn read_grammar(
    corpus: &[Vec<u32>],
    terminals: &[String],
    constituents: Constituents,
) -> (Grammar, Vec<Tree>, Constituents) {
    // Renumber labels by first appearance in a pre-order walk (S first).
    let mut rename: HashMap<u32, u32> = HashMap::new();
    rename.insert(0, 0);
    let mut rules: Vec<Rule> = Vec::new();
    let mut rule_index: HashMap<(u32, Vec<Sym>), usize> = HashMap::new();
    let mut trees = Vec::with_capacity(corpus.len());
    let mut renamed_constituents = Vec::with_capacity(corpus.len());

    for (s, cons) in constituents.iter().enumerate() {
        let words = &corpus[s];
        // Sort: start asc, end desc (parents before children); empty spans
        // after non-empty spans that start at the same place.
        let mut c = cons.clone();
        c.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1)));
        if !c
            .iter()
            .any(|&(b, e, l)| b == 0 && e == words.len() && l == 0)
        {
            c.insert(0, (0, words.len(), 0));
        }
        let tree = build_node(0, &c, words, &mut rename, &mut rules, &mut rule_index);
        renamed_constituents.push(
            c.iter()
                .map(|&(b, e, l)| (b, e, *rename.get(&l).unwrap_or(&l)))
                .collect(),
        );
        trees.push(tree);
    }
    let n_nt = rename.len();
    let mut nonterminals = vec![String::new(); n_nt];
    for (_, &new) in rename.iter() {
        nonterminals[new as usize] = if new == 0 {
            "S".to_string()
        } else {
            format!("X{new}")
        };
    }
    // Group rules by left-hand side (stable), fixing tree rule indices.
    let mut order: Vec<usize> = (0..rules.len()).collect();
    order.sort_by_key(|&i| (rules[i].lhs, i));
    let mut new_index = vec![0; rules.len()];
    for (new, &old) in order.iter().enumerate() {
        new_index[old] = new;
    }
    let rules: Vec<Rule> = order.iter().map(|&i| rules[i].clone()).collect();
    fn fix(t: &mut Tree, map: &[usize]) {
        if let Tree::Node { rule, children, .. } = t {
            *rule = map[*rule];
            children.iter_mut().for_each(|c| fix(c, map));
        }
    }
    for t in trees.iter_mut() {
        fix(t, &new_index);
    }
    (
        Grammar {
            terminals: terminals.to_vec(),
            nonterminals,
            start: 0,
            rules,
        },
        trees,
        renamed_constituents,
    )
}

fn build_node(
    idx: usize,
    c: &[(usize, usize, u32)],
    words: &[u32],
    rename: &mut HashMap<u32, u32>,
    rules: &mut Vec<Rule>,
    rule_index: &mut HashMap<(u32, Vec<Sym>), usize>,
) -> Tree {
    let (b, e, label) = c[idx];
    let next = rename.len() as u32;
    let nt = *rename.entry(label).or_insert(next);
    // Direct children: constituents inside (b, e) (an empty span may sit at
    // either end), other than (b, e) itself, not inside another such
    // non-empty constituent (an empty span is inside one only strictly).
    let inside_parent = |j: usize| {
        let (cb, ce, _) = c[j];
        j != idx && b <= cb && ce <= e && (cb, ce) != (b, e)
    };
    let strictly_in = |outer: usize, inner: usize| {
        let (ob, oe, _) = c[outer];
        let (ib, ie, _) = c[inner];
        if ob == oe || (ob, oe) == (ib, ie) {
            false
        } else if ib == ie {
            ob < ib && ib < oe
        } else {
            ob <= ib && ie <= oe
        }
    };
    let candidates: Vec<usize> = (0..c.len()).filter(|&j| inside_parent(j)).collect();
    let mut kids: Vec<usize> = candidates
        .iter()
        .copied()
        .filter(|&j| !candidates.iter().any(|&o| o != j && strictly_in(o, j)))
        .collect();
    kids.sort_by(|&x, &y| {
        let (xb, xe, _) = c[x];
        let (yb, ye, _) = c[y];
        // Position order; at equal start, an empty span comes first.
        xb.cmp(&yb).then((xe > xb).cmp(&(ye > yb)))
    });
    let mut children = Vec::new();
    let mut rhs = Vec::new();
    let mut pos = b;
    let mut k = 0;
    while pos < e || k < kids.len() {
        if k < kids.len() && c[kids[k]].0 == pos {
            let child = build_node(kids[k], c, words, rename, rules, rule_index);
            if let Tree::Node { nt: cn, .. } = &child {
                rhs.push(Sym::N(*cn));
            }
            pos = c[kids[k]].1;
            children.push(child);
            k += 1;
        } else if pos < e {
            rhs.push(Sym::T(words[pos]));
            children.push(Tree::Leaf(words[pos]));
            pos += 1;
        } else {
            // A child that does not start at the current position cannot
            // occur for non-crossing sets; skip it defensively.
            k += 1;
        }
    }
    let key = (nt, rhs.clone());
    let ri = match rule_index.get(&key) {
        Some(&i) => i,
        None => {
            rules.push(Rule {
                lhs: nt,
                rhs,
                count: 0,
            });
            rule_index.insert(key, rules.len() - 1);
            rules.len() - 1
        }
    };
    rules[ri].count += 1;
    Tree::Node {
        nt,
        rule: ri,
        children,
    }
}
