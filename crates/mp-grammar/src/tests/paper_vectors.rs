//! Test vectors from the motion-grammar paper (Park, Lee & Lee 2011) and the
//! ABL reference documentation.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use crate::abl::align_and_cluster;
use crate::Grammar;
use crate::{learn, AblParams, Alignment, Clustering, Corpus, Selection};
use crate::{score_partition, search_partition, PartitionParams};

fn chars(s: &str) -> Vec<String> {
    s.chars().map(|c| c.to_string()).collect()
}

/// §5.1: `abxcd|abycd|abxcd` with {S → a b A c d, A → x | y} costs 3 bits.
#[test]
fn mdl_paper_example() {
    let g = Grammar::from_text("S -> a b A c d\nA -> x\nA -> y", None).unwrap();
    let z = g
        .encode_sentences(&[chars("abxcd"), chars("abycd"), chars("abxcd")])
        .unwrap();
    assert_eq!(g.encoding_bits(&z).unwrap(), 3.0);
}

/// The good partition has a lower DL than `abxc|dabycda|bxcd`, with every
/// ABL alignment method, and ABL learns exactly the paper's grammar.
#[test]
fn mdl_prefers_the_paper_partition() {
    let c = Corpus::from_sentences(&[chars("abxcdabycdabxcd")]);
    let s = &c.sentences[0];
    for flag in ["wm", "st3"] {
        let abl = AblParams {
            alignment: Alignment::from_flag(flag).unwrap(),
            ..Default::default()
        };
        let good = score_partition(s, &[5, 10], &c.vocab, &abl).unwrap();
        let bad = score_partition(s, &[4, 11], &c.vocab, &abl).unwrap();
        assert!(
            good.dl.total_bits < bad.dl.total_bits,
            "{flag}: {:?} vs {:?}",
            good.dl,
            bad.dl
        );
        if flag == "wm" {
            let text = good.learned.grammar.to_string();
            assert_eq!(good.learned.grammar.n_rules(), 3, "{text}");
            assert_eq!(good.dl.data_bits, 3.0, "{text}");
            assert!(text.contains("S -> a b X1 c d"), "{text}");
        }
    }
    // The search finds a partition at least as good as the paper's.
    let best = search_partition(
        s,
        &c.vocab,
        &PartitionParams {
            abl: AblParams {
                alignment: Alignment::from_flag("wm").unwrap(),
                ..Default::default()
            },
            ..Default::default()
        },
    )
    .unwrap();
    let good = score_partition(
        s,
        &[5, 10],
        &c.vocab,
        &AblParams {
            alignment: Alignment::from_flag("wm").unwrap(),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(best.dl.total_bits <= good.dl.total_bits + 1e-9);
}

/// ABL reference documentation: `she is smart` / `she is tired`.
#[test]
fn abl_she_is_smart() {
    let c = Corpus::from_lines("she is smart\nshe is tired\n").unwrap();
    for flag in ["wm", "st1", "st3"] {
        let p = AblParams {
            alignment: Alignment::from_flag(flag).unwrap(),
            ..Default::default()
        };
        let (store, _) = align_and_cluster(&c.sentences, &p);
        for s in 0..2 {
            let mut v: Vec<(usize, usize, u32)> = store.sentences[s]
                .iter()
                .map(|h| (h.b, h.e, h.labels[0]))
                .collect();
            v.sort_unstable();
            assert_eq!(v, vec![(0, 3, 0), (2, 3, 1)], "{flag} sentence {s}");
        }
    }
}

/// Paper §7: the grammar learned from the six basketball strings derives
/// all of them and is compact (paper: 5 nonterminals, 11 rules). With the
/// default `Equivalence` clustering (`st3` + `branch`) the grammar is at
/// least that compact; `FirstMapping` (the previous default) gives 8 / 18.
#[test]
fn basketball_six_strings() {
    let words = ["rfdpm", "rfdsm", "rdfsm", "rdpm", "rdsm", "rpm"];
    let sentences: Vec<Vec<String>> = words.iter().map(|w| chars(w)).collect();
    let c = Corpus::from_sentences(&sentences);
    for (flag, sel, clustering) in [
        ("st3", Selection::Branch, Clustering::Equivalence),
        ("st3", Selection::Branch, Clustering::FirstMapping),
        ("wm", Selection::Branch, Clustering::Equivalence),
        ("wm", Selection::Branch, Clustering::FirstMapping),
        ("wm", Selection::First, Clustering::Equivalence),
    ] {
        let p = AblParams {
            alignment: Alignment::from_flag(flag).unwrap(),
            selection: sel,
            clustering,
            seed: 0,
        };
        let r = learn(&c.sentences, &c.vocab, &p).unwrap();
        let g = &r.grammar;
        g.validate().unwrap();
        for (i, s) in c.sentences.iter().enumerate() {
            let t = g
                .parse(s)
                .unwrap_or_else(|| panic!("{flag}: {} not derivable\n{g}", words[i]));
            assert_eq!(&t.yield_terminals(), s);
            assert_eq!(&r.trees[i].yield_terminals(), s);
            // The learned trees use the grammar's own rules.
            check_tree(g, &r.trees[i]);
        }
        println!(
            "{flag} {sel:?} {clustering:?}: {} nonterminals, {} rules\n{g}",
            g.n_nonterminals(),
            g.n_rules()
        );
        // No two nonterminals with the same rule set, no duplicate rule.
        if clustering == Clustering::Equivalence {
            let mut sets: Vec<Vec<String>> = (0..g.n_nonterminals())
                .map(|x| {
                    let mut v: Vec<String> = g
                        .rules_of(x as u32)
                        .iter()
                        .map(|&i| format!("{:?}", g.rules[i].rhs))
                        .collect();
                    v.sort();
                    v
                })
                .collect();
            let n = sets.len();
            sets.sort();
            sets.dedup();
            assert_eq!(sets.len(), n, "{flag}: equal rule sets remain\n{g}");
        }
        match (flag, clustering) {
            // Paper (reference ABL, st3 + branch): 5 nonterminals, 11 rules.
            ("st3", Clustering::Equivalence) => assert!(
                g.n_rules() <= 11 && g.n_nonterminals() <= 5,
                "{flag}: not compact\n{g}"
            ),
            ("st3", Clustering::FirstMapping) => {
                assert_eq!((g.n_nonterminals(), g.n_rules()), (8, 18), "{g}")
            }
            _ => {}
        }
        assert!(g.n_nonterminals() >= 2, "{flag}: no structure found\n{g}");
    }
}

/// Every node of a tree uses a rule of its own nonterminal whose right-hand
/// side matches the children.
fn check_tree(g: &Grammar, t: &crate::Tree) {
    use crate::{Sym, Tree};
    if let Tree::Node { nt, rule, children } = t {
        let r = &g.rules[*rule];
        assert_eq!(r.lhs, *nt);
        assert_eq!(r.rhs.len(), children.len());
        for (s, c) in r.rhs.iter().zip(children) {
            match (s, c) {
                (Sym::T(a), Tree::Leaf(b)) => assert_eq!(a, b),
                (Sym::N(a), Tree::Node { nt: b, .. }) => assert_eq!(a, b),
                _ => panic!("tree does not follow rule {rule}"),
            }
            check_tree(g, c);
        }
    }
}

#[test]
fn bad_input_is_an_error() {
    let c = Corpus::from_sentences(&[chars("ab")]);
    assert!(learn(&[], &c.vocab, &AblParams::default()).is_err());
    assert!(learn(&[vec![]], &c.vocab, &AblParams::default()).is_err());
    assert!(learn(&[vec![7]], &c.vocab, &AblParams::default()).is_err());
    assert!(Corpus::from_lines("\n \n").is_err());
    assert!(search_partition(&[], &c.vocab, &PartitionParams::default()).is_err());
    assert!(score_partition(&c.sentences[0], &[0], &c.vocab, &AblParams::default()).is_err());
    assert!(Alignment::from_flag("xx").is_err());
    assert!(PartitionParams {
        min_sentence_len: 0,
        ..Default::default()
    }
    .validate()
    .is_err());
}
