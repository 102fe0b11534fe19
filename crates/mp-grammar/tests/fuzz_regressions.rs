//! Inputs found by fuzzing (`crates/mp-fuzz`, target `grammar_json`) that
//! made reading a grammar model panic; each must now be a typed error.

use std::path::Path;

use mp_grammar::GrammarModel;

/// A segment that ends before it starts (`rules_text` subtracted the
/// frames with overflow).
const BACKWARD_SEGMENT: &[u8] =
    br#"{"format":"mp-grammar-model/1","source":{"paths":["m.npz"],"kind":"positions",
"frame_step":1,"n_frames":10,"fps":30.0,"n_joints":3,"dims":3},"symbols":{"k":1,
"n_frames":10,"fps":30.0,"segments":[{"start":5,"end":2,"symbol":0}],"medoids":[0],
"quality":{"r":0.125,"e_prime":0.0,"f":16.0},"d_max":2.042148170004908,
"stats":{"ga_generations":69,"ga_evaluations":3951,"ga_best_f":16.0,
"sa_iterations":1000,"sa_accepted":0,"seconds_dmax":3.3008e-05,
"seconds_ga":0.017806687,"seconds_sa":0.002503007}},"cuts":[],"sentences":[[0]],
"grammar":{"terminals":["a"],"nonterminals":["S"],"start":0,"rules":[{"lhs":0,
"rhs":[{"T":0}],"count":1}]},"description_length":{"grammar_bits":46.43856189774724,
"data_bits":18.0,"total_bits":64.43856189774723},"abl":{"hypotheses":14,
"labels_before_clustering":7,"labels_after_clustering":1,"selected":9,
"nonterminals_merged":0},"symbol_params":{"k":3,"omega":0.5,
"candidate_step_frames":10,"min_segment_frames":5,"max_segment_frames":40,
"max_segments":null,"kmedoids":{"method":"FasterPam","max_iter":100},
"ga":{"population":100,"generations":500,"stall_generations":50,
"crossover_rate":0.9,"mutation_rate":null,"elite":2,"init_cut_probability":0.5,
"chunk_candidates":64},"sa":{"iterations":1000,"initial_step_frames":null,
"min_step_frames":1,"patience":200,"max_iterations":5000,"initial_temperature":0.0},
"seed":0},"partition_params":{"candidates":200,"min_sentence_len":3,
"max_sentence_len":12,"min_repeat_len":2,"include_whole_string":false,
"abl":{"alignment":{"SuffixTree":{"variant":"St3"}},"selection":"Branch",
"clustering":"Equivalence","seed":0},"seed":0},"distance":{"root":"SkeletonRoot",
"scale_normalise":true,"joints":null},"seconds_symbols":0.020424106,
"seconds_grammar":0.000210321}"#;

/// `k` = 10^18 symbols for one segment (listing the members of each symbol
/// allocated `k` lists).
const HUGE_K: &[u8] =
    br#"{"format":"mp-grammar-model/1","source":{"paths":["m.npz"],"kind":"positions",
"frame_step":1,"n_frames":10,"fps":30.0,"n_joints":3,"dims":3},
"symbols":{"k":1000000000000000000,"n_frames":10,"fps":30.0,"segments":[{"start":0,
"end":10,"symbol":0}],"medoids":[0],"quality":{"r":0.125,"e_prime":0.0,"f":16.0},
"d_max":2.042148170004908,"stats":{"ga_generations":69,"ga_evaluations":3951,
"ga_best_f":16.0,"sa_iterations":1000,"sa_accepted":0,"seconds_dmax":3.3008e-05,
"seconds_ga":0.017806687,"seconds_sa":0.002503007}},"cuts":[],"sentences":[[0]],
"grammar":{"terminals":["a"],"nonterminals":["S"],"start":0,"rules":[{"lhs":0,
"rhs":[{"T":0}],"count":1}]},"description_length":{"grammar_bits":46.43856189774724,
"data_bits":18.0,"total_bits":64.43856189774723},"abl":{"hypotheses":14,
"labels_before_clustering":7,"labels_after_clustering":1,"selected":9,
"nonterminals_merged":0},"symbol_params":{"k":3,"omega":0.5,
"candidate_step_frames":10,"min_segment_frames":5,"max_segment_frames":40,
"max_segments":null,"kmedoids":{"method":"FasterPam","max_iter":100},
"ga":{"population":100,"generations":500,"stall_generations":50,
"crossover_rate":0.9,"mutation_rate":null,"elite":2,"init_cut_probability":0.5,
"chunk_candidates":64},"sa":{"iterations":1000,"initial_step_frames":null,
"min_step_frames":1,"patience":200,"max_iterations":5000,"initial_temperature":0.0},
"seed":0},"partition_params":{"candidates":200,"min_sentence_len":3,
"max_sentence_len":12,"min_repeat_len":2,"include_whole_string":false,
"abl":{"alignment":{"SuffixTree":{"variant":"St3"}},"selection":"Branch",
"clustering":"Equivalence","seed":0},"seed":0},"distance":{"root":"SkeletonRoot",
"scale_normalise":true,"joints":null},"seconds_symbols":0.020424106,
"seconds_grammar":0.000210321}"#;

fn read(bytes: &[u8]) -> std::result::Result<GrammarModel, mp_grammar::GrammarError> {
    GrammarModel::from_json(&String::from_utf8_lossy(bytes), Path::new("fuzz.json"))
}

#[test]
fn backward_segment_is_an_error() {
    let e = read(BACKWARD_SEGMENT).unwrap_err().to_string();
    assert!(e.contains("segment 0 (5..2"), "{e}");
}

#[test]
fn more_symbols_than_segments_is_an_error() {
    let e = read(HUGE_K).unwrap_err().to_string();
    assert!(e.contains("symbols for 1 segments"), "{e}");
}

#[test]
fn the_fixed_inputs_read_once_repaired() {
    let ok = std::str::from_utf8(BACKWARD_SEGMENT).unwrap().replace(
        r#"{"start":5,"end":2,"symbol":0}"#,
        r#"{"start":0,"end":10,"symbol":0}"#,
    );
    let m = GrammarModel::from_json(&ok, Path::new("fuzz.json")).unwrap();
    assert!(m.rules_text().contains("S -> a"));
}
