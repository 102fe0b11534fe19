//! mp-grammar
