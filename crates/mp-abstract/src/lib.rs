//! mp-abstract
