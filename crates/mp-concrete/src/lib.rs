//! mp-concrete
