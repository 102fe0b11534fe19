//! The text form of concrete programs (see `docs/DSL.md`).
//!
//! ```text
//! program(fps=30, units=px, dims=2, skeleton="penn13")
//!
//! joint "right_wrist" {
//!     circular_motion(center=(220.56, 175.67), radius=108.23, angle=3.17*t + 79.99, duration=7)
//!     stationary(x=129.25, y=121.59, duration=4)
//!     linear_motion(x=0.69*t + 256.2, y=-5.79*t + 182.64, duration=11)
//! }
//! ```
//!
//! [`Program::to_dsl`](crate::Program::to_dsl) writes every number in its
//! shortest round-trip form, so `Program::from_dsl(&p.to_dsl()) == p`
//! exactly; [`Program::to_dsl_pretty`](crate::Program::to_dsl_pretty) rounds
//! to a fixed number of decimals, like the paper's figures.

pub mod lex;
mod parse;
mod print;

pub(crate) use parse::parse;
#[cfg(test)]
pub(crate) use parse::parse_statement;
#[cfg(test)]
pub(crate) use print::statement;
pub use print::{axis_name, NumberFormat};
pub(crate) use print::{print, print_pretty};
